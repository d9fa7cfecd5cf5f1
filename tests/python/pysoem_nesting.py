"""Consistency nesting, as Beckhoff's EL6751 manual allows it for the
start-up SDOs ("with Complete Access or with consistency nesting"), played
by an independent master (SOEM, through pysoem) against canif's terminal:
sub-index 0 written 0 opens an object, its entries are written, sub-index 0
written back closes it. The same configuration written both ways reads back
alike; a record left open refuses SAFEOP; the nested configuration then
carries a 29-bit message with its transaction number. Written from
ETG.1020's nesting, the manual's words and SOEM's API, not canif's master.

usage: pysoem_nesting.py IFACE
prints one line per step; exits 1 on the first thing that is not as expected.
"""

import struct
import sys

import pysoem
from soem_steps import back_to_init, exchange_29bit_message, fail, map_and_start, one_terminal

U8, U16, U32 = "<B", "<H", "<I"

# 29-bit identifiers with transaction number, 10 Tx and 10 Rx slots, queues of 150.
INTERFACE = [(0x20, 0x0008), (0x21, 10), (0x22, 10), (0x23, 150), (0x24, 150)]
# One filter row accepting every 29-bit identifier.
ROW = bytes.fromhex("01000000 0000 FFFFFF1F".replace(" ", ""))


def read_back(terminal):
    """What a configurator reads of the three objects."""
    interface = [struct.unpack(U16, terminal.sdo_read(0x8000, sub))[0] for sub, _ in INTERFACE]
    filters = (terminal.sdo_read(0x8001, 0)[0], bytes(terminal.sdo_read(0x8001, 1)))
    bus = [bytes(terminal.sdo_read(0xF800, sub)) for sub in (1, 2)]
    return interface, filters, bus


def with_complete_access(terminal):
    terminal.sdo_write(0xF800, 0, struct.pack("<BxII", 2, 0x01020304, 0), ca=True)
    values = [v for _, v in INTERFACE]
    terminal.sdo_write(0x8000, 0, struct.pack("<BxHHHHH", 0x24, *values), ca=True)
    terminal.sdo_write(0x8001, 0, bytes([1, 0]) + ROW, ca=True)


def nested(terminal, index, entries, close):
    terminal.sdo_write(index, 0, struct.pack(U8, 0))
    for sub, data in entries:
        terminal.sdo_write(index, sub, data)
    terminal.sdo_write(index, 0, struct.pack(U8, close))


def with_nesting(terminal):
    nested(terminal, 0xF800, [(1, struct.pack(U32, 0x01020304)), (2, struct.pack(U32, 0))], 2)
    nested(terminal, 0x8000, [(sub, struct.pack(U16, v)) for sub, v in INTERFACE], 0x24)
    nested(terminal, 0x8001, [(1, ROW)], 1)


def something_else(terminal):
    """Another configuration, so that the nested one is seen to replace it."""
    terminal.sdo_write(0x8000, 0, struct.pack("<BxHHHHH", 0x24, 0, 2, 2, 20, 20), ca=True)
    terminal.sdo_write(0x8001, 0, bytes([0, 0]), ca=True)
    terminal.sdo_write(0xF800, 0, struct.pack("<BxII", 2, 0, 0), ca=True)


def main(interface):
    with one_terminal(interface) as (master, terminal):
        for index, entries in ((0x1C12, [0x1600]), (0x1C13, [0x1A00, 0x1A85])):
            nested(terminal, index, [(n + 1, struct.pack(U16, pdo)) for n, pdo in enumerate(entries)], len(entries))
        with_complete_access(terminal)
        by_complete_access = read_back(terminal)
        something_else(terminal)
        if read_back(terminal) == by_complete_access:
            fail("the other configuration did not take")
        with_nesting(terminal)
        by_nesting = read_back(terminal)
        if by_nesting != by_complete_access:
            fail(f"nesting read back {by_nesting}, complete access {by_complete_access}")
        print("complete access and nesting read back alike")
        # A record left open: sub-index 0 reads 0, and SAFEOP is refused.
        terminal.sdo_write(0x8000, 0, struct.pack(U8, 0))
        if terminal.sdo_read(0x8000, 0)[0] != 0:
            fail("0x8000:00 does not read 0 while the record is open")
        print("0x8000:00 reads 0 while open")
        master.config_map()
        if master.state_check(pysoem.SAFEOP_STATE, 50_000) == pysoem.SAFEOP_STATE:
            fail("SAFEOP with 0x8000 left open")
        master.read_state()
        if terminal.al_status != 0x0026:
            fail(f"an open 0x8000 refused SAFEOP with {terminal.al_status:#06x}, not 0x0026")
        print("an open 0x8000 refuses SAFEOP with AL status 0x0026")
        # Closed, acknowledged, the terminal starts with the nested configuration.
        terminal.sdo_write(0x8000, 0, struct.pack(U8, 0x24))
        master.state = pysoem.PREOP_STATE + pysoem.STATE_ACK
        master.write_state()
        if master.state_check(pysoem.PREOP_STATE, 50_000) != pysoem.PREOP_STATE:
            fail("the refusal could not be acknowledged")
        map_and_start(master, terminal, (166, 154))
        exchange_29bit_message(master, terminal)
        back_to_init(master)


if __name__ == "__main__":
    main(sys.argv[1])
