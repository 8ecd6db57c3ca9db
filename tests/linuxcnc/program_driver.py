#!/usr/bin/python3
"""A headless LinuxCNC display for tests/test_check_path_machine.py: LinuxCNC starts it as its
[DISPLAY] program. It homes, then runs each G-code program of $KINGEN_PROGRAMS (a JSON list of
paths; each ends where it started) in AUTO mode, every 10 ms recording the line motion is
executing, the world position and each joint's velocity as motion computes it (per servo
period, so independent of how late a loaded machine runs it), and keeping every message of
LinuxCNC's error channel; it writes everything as JSON to $KINGEN_RESULT, then exits, and
LinuxCNC shuts down. Runs under Debian's /usr/bin/python3 (the linuxcnc module)."""

import json
import os
import time

import linuxcnc

from display import command, power_on_and_home, status

result = {"log": [], "programs": []}
errors = linuxcnc.error_channel()


def run(program):
    """Run one program from the machine's current position: what happened. The run ends once
    the program, having started (the interpreter busy, or LinuxCNC reporting an error), has the
    interpreter idle again and motion with no segment left and in position (a loaded machine's
    motion can lag the interpreter by many polls); a program not started within 5 s is an error."""
    run = {"errors": [], "samples": []}
    command.mode(linuxcnc.MODE_AUTO)
    command.wait_complete()
    command.program_open(program)
    command.wait_complete()
    command.auto(linuxcnc.AUTO_RUN, 0)
    started, running = time.time(), False
    while time.time() - started < 120:
        status.poll()
        run["samples"].append({"line": status.motion_line, "world": list(status.actual_position[:6]),
                               "velocities": [joint["velocity"] for joint in status.joint[:status.joints]]})
        message = errors.poll()
        if message:
            run["errors"].append({"kind": message[0], "text": message[1]})
        idle = status.interp_state == linuxcnc.INTERP_IDLE
        running = running or not idle or bool(run["errors"])
        if running and idle and status.queue == 0 and status.inpos:
            break
        if not running and time.time() - started > 5:
            run["errors"].append({"kind": "driver", "text": "the program did not start in 5 s"})
            break
        time.sleep(0.01)
    time.sleep(0.2)
    while True:
        message = errors.poll()
        if not message:
            break
        run["errors"].append({"kind": message[0], "text": message[1]})
    run["finished"] = not run["errors"]
    command.abort()
    command.wait_complete()
    return run


try:
    power_on_and_home()
    for program in json.loads(os.environ["KINGEN_PROGRAMS"]):
        result["programs"].append(run(program))
except Exception as error:
    result["log"].append(repr(error))
finally:
    with open(os.environ["KINGEN_RESULT"], "w") as stream:
        json.dump(result, stream)
