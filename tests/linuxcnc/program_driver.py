#!/usr/bin/python3
"""A headless LinuxCNC display for tests/test_check_path_machine.py: LinuxCNC starts it as its
[DISPLAY] program. It homes, then runs each G-code program of $KINGEN_PROGRAMS (a JSON list of
paths; each ends where it started) in AUTO mode, every 10 ms recording the line motion is
executing, the world position and each joint's velocity as motion computes it (per servo
period, so independent of how late a loaded machine runs it), and keeping every message of
LinuxCNC's error channel; with $KINGEN_SAMPLER set, also every servo period's line and joint
velocities that HAL's sampler recorded while the program ran ("servo"); it writes everything as
JSON to $KINGEN_RESULT, then exits, and LinuxCNC shuts down. Runs under Debian's /usr/bin/python3 (the linuxcnc module)."""

import json
import os
import subprocess
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
    sampled = bool(os.environ.get("KINGEN_SAMPLER"))
    if sampled:
        subprocess.run(["halcmd", "setp", "sampler.0.enable", "1"], check=True)
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
    if sampled:
        run["servo"] = servo_samples()
    command.abort()
    command.wait_complete()
    return run


def servo_samples():
    """Stop HAL's sampler and read what it holds: [line, joint velocities...] per servo period."""
    subprocess.run(["halcmd", "setp", "sampler.0.enable", "0"], check=True)
    depth = int(subprocess.run(["halcmd", "-s", "getp", "sampler.0.curr-depth"], check=True, capture_output=True,
                               text=True).stdout.split()[0])
    if depth == 0:
        return []
    text = subprocess.run(["halsampler", "-n", str(depth)], check=True, capture_output=True, text=True,
                          timeout=60).stdout
    rows = [line.split() for line in text.splitlines()]  # "overrun" marks a gap (none expected): not a sample
    return [[float(value) for value in row] for row in rows if row and row[0] != "overrun"]


try:
    power_on_and_home()
    for program in json.loads(os.environ["KINGEN_PROGRAMS"]):
        result["programs"].append(run(program))
except Exception as error:
    result["log"].append(repr(error))
finally:
    with open(os.environ["KINGEN_RESULT"], "w") as stream:
        json.dump(result, stream)
