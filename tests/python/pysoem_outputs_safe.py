"""Outputs are acted on in OP only: an independent master (SOEM, through
pysoem) hands canif's terminal a batch outside OP and reads whether the
terminal took it. ETG.1000.6's state machine: in SAFEOP a SubDevice
delivers inputs but keeps its outputs in their safe state; a real EL6751
sends nothing before OP. Written from ETG.1000.6, 003's handshake and
SOEM's API, not from canif's master.

usage: pysoem_outputs_safe.py IFACE never-op|fallbacks
  never-op:  configure, SAFEOP, 100 cycles with a batch handed over, INIT
  fallbacks: SAFEOP (none), OP (all), the master's fall back to SAFEOP
             (none until OP again), the SM watchdog's (likewise)
prints one line per step; exits 1 on the first thing that is not as expected.
"""

import struct
import sys
import time

import pysoem
from soem_steps import back_to_init, fail, one_terminal, write_11bit_two_slots


def batch(tx_counter, ident, data):
    """TxCounter, RxCounter 0, NoOfTxMessages 1, then one 11-bit message
    (COB ID word: length in bits 0-3, identifier in bits 5-15) and a free slot."""
    message = struct.pack("<H8s", (ident << 5) | len(data), data)
    return struct.pack("<HHH", tx_counter, 0, 1) + message + bytes(10)


def cycles(master, terminal, count, until=None):
    """Process data `count` times (or until Inputs.TxCounter is `until`):
    the Inputs.TxCounter each cycle read."""
    seen = []
    for _ in range(count):
        master.send_processdata()
        master.receive_processdata(2000)
        seen.append(struct.unpack("<H", bytes(terminal.input[0:2]))[0])
        if until is not None and seen[-1] == until:
            break
        time.sleep(0.001)
    return seen


def request(master, terminal, state, what):
    master.state = state
    master.write_state()
    state &= 0x0F  # the acknowledge bit is asked, never shown
    if master.state_check(state, 50_000) != state:
        fail(f"not in {what}: AL status code {terminal.al_status:#06x}")


def configure(master, terminal):
    write_11bit_two_slots(terminal)
    master.config_map()
    if (len(terminal.output), len(terminal.input)) != (26, 32):
        fail(f"mapped {len(terminal.output)} output and {len(terminal.input)} input bytes")
    if master.state_check(pysoem.SAFEOP_STATE, 50_000) != pysoem.SAFEOP_STATE:
        fail(f"not in SAFEOP: AL status code {terminal.al_status:#06x}")


def held(master, terminal, count, confirmed, what):
    seen = cycles(master, terminal, count)
    if any(c != confirmed for c in seen):
        fail(f"{what}: Inputs.TxCounter went {sorted(set(seen))}, the batch was taken outside OP")
    print(f"{what}: {count} cycles, Inputs.TxCounter stays {confirmed}")


def taken(master, terminal, tx_counter, what):
    seen = cycles(master, terminal, 100, until=tx_counter)
    if seen[-1] != tx_counter:
        fail(f"{what}: Inputs.TxCounter never confirmed {tx_counter}: {seen[-5:]}")
    print(f"{what}: Inputs.TxCounter confirmed {tx_counter}")


def main(interface, mode):
    with one_terminal(interface) as (master, terminal):
        configure(master, terminal)
        terminal.output = batch(1, 0x111, b"\x5a\xfe")
        held(master, terminal, 100, 0, "SAFEOP")
        if mode == "never-op":
            back_to_init(master)
            return
        # OP: the batch handed over in SAFEOP is still in the outputs.
        request(master, terminal, pysoem.OP_STATE, "OP")
        taken(master, terminal, 1, "OP")
        terminal.output = batch(2, 0x222, b"\x0b\x0b")
        taken(master, terminal, 2, "OP, the next batch")
        # The master falls back to SAFEOP: nothing new until OP again.
        request(master, terminal, pysoem.SAFEOP_STATE, "SAFEOP")
        terminal.output = batch(3, 0x333, b"\x33")
        held(master, terminal, 50, 2, "SAFEOP again (the master's)")
        request(master, terminal, pysoem.OP_STATE, "OP")
        taken(master, terminal, 3, "OP again")
        # The SM watchdog: no outputs for longer than its 100 ms.
        time.sleep(0.3)
        terminal.output = batch(4, 0x444, b"\x44")
        cycles(master, terminal, 1)
        master.read_state()
        if terminal.state & 0x0F != pysoem.SAFEOP_STATE or terminal.al_status != 0x001B:
            fail(f"after 300 ms without outputs: state {terminal.state:#x}, AL status {terminal.al_status:#06x}")
        print("the SM watchdog: SAFEOP, AL status 0x001b")
        held(master, terminal, 50, 3, "SAFEOP after the watchdog")
        # The error acknowledged, then OP: the batch goes.
        request(master, terminal, pysoem.SAFEOP_STATE + pysoem.STATE_ACK, "SAFEOP (acknowledged)")
        request(master, terminal, pysoem.OP_STATE, "OP")
        taken(master, terminal, 4, "OP after the watchdog")
        back_to_init(master)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
