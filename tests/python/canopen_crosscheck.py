#!/usr/bin/env python3
"""Python's canopen package (an SDO/NMT client written by others) drives the
simulated coupler over python-can's socketcand interface (a TCP port), or over
a SocketCAN interface (python-can's `socketcan` interface, in the kernel lane).
Prints one JSON object with every check; exits 1 if any disagrees with the
quick start (002), the SDO page (004) or CiA 301 (stopped nodes, resets).

Usage: canopen_crosscheck.py PORT NODE
       canopen_crosscheck.py socketcan:IFACE NODE
"""
import json
import sys
import threading

import canopen

where, node_id = sys.argv[1], int(sys.argv[2])
network = canopen.Network()
if where.startswith("socketcan:"):
    network.connect(interface="socketcan", channel=where.split(":", 1)[1])
else:
    network.connect(interface="socketcand", channel="can0", host="127.0.0.1", port=int(where))
node = canopen.RemoteNode(node_id, canopen.ObjectDictionary())
network.add_node(node)
checks = {}


def check(name, fn):
    try:
        result = fn()
        checks[name] = {"ok": True, "value": result}
    except AssertionError as error:
        checks[name] = {"ok": False, "error": str(error)}
    except Exception as error:  # noqa: BLE001 - any failure of the tool is a disagreement
        checks[name] = {"ok": False, "error": f"{type(error).__name__}: {error}"}


def upload_device_type():
    value = int.from_bytes(node.sdo.upload(0x1000, 0), "little")
    assert value == 0x00190191, hex(value)
    return hex(value)


def upload_u8():
    data = node.sdo.upload(0x1001, 0)
    assert data == b"\x00", data  # Unsigned8: one byte (0x4F), SDO-005/008
    return data.hex()


def abort_unknown_object():
    try:
        node.sdo.upload(0x2345, 0)
    except canopen.SdoAbortedError as error:
        assert error.code == 0x06020000, hex(error.code)
        return hex(error.code)
    raise AssertionError("no abort")


def abort_unknown_subindex():
    try:
        node.sdo.upload(0x1018, 9)
    except canopen.SdoAbortedError as error:
        assert error.code == 0x06090011, hex(error.code)
        return hex(error.code)
    raise AssertionError("no abort")


def heartbeat_after_download():
    node.sdo.download(0x1017, 0, (100).to_bytes(2, "little"))  # canopen sends 0x2B (2 bytes)
    state = node.nmt.wait_for_heartbeat(timeout=2)
    assert state == "PRE-OPERATIONAL", state
    return state


def start_and_heartbeat_state():
    node.nmt.state = "OPERATIONAL"  # NMT 0x01 to the node
    node.nmt.wait_for_heartbeat(timeout=2)
    state = node.nmt.wait_for_heartbeat(timeout=2)
    assert state == "OPERATIONAL", state
    return state


def enter_pre_operational():
    node.nmt.state = "PRE-OPERATIONAL"  # NMT 0x80 (ruling R6)
    node.nmt.wait_for_heartbeat(timeout=2)
    state = node.nmt.wait_for_heartbeat(timeout=2)
    assert state == "PRE-OPERATIONAL", state
    return state


def read_back_heartbeat_time():
    value = int.from_bytes(node.sdo.upload(0x1017, 0), "little")
    assert value == 100, value
    return value


def stopped_node_answers_no_sdo():
    node.nmt.state = "STOPPED"  # NMT 0x02
    node.nmt.wait_for_heartbeat(timeout=2)
    state = node.nmt.wait_for_heartbeat(timeout=2)
    assert state == "STOPPED", state
    try:
        node.sdo.upload(0x1017, 0)
    except canopen.SdoCommunicationError as error:
        return f"no answer ({error})"  # CiA 301: stopped serves NMT and error control only
    finally:
        node.nmt.state = "PRE-OPERATIONAL"
    raise AssertionError("a stopped node answered an SDO upload")


def reset_communication_restores_defaults():
    # Listen before the command: the node may boot before canopen's
    # wait_for_bootup starts waiting, and that wait forgets what came before it.
    booted = threading.Event()

    def on_error_control(can_id, data, timestamp):
        if data[:1] == b"\x00":
            booted.set()

    network.subscribe(0x700 + node_id, on_error_control)
    try:
        node.nmt.state = "RESET COMMUNICATION"  # NMT 0x82
        assert booted.wait(2), "no boot-up message (0x700 + node id, 00) within 2 s"
    finally:
        network.unsubscribe(0x700 + node_id, on_error_control)
    value = int.from_bytes(node.sdo.upload(0x1017, 0), "little")
    assert value == 0, f"0x1017 reads {value} after reset communication, not the power-on 0"
    return value


for name, fn in [
    ("SDO upload 0x1000 (4 bytes)", upload_device_type),
    ("SDO upload 0x1001 (Unsigned8)", upload_u8),
    ("SDO abort: object does not exist", abort_unknown_object),
    ("SDO abort: sub-index does not exist", abort_unknown_subindex),
    ("SDO download 0x1017, then heartbeats", heartbeat_after_download),
    ("NMT start, heartbeat says operational", start_and_heartbeat_state),
    ("NMT enter pre-operational", enter_pre_operational),
    ("SDO upload 0x1017 reads back 100", read_back_heartbeat_time),
    ("NMT stop: SDO gets no answer (CiA 301)", stopped_node_answers_no_sdo),
    ("NMT reset communication: 0x1017 back to 0 (CiA 301)", reset_communication_restores_defaults),
]:
    check(name, fn)

network.disconnect()
print(json.dumps(checks))
sys.exit(0 if all(c["ok"] for c in checks.values()) else 1)
