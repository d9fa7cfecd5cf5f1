#!/usr/bin/env python3
"""A PLC-side client of the CAN interface in Python, written only from
docs/adapter-protocol.md ("The client role" and "Image offsets").

It speaks protocol 3 where the harness offers it (the tasks as records in
shared memory: `Shared` below, through mmap and eventfds), else 1.

Inside, a frame's data and the images are bytes; only the lines carry hex.

Once per task it reads new Rx messages (when Inputs.RxCounter differs from
the Outputs.RxCounter it wrote, at most NoOfRxMessages and never more than
the slots) and acknowledges by copying Inputs.RxCounter; it hands the
application's messages over in batches, only while Outputs.TxCounter equals
Inputs.TxCounter, then sets Outputs.TxCounter to Inputs.TxCounter + 1. It keeps
its own output image, so it does not care what buffer the master hands it.
With transaction numbers it tells which messages were sent: every message
up to the one Inputs.TransactionNumber names (`sent`).

    cargo run --release -- run plc --iut "exec:python3 examples/python/minimal_client.py"
"""
import json
import mmap
import os
import select
import struct
import sys
import time

FD_SIZES = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64]


def u16(b, at):
    return b[at] | (b[at + 1] << 8)


def put(b, at, value, size):
    b[at:at + size] = value.to_bytes(size, "little")


def get(b, at, size):
    return int.from_bytes(b[at:at + size], "little")


class Client:
    def __init__(self, config):
        self.format = config["format"]
        tn = config["transaction_number"]
        ts = config["time_stamp"]
        self.tx_slots = config["tx_slots"]
        self.rx_slots = config["rx_slots"]
        self.input_size = config["input_size"]
        self.outputs = bytearray(config["output_size"])
        self.queue = []
        # Where the messages start and how large they are (the offsets tables).
        with_tn = tn or self.format == "fd"
        self.rx_start = 8 if with_tn else 6
        self.with_tn = with_tn
        # Transaction numbers handed over and not yet known to be sent.
        self.in_flight = []
        if self.format == "11-bit":
            self.tx_size, self.rx_size = (12 if tn else 10), 10
        elif self.format == "29-bit":
            self.tx_size, self.rx_size = (16 if tn else 14), (22 if ts else 14)
        else:
            self.tx_size, self.rx_size = 72, 78
        self.tn, self.ts = tn, ts

    def fits(self, message):
        frame = message["frame"]
        if self.format == "11-bit":
            return not frame["extended"] and not frame["fd"]
        if self.format == "29-bit":
            return not frame["fd"]
        return True

    def encode(self, at, message):
        frame = message["frame"]
        data = frame["data"]
        b = self.outputs
        b[at:at + self.tx_size] = bytes(self.tx_size)
        if self.format == "11-bit":
            if self.tn:
                put(b, at, message["transaction_number"], 2)
                at += 2
            word = (frame["id"] << 5) | (0x10 if frame["rtr"] else 0) | frame["len"]
            put(b, at, word, 2)
            b[at + 2:at + 2 + len(data)] = data
            return
        cob = frame["id"] | (0x80000000 if frame["extended"] else 0) | (0x40000000 if frame["rtr"] else 0)
        if self.format == "29-bit":
            if self.tn:
                put(b, at, message["transaction_number"], 2)
                at += 2
            put(b, at, frame["len"], 2)
            put(b, at + 2, cob, 4)
            b[at + 6:at + 6 + len(data)] = data
            return
        put(b, at, message["transaction_number"], 2)
        b[at + 2] = frame["len"]
        b[at + 3] = (1 if frame["fd"] else 0) | (2 if frame["brs"] else 0) | (4 if frame["esi"] else 0)
        put(b, at + 4, cob, 4)
        b[at + 8:at + 8 + len(data)] = data

    def decode(self, inputs, at):
        b = inputs
        fd = brs = esi = False
        stamp = 0
        if self.format == "11-bit":
            word = u16(b, at)
            ident, rtr, extended, length = word >> 5, bool(word & 0x10), False, min(word & 0xF, 8)
            data_at = at + 2
        else:
            if self.format == "29-bit":
                length, cob, data_at = u16(b, at), get(b, at + 2, 4), at + 6
                if self.ts:
                    stamp = get(b, at + 14, 8)
            else:
                length, flags, cob, data_at = b[at], b[at + 1], get(b, at + 2, 4), at + 6
                fd, brs, esi = bool(flags & 1), bool(flags & 2), bool(flags & 4)
                stamp = get(b, at + 70, 8)
            ident = cob & 0x1FFFFFFF
            extended, rtr = bool(cob & 0x80000000), bool(cob & 0x40000000)
            length = min(length, 64 if fd else 8)
            if fd:
                length = next(size for size in FD_SIZES if size >= length)
        data = b"" if rtr else bytes(b[data_at:data_at + length])
        frame = {"id": ident, "extended": extended, "rtr": rtr, "fd": fd,
                 "brs": brs if fd else False, "esi": esi if fd else False, "len": length, "data": data}
        return {"frame": frame, "transaction_number": 0, "time_stamp_ns": stamp}

    def task(self, inputs, requests):
        refused = []
        for index, message in enumerate(requests):
            if self.fits(message):
                self.queue.append(message)
            else:
                refused.append(index)
        delivered = []
        # Read: a new Inputs.RxCounter means NoOfRxMessages new messages.
        if u16(inputs, 2) != u16(self.outputs, 2):
            count = min(u16(inputs, 4), self.rx_slots)
            for n in range(count):
                delivered.append(self.decode(inputs, self.rx_start + n * self.rx_size))
            self.outputs[2:4] = inputs[2:4]
        # Sent: up to the message Inputs.TransactionNumber names.
        sent = []
        if self.with_tn and u16(inputs, 6) in self.in_flight:
            last = self.in_flight.index(u16(inputs, 6))
            sent, self.in_flight = self.in_flight[:last + 1], self.in_flight[last + 1:]
        # Send: only while the last batch is acknowledged.
        if u16(self.outputs, 0) == u16(inputs, 0) and self.queue:
            count = min(len(self.queue), self.tx_slots)
            for n in range(count):
                message = self.queue.pop(0)
                self.encode(6 + n * self.tx_size, message)
                if self.with_tn:
                    self.in_flight.append(message["transaction_number"])
            put(self.outputs, 4, count, 2)
            put(self.outputs, 0, (u16(inputs, 0) + 1) & 0xFFFF, 2)
        return {"type": "tasked", "outputs": bytes(self.outputs), "delivered": delivered,
                "refused": refused, "sent": sent}


