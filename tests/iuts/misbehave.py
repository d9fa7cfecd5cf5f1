"""A deliberately broken IUT for tests/iut_boundary.rs: it speaks the adapter
protocol correctly (a device that accepts every configuration, answers every
cycle with an empty input image) except for one misbehaviour, chosen by argv[1]:

  babble       every poll_transmit answers a frame (a babbling controller)
  stuck-time   every poll_transmit answers next_ns = now_ns + 1
  lie-len      every poll_transmit answers a frame whose len says 15, data 8
  fork-hang    starts a child that sleeps, records both pids, then hangs
  setsid-hang  the same with a child in a session of its own (out of the process group)
  daemon-hang  a daemon: double fork, setsid, stdio closed, exec with an empty
               environment (nothing marks it as the IUT's), then hangs
  exit-leaving-child  starts a child that sleeps, records both pids, and exits
               at the first cycle: the child, orphaned, lives on
"""
import json
import os
import shutil
import subprocess
import sys

mode = sys.argv[1]
pids = os.environ.get("CANIF_TEST_PIDS")
if pids:
    with open(pids, "a") as f:
        f.write(f"{os.getpid()}\n")
if mode in ("fork-hang", "setsid-hang", "exit-leaving-child"):
    # The orphan holds no end of the protocol: canif sees its parent exit.
    quiet = subprocess.DEVNULL if mode == "exit-leaving-child" else None
    child = subprocess.Popen(["sleep", "3600"], start_new_session=mode == "setsid-hang",
                             stdin=quiet, stdout=quiet)
    if pids:
        with open(pids, "a") as f:
            f.write(f"{child.pid}\n")
if mode == "daemon-hang":
    sleep = shutil.which("sleep")
    first = os.fork()
    if first == 0:
        os.setsid()
        if os.fork() == 0:
            if pids:
                with open(pids, "a") as f:
                    f.write(f"{os.getpid()}\n")
            null = os.open(os.devnull, os.O_RDWR)
            for fd in (0, 1, 2):
                os.dup2(null, fd)
            os.execve(sleep, ["sleep", "3600"], {})
        os._exit(0)
    os.waitpid(first, 0)
input_size = 0
for line in sys.stdin:
    request = json.loads(line)
    kind = request["type"]
    if kind == "configure":
        input_size = request["config"]["input_size"]
        answer = {"type": "configured", "protocol": 1, "accepted": True}
    elif kind == "cycle":
        if mode in ("fork-hang", "setsid-hang", "daemon-hang"):
            continue  # never answers: the harness's timeout must end both processes
        if mode == "exit-leaving-child":
            os._exit(3)  # the child, orphaned, is canif's to end
        answer = {"type": "inputs", "inputs": "00" * input_size}
    elif kind == "poll_transmit":
        frame = {"id": 0x123, "extended": False, "rtr": False, "fd": False, "brs": False,
                 "esi": False, "len": 8, "data": "0102030405060708"}
        if mode == "babble":
            answer = {"type": "transmit", "frame": frame}
        elif mode == "stuck-time":
            answer = {"type": "transmit", "frame": None, "next_ns": request["now_ns"] + 1}
        elif mode == "lie-len":
            answer = {"type": "transmit", "frame": dict(frame, len=15)}
        elif mode == "brs-classic":
            answer = {"type": "transmit", "frame": dict(frame, brs=True)}
        elif mode == "wide-id":
            answer = {"type": "transmit", "frame": dict(frame, id=0x1234)}
        else:
            answer = {"type": "transmit", "frame": None}
    elif kind == "bye":
        break
    else:
        answer = {"type": "ok"}
    sys.stdout.write(json.dumps(answer) + "\n")
    sys.stdout.flush()
