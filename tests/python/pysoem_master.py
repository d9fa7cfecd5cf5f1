"""An independent EtherCAT master (SOEM, through pysoem) drives canif's
emulated terminal: scan, identity, configuration by complete-access SDO
downloads, PDO mapping read by SOEM itself, OP, and one CAN message sent
through the process image. Written from ETG.1000, docs/ethercat.md and
SOEM's API only, not from canif's master.

usage: pysoem_master.py IFACE   (the terminal: canif device --ethercat PEER)
prints one line per step; exits 1 on the first thing that is not as expected.
"""

import struct
import sys
import time

import pysoem
from soem_steps import back_to_init, fail, map_and_start, patient, write_11bit_two_slots



def main(interface):
    master = patient(pysoem.Master())
    master.open(interface)
    try:
        found = master.config_init()
        if found != 1:
            fail(f"{found} SubDevices found, 1 expected")
        terminal = master.slaves[0]
        print(f"found {terminal.name} vendor {terminal.man:#010x} product {terminal.id:#010x} revision {terminal.rev:#010x}")
        vendor = struct.unpack("<I", terminal.sdo_read(0x1018, 1))[0]
        if vendor != terminal.man:
            fail(f"0x1018:01 says vendor {vendor:#x}, the SII {terminal.man:#x}")
        # 0xF800 bus parameters, 0x8000 interface (11-bit, 2 Tx and 2 Rx slots,
        # the terminal's own queue depths read back), 0x8001 no filters.
        write_11bit_two_slots(terminal)
        print("configured: 11-bit, 2 Tx and 2 Rx slots")
        # 6 header bytes + 2 x 10 (Tx); 6 + 2 x 10 (Rx), as 003 lays the
        # image out, then the 6 bytes of CAN status (0x1A85).
        map_and_start(master, terminal, (26, 32))
        # One message: TxCounter 1, RxCounter 0, NoOfTxMessages 1, then COB ID
        # word (length 2, id 0x123 in bits 5-15) and the data.
        message = struct.pack("<H8s", (0x123 << 5) | 2, bytes([0xCA, 0x1F]))
        terminal.output = struct.pack("<HHH", 1, 0, 1) + message + bytes(10)
        confirmed = False
        for _ in range(4):
            master.send_processdata()
            master.receive_processdata(2000)
            tx_counter = struct.unpack("<H", bytes(terminal.input[0:2]))[0]
            if tx_counter == 1:
                confirmed = True
                break
            time.sleep(0.001)
        if not confirmed:
            fail(f"Inputs.TxCounter never confirmed 1: inputs {bytes(terminal.input).hex()}")
        print("Inputs.TxCounter confirmed 1")
        back_to_init(master)
    finally:
        master.close()


if __name__ == "__main__":
    main(sys.argv[1])
