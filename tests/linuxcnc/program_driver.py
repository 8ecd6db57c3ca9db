#!/usr/bin/python3
"""A headless LinuxCNC display for tests/test_check_path_machine.py: LinuxCNC starts it as its
[DISPLAY] program. It homes, runs the G-code program $KINGEN_PROGRAM in AUTO mode, and every
10 ms records the time, the line motion is executing, the world position and the joint positions; it
keeps every message of LinuxCNC's error channel, and writes everything as JSON to
$KINGEN_RESULT when the program ends or stops; then it exits, and LinuxCNC shuts down. Runs
under Debian's /usr/bin/python3 (the linuxcnc module)."""

import json
import os
import time

import linuxcnc

result = {"log": [], "errors": [], "samples": [], "finished": False}
status, command, errors = linuxcnc.stat(), linuxcnc.command(), linuxcnc.error_channel()


def wait(condition, what, timeout=30.0):
    end = time.time() + timeout
    while time.time() < end:
        status.poll()
        if condition():
            return
        time.sleep(0.01)
    raise TimeoutError(f"no {what} in {timeout:g} s")


try:
    wait(lambda: True, "status")
    command.state(linuxcnc.STATE_ESTOP_RESET)
    command.state(linuxcnc.STATE_ON)
    wait(lambda: status.task_state == linuxcnc.STATE_ON, "machine on")
    command.mode(linuxcnc.MODE_MANUAL)
    command.wait_complete()
    command.home(-1)
    wait(lambda: all(status.homed[:status.joints]), "homing")
    command.mode(linuxcnc.MODE_AUTO)
    command.wait_complete()
    command.program_open(os.environ["KINGEN_PROGRAM"])
    command.wait_complete()
    command.auto(linuxcnc.AUTO_RUN, 0)
    started = time.time()
    while time.time() - started < 120:
        status.poll()
        result["samples"].append({"time": time.time(), "line": status.motion_line, "world": list(status.actual_position[:6]),
                                  "joints": list(status.joint_actual_position[:status.joints])})
        message = errors.poll()
        if message:
            result["errors"].append({"kind": message[0], "text": message[1], "line": status.motion_line})
        if time.time() - started > 0.5 and status.interp_state == linuxcnc.INTERP_IDLE and status.queue == 0:
            break
        time.sleep(0.01)
    time.sleep(0.2)
    message = errors.poll()
    if message:
        result["errors"].append({"kind": message[0], "text": message[1], "line": status.motion_line})
    status.poll()
    result["finished"] = not result["errors"]
    result["last_line"] = status.motion_line
except Exception as error:
    result["log"].append(repr(error))
finally:
    with open(os.environ["KINGEN_RESULT"], "w") as stream:
        json.dump(result, stream)
