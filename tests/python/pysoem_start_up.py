"""A real EL6751 configuration, played by an independent master (SOEM,
through pysoem) against canif's terminal: the PREOP start-up list a
configurator derives from the EL6751's public description, in the layout
the terminal's SII gives (the real EL6751's), then OP and the CAN-interface
handshake through the process image at the real sizes.

Written from Beckhoff's public EL6751 object description, ETHERCAT.md's
public example configuration (flags 0x0008, 10 Tx and 10 Rx slots, queues
of 150, one filter row accepting every identifier: 166 output and 154 input
bytes) and SOEM's API -- not from canif's master or canif's objects.

usage: pysoem_start_up.py IFACE   (the terminal: canif device --ethercat PEER)
prints one line per step; exits 1 on the first thing that is not as expected.
"""

import struct
import sys

import pysoem
from soem_steps import back_to_init, exchange_29bit_message, fail, map_and_start, patient

U8, U16, U32 = "<B", "<H", "<I"

# The start-up list, in the order the documentation gives: PDO assignment
# and sync parameters, then 0xF800, 0x8000, 0x8001 (each object after the
# one it depends on), then the local cycle measurement (000 §5).
START_UP = [
    (0x1C12, 0x00, U8, 0),
    (0x1C12, 0x01, U16, 0x1600),  # RxPDO-Map CAN Interface
    (0x1C12, 0x00, U8, 1),
    (0x1C13, 0x00, U8, 0),
    (0x1C13, 0x01, U16, 0x1A00),  # TxPDO-Map CAN Interface
    (0x1C13, 0x02, U16, 0x1A85),  # TxPDO-Map CAN Status
    (0x1C13, 0x00, U8, 2),
    (0x1C32, 0x01, U16, 1),  # synchronous with the SM2 event
    (0x1C32, 0x02, U32, 8_000_000),  # 8 ms, as the example
    (0x1C33, 0x01, U16, 0x22),  # inputs with the SM2 event
    (0x1C33, 0x02, U32, 8_000_000),
    (0x8000, 0x20, U16, 0x0008),  # 29-bit identifiers, transaction number
    (0x8000, 0x21, U16, 10),  # Rx slots
    (0x8000, 0x22, U16, 10),  # Tx slots
    (0x8000, 0x23, U16, 150),  # Rx queue
    (0x8000, 0x24, U16, 150),  # Tx queue
]

# 0x8001 with complete access: one row accepting every identifier.
FILTERS = bytes([1, 0]) + bytes.fromhex("01000000 0000 FFFFFF1F".replace(" ", ""))



def main(interface):
    master = patient(pysoem.Master())
    master.open(interface)
    try:
        if master.config_init() != 1:
            fail("not exactly one SubDevice found")
        terminal = master.slaves[0]
        print(f"found {terminal.name} vendor {terminal.man:#010x} product {terminal.id:#010x}")
        if (terminal.man, terminal.id) != (0x2, 0x1A5F3052):
            fail("not an EL6751's identity")
        name = terminal.sdo_read(0x1008, 0).rstrip(b"\0").decode()
        device_type = struct.unpack(U32, terminal.sdo_read(0x1000, 0))[0]
        print(f"0x1008 {name!r}, 0x1000 {device_type:#010x}")
        if name != "EL6751":
            fail(f"0x1008 reads {name!r}")
        # SDO Information: the dictionary, as a configurator reads it.
        objects = {o.index: o for o in terminal.od}
        for index in (0x1000, 0x1018, 0x1C32, 0x1C33, 0x6001, 0x7001, 0x8000, 0x8001, 0xF000, 0xF108, 0xF800):
            if index not in objects:
                fail(f"SDO Information lists no {index:#06x} (it lists {sorted(hex(i) for i in objects)})")
        print(f"SDO Information: {len(objects)} objects, 0x8000 is {objects[0x8000].name.decode()!r}")

        written = 0
        for index, sub, kind, value in START_UP:
            try:
                terminal.sdo_write(index, sub, struct.pack(kind, value))
            except pysoem.SdoError as error:
                fail(f"{index:#06x}:{sub:02x} = {value} refused: {error}")
            written += 1
        terminal.sdo_write(0x8001, 0, FILTERS, ca=True)
        terminal.sdo_write(0x1C32, 0x08, struct.pack(U16, 1))
        print(f"start-up list: {written + 2} downloads accepted")

        # A refused setting is refused as a real terminal refuses it.
        try:
            terminal.sdo_write(0x8000, 0x24, struct.pack(U16, 151))
            fail("a Tx queue of 151 (the EL6751 keeps at most 150) was accepted")
        except pysoem.SdoError as error:
            if error.abort_code != 0x06090030:
                fail(f"a Tx queue of 151 aborted with {error.abort_code:#010x}, not 0x06090030")
        print("a Tx queue of 151 refused with 0x06090030")

        map_and_start(master, terminal, (166, 154))

        exchange_29bit_message(master, terminal)
        # The image objects read what the last cycle left (0x7001:01 the
        # TxCounter written, 0x6001:04 the transaction number confirmed).
        tx_counter = struct.unpack(U16, terminal.sdo_read(0x7001, 0x01))[0]
        transaction = struct.unpack(U16, terminal.sdo_read(0x6001, 0x04))[0]
        if (tx_counter, transaction) != (1, 0x42):
            fail(f"0x7001:01 {tx_counter}, 0x6001:04 {transaction:#x}: not the image's 1 and 0x42")
        print("0x7001:01 and 0x6001:04 read the image")
        status = bytes(terminal.input[148:154])
        print(f"CAN status {status.hex()}")
        back_to_init(master)
    finally:
        master.close()


if __name__ == "__main__":
    main(sys.argv[1])