# Protocol 3 (docs/adapter-protocol.md, "Protocol 3"): the tasks as records
# in memory shared with the harness, a wake-up each way; the lines carry only
# `start` and `bye`. Offsets and fields as the document lays them out.
REQUEST_SEQ, IUT_ASLEEP, ANSWER_SEQ, HARNESS_ASLEEP = 64, 68, 128, 132
OUTPUTS_AT, INPUTS_AT = 4096, 4096 + 65536
REQUEST_AT = INPUTS_AT + 65536
RECORD_ROOM = ((24 + 4096 * 96 + 4095) // 4096) * 4096
ANSWER_AT = REQUEST_AT + RECORD_ROOM
TASK, TASKED, ERROR = 7, 106, 102
MESSAGE, REFUSED, SENT = 9, 10, 11
SPIN_S = 0.002 if len(os.sched_getaffinity(0)) > 1 else 0
HEAD = struct.Struct("<IIQII")      # kind, count, time, outputs_len, inputs_len
ENTRY = struct.Struct("<IIQIBBH64sQ")  # tag, aux, time, id, flags, len, tn, data, stamp


class Shared:
    def __init__(self, offer):
        self.map = mmap.mmap(offer["memfd"], offer["size"])
        self.wake_iut, self.wake_harness = offer["wake_iut"], offer["wake_harness"]
        self.seen = self.word(REQUEST_SEQ)
        self.poller = select.poll()
        self.poller.register(self.wake_iut, select.POLLIN)
        self.poller.register(sys.stdin.fileno(), select.POLLIN)

    def word(self, at):
        return struct.unpack_from("<I", self.map, at)[0]

    def next_task(self):
        """The next task's (inputs, outputs, requests), or None when a line waits."""
        # A moment's spin first: the harness's next task usually comes within
        # it, and a wake-up from sleep costs more than the task itself.
        until = time.perf_counter() + SPIN_S
        while self.word(REQUEST_SEQ) == self.seen and time.perf_counter() < until:
            pass
        while self.word(REQUEST_SEQ) == self.seen:
            struct.pack_into("<I", self.map, IUT_ASLEEP, 1)
            if self.word(REQUEST_SEQ) != self.seen:
                struct.pack_into("<I", self.map, IUT_ASLEEP, 0)
                break
            ready = dict(self.poller.poll(1000))
            struct.pack_into("<I", self.map, IUT_ASLEEP, 0)
            if self.wake_iut in ready:
                try:
                    os.eventfd_read(self.wake_iut)
                except BlockingIOError:
                    pass
            if sys.stdin.fileno() in ready and self.word(REQUEST_SEQ) == self.seen:
                return None
        self.seen = self.word(REQUEST_SEQ)
        kind, count, _, outputs_len, inputs_len = HEAD.unpack_from(self.map, REQUEST_AT)
        if kind != TASK:
            raise ValueError("a record of kind %d where a task was due" % kind)
        requests = []
        for n in range(count):
            _, aux, _, ident, flags, length, tn, data, _ = ENTRY.unpack_from(self.map, REQUEST_AT + 24 + 96 * n)
            frame = {"id": ident, "extended": bool(flags & 1), "rtr": bool(flags & 2), "fd": bool(flags & 4),
                     "brs": bool(flags & 8), "esi": bool(flags & 16), "len": length, "data": data[:aux]}
            requests.append({"frame": frame, "transaction_number": tn, "time_stamp_ns": 0})
        inputs = self.map[INPUTS_AT:INPUTS_AT + inputs_len]
        return inputs, requests

    def answer(self, tasked):
        outputs = tasked["outputs"]
        self.map[OUTPUTS_AT:OUTPUTS_AT + len(outputs)] = outputs
        entries = []
        for message in tasked["delivered"]:
            frame = message["frame"]
            data = frame["data"]
            flags = sum(bit for bit, key in ((1, "extended"), (2, "rtr"), (4, "fd"), (8, "brs"), (16, "esi")) if frame[key])
            entries.append(ENTRY.pack(MESSAGE, len(data), 0, frame["id"], flags, frame["len"],
                                      message["transaction_number"], data, message["time_stamp_ns"]))
        entries += [ENTRY.pack(REFUSED, index, 0, 0, 0, 0, 0, b"", 0) for index in tasked["refused"]]
        entries += [ENTRY.pack(SENT, 0, 0, 0, 0, 0, number, b"", 0) for number in tasked["sent"]]
        record = HEAD.pack(TASKED, len(entries), 0, len(outputs), 0) + b"".join(entries)
        self.map[ANSWER_AT:ANSWER_AT + len(record)] = record
        struct.pack_into("<I", self.map, ANSWER_SEQ, self.seen)
        if self.word(HARNESS_ASLEEP):
            os.eventfd_write(self.wake_harness, 1)


def lines(tasked):
    """A task's answer as the line carries it: bytes as hex."""
    for message in tasked["delivered"]:
        message["frame"]["data"] = message["frame"]["data"].hex()
    tasked["outputs"] = tasked["outputs"].hex()
    return tasked


def main():
    client = None
    shared = None
    while True:
        if shared is not None:
            task = shared.next_task()
            if task is not None:
                inputs, requests = task
                shared.answer(client.task(inputs, requests))
                continue
        line = sys.stdin.readline()
        if not line:
            return
        request = json.loads(line)
        kind = request["type"]
        if kind == "bye":
            return
        if kind == "start":
            client = Client(request["config"])
            # Protocol 3 where the harness offers it and Python can map it.
            offer = request.get("shared")
            # (`--lines`: version 1 only, every task a line, to read them.)
            usable = offer and request["protocol"] >= 3 and hasattr(os, "eventfd_read")
            shared = Shared(offer) if usable and "--lines" not in sys.argv[1:] else None
            # What this client is (docs/plc-side.md): any slot count, both
            # ways, one stream; a restarted program (a new process) delivers
            # the batch it finds in the image, perhaps again (P3).
            # Each start makes a new Client: nothing of the program before is
            # kept, so canif may start the next program in this process.
            answer = {"type": "started", "protocol": 3 if shared else 1, "tells_sent": True, "restarts": True,
                      "declares": {"slots": "1..32", "direction": "both",
                                   "application": "one-stream",
                                   "restart": "delivers-twice"}}
        elif kind == "task" and client is not None:
            requests = request["requests"]
            for message in requests:
                message["frame"]["data"] = bytes.fromhex(message["frame"]["data"])
            answer = lines(client.task(bytes.fromhex(request["inputs"]), requests))
        else:
            answer = {"type": "error", "message": "unexpected request " + kind}
        sys.stdout.write(json.dumps(answer, separators=(",", ":")) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
