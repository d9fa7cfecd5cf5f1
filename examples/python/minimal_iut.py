#!/usr/bin/env python3
"""A tiny CAN interface device in Python, written only from docs/adapter-protocol.md.

It implements the plain buffered 11-bit interface with filters: the Tx/Rx
counter handshake, a local send queue with back-pressure, a local receive queue
with tail drop, and the filter table (first match decides). It refuses every
other configuration, so it certifies on the profile that offers exactly that:

    cargo run --release -- run --iut "exec:python3 examples/python/minimal_iut.py" \
        --profile fc510x-before-fw2.14
"""
import json
import sys


def u16(b, at):
    return b[at] | (b[at + 1] << 8)


def put16(b, at, v):
    b[at] = v & 0xFF
    b[at + 1] = (v >> 8) & 0xFF


class Device:
    def __init__(self, config, caps):
        self.slots_tx = config["tx_slots"]
        self.slots_rx = config["rx_slots"]
        self.filters = config["filters"]
        self.rx_depth = caps["rx_queue_depth"]
        self.tx_depth = caps["tx_queue_depth"]
        self.inputs = bytearray(config["input_size"])
        self.send_queue = []
        self.in_flight = None
        self.receive_queue = []

    def cycle(self, outputs):
        # Tx: a changed TxCounter is a new batch; accept it when the queue has room.
        requested = u16(outputs, 0)
        if requested != u16(self.inputs, 0):
            count = min(u16(outputs, 4), self.slots_tx)
            busy = len(self.send_queue)  # the frame on the wire has left the queue (HS-TX-012)
            if busy == 0 or busy + count <= self.tx_depth:
                for i in range(count):
                    at = 6 + 10 * i
                    word = u16(outputs, at)
                    length = min(word & 0xF, 8)
                    remote = bool(word & 0x10)
                    data = b"" if remote else bytes(outputs[at + 2:at + 2 + length])
                    self.send_queue.append({"id": word >> 5, "rtr": remote, "len": length, "data": data})
                put16(self.inputs, 0, requested)
        # Rx: fill the image only when the PLC has released it.
        if u16(outputs, 2) == u16(self.inputs, 2) and self.receive_queue:
            count = min(len(self.receive_queue), self.slots_rx)
            for i in range(self.slots_rx):
                at = 6 + 10 * i
                self.inputs[at:at + 10] = bytes(10)
                if i < count:
                    frame = self.receive_queue.pop(0)
                    word = (frame["id"] << 5) | (0x10 if frame["rtr"] else 0) | frame["len"]
                    put16(self.inputs, at, word)
                    self.inputs[at + 2:at + 2 + len(frame["data"])] = frame["data"]
            put16(self.inputs, 4, count)
            put16(self.inputs, 2, (u16(self.inputs, 2) + 1) & 0xFFFF)
        return self.inputs

    def passes_filters(self, ident):
        for row in self.filters:
            if row["kind"] == "range":
                hit = row["from"] <= ident <= row["to"]
            else:
                hit = (ident & row["mask"]) == (row["code"] & row["mask"])
            if hit:
                return row["action"] == "accept"
        return not any(row["action"] == "accept" for row in self.filters)

    def receive(self, frame):
        if frame["extended"] or frame["fd"] or not self.passes_filters(frame["id"]):
            return
        if len(self.receive_queue) < self.rx_depth:  # full: the new frame is lost (tail drop)
            data = bytes.fromhex(frame["data"])
            self.receive_queue.append({"id": frame["id"], "rtr": frame["rtr"], "len": frame["len"], "data": data})

    def poll_transmit(self):
        if self.in_flight is None and self.send_queue:
            self.in_flight = self.send_queue.pop(0)
            f = self.in_flight
            return {"id": f["id"], "extended": False, "rtr": f["rtr"], "fd": False, "brs": False, "esi": False,
                    "len": f["len"], "data": f["data"].hex()}
        return None


def refusal(config, caps):
    if config["format"] != "11-bit":
        return "this example implements the 11-bit interface only"
    if not caps["base11"]:
        return "the profile does not offer the 11-bit interface"
    if config["queue"] != "standard":
        return "this example implements the buffered queue only"
    if config["transaction_number"] or config["time_stamp"]:
        return "no transaction number or time stamp here"
    if config["sync1_shift_ns"] is not None:
        return "no distributed clocks here"
    if config["filters"] and not caps["filters"]:
        return "the profile offers no filters"
    for row in config["filters"]:
        if row["kind"] == "range" and (row["from"] > row["to"] or row["to"] > 0x1FFFFFFF):
            return "malformed filter range"
        if row["kind"] == "mask" and (row["code"] | row["mask"]) > 0x1FFFFFFF:
            return "malformed filter mask"
    for slots in (config["tx_slots"], config["rx_slots"]):
        if not 1 <= slots <= caps["max_slots"]:
            return "slot count out of range"
    return None


def main():
    device = None
    for line in sys.stdin:
        request = json.loads(line)
        kind = request["type"]
        if kind == "bye":
            return
        if kind == "configure":
            reason = refusal(request["config"], request["capabilities"])
            device = None if reason else Device(request["config"], request["capabilities"])
            answer = {"type": "configured", "protocol": 1, "accepted": reason is None}
            if reason:
                answer["reason"] = reason
        elif kind == "cycle":
            inputs = device.cycle(bytes.fromhex(request["outputs"]))
            answer = {"type": "inputs", "inputs": inputs.hex()}
        elif kind == "receive":
            device.receive(request["frame"])
            answer = {"type": "ok"}
        elif kind == "poll_transmit":
            answer = {"type": "transmit", "frame": device.poll_transmit()}
        elif kind == "transmit_complete":
            device.in_flight = None
            answer = {"type": "ok"}
        elif kind == "controller_status":
            answer = {"type": "ok"}
        else:
            answer = {"type": "error", "message": "unknown request " + kind}
        sys.stdout.write(json.dumps(answer) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
