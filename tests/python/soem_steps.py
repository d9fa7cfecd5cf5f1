"""Steps both SOEM scripts take (pysoem_master.py, pysoem_start_up.py):
written once, from SOEM's API."""

import sys

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
