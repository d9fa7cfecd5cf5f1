"""Steps both SOEM scripts take (pysoem_master.py, pysoem_start_up.py):
written once, from SOEM's API."""

import struct
import sys
from contextlib import contextmanager

import pysoem


def fail(what):
    print(f"FAIL {what}")
    sys.exit(1)


def patient(master):
    """Mailbox timeouts of 5 s instead of SOEM's 0.7 s: on a machine busy
    with a build, the terminal's process may wait that long for a core, and
    a slow answer is not a wrong one."""
    master.sdo_read_timeout = 5_000_000
    master.sdo_write_timeout = 5_000_000
    return master


def map_and_start(master, terminal, expected):
    """Maps the process data (expected: output and input bytes), then SAFEOP and OP."""
    master.config_map()
    outputs, inputs = len(terminal.output), len(terminal.input)
    if (outputs, inputs) != expected:
        fail(f"mapped {outputs} output and {inputs} input bytes, {expected[0]} and {expected[1]} expected")
    print(f"mapped {outputs} output and {inputs} input bytes")
    if master.state_check(pysoem.SAFEOP_STATE, 50_000) != pysoem.SAFEOP_STATE:
        fail(f"not in SAFEOP: AL status code {terminal.al_status:#06x}")
    master.state = pysoem.OP_STATE
    master.send_processdata()
    master.receive_processdata(2000)
    master.write_state()
    if master.state_check(pysoem.OP_STATE, 50_000) != pysoem.OP_STATE:
        fail("not in OP")
    print("OP")


def back_to_init(master):
    """INIT, then the socket closed: the terminal is left as it was found."""
    master.state = pysoem.INIT_STATE
    master.write_state()


@contextmanager
def one_terminal(interface):
    """A master on `interface` that found exactly one SubDevice: (master, terminal)."""
    master = patient(pysoem.Master())
    master.open(interface)
    try:
        if master.config_init() != 1:
            fail("not exactly one SubDevice found")
        yield master, master.slaves[0]
    finally:
        master.close()


def write_11bit_two_slots(terminal):
    """0xF800, 0x8000 (11-bit, 2 Tx and 2 Rx slots, the terminal's own queue
    depths read back) and 0x8001 (no filters), each with complete access."""
    rx_depth = struct.unpack("<H", terminal.sdo_read(0x8000, 0x23))[0]
    tx_depth = struct.unpack("<H", terminal.sdo_read(0x8000, 0x24))[0]
    terminal.sdo_write(0xF800, 0, struct.pack("<BxII", 2, 0x01020304, 0), ca=True)
    terminal.sdo_write(0x8000, 0, struct.pack("<BxHHHHH", 0x24, 0, 2, 2, rx_depth, tx_depth), ca=True)
    terminal.sdo_write(0x8001, 0, bytes([0, 0]), ca=True)


def exchange_29bit_message(master, terminal):
    """One 29-bit message with transaction number 0x42 through 10 Tx slots of
    16 bytes: TxCounter 1, RxCounter 0, NoOfTxMessages 1, then transaction
    number, length, COB ID (bit 31: extended) and the data; until the inputs
    confirm TxCounter 1 and TransactionNumber 0x42."""
    message = struct.pack("<HHI8s", 0x42, 2, 0x80000000 | 0x1234567, bytes([0xCA, 0x1F]))
    terminal.output = struct.pack("<HHH", 1, 0, 1) + message + bytes(16 * 9)
    seen = None
    for _ in range(50):
        master.send_processdata()
        master.receive_processdata(2000)
        seen = struct.unpack("<HHHH", bytes(terminal.input[0:8]))
        if (seen[0], seen[3]) == (1, 0x42):
            break
    else:
        fail(f"Inputs.TxCounter/TransactionNumber never confirmed 1/0x42: {seen}")
    print("Inputs.TxCounter confirmed 1, Inputs.TransactionNumber 0x42")
