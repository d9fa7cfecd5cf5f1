"""Stands between the harness and `canif device --stdio` (argv[1:]) and exits
the moment the device has a frame to send: the protocol break must be an
error naming the exit, never a non-conformance on HS-TX-*."""
import json
import subprocess
import sys

device = subprocess.Popen(sys.argv[1:], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
for line in sys.stdin:
    device.stdin.write(line)
    device.stdin.flush()
    answer = device.stdout.readline()
    message = json.loads(answer)
    # Protocol 1 hands the frame over in `transmit`, protocol 2 lists it in the plan.
    if (message.get("type") == "transmit" and message.get("frame") is not None) or (
        message.get("type") == "stepped" and message.get("plan")
    ):
        device.kill()
        print("dying with a frame due", file=sys.stderr)
        sys.exit(3)
    sys.stdout.write(answer)
    sys.stdout.flush()
