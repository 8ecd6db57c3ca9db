#!/usr/bin/python3
"""A headless LinuxCNC display for tests/test_linuxcnc_machine.py: LinuxCNC starts it as its
[DISPLAY] program. It homes, jogs joint j by v in joint mode first when $KINGEN_FIRST_JOG is "j v", makes the
MDI moves of $KINGEN_MOVES (on the axes $KINGEN_AXES, default XYZABC), jogs joint 0
by $KINGEN_JOG in joint mode, reads joint and world positions back after each (and after each
move the module's load pins, its payload.mass set to $KINGEN_PAYLOAD kg first when given), reads the
kinematics module's pins with halcmd, and writes everything as JSON to $KINGEN_RESULT; then it
exits, and LinuxCNC shuts down. Runs under Debian's /usr/bin/python3 (the linuxcnc module)."""

import json
import os
import subprocess
import time

import linuxcnc

from display import command, power_on_and_home, status, wait

result = {"log": [], "moves": []}


def settled():
    wait(lambda: status.inpos and status.queue == 0 and status.interp_state == linuxcnc.INTERP_IDLE, "end of motion")
    time.sleep(0.1)
    status.poll()
    return {"joints": list(status.joint_actual_position[:status.joints]), "world": list(status.actual_position[:6])}


def load_pins():
    """The module's pins load.0, load.1, ... (N or N m) as halcmd reads them."""
    loads, index = [], 0
    while True:
        read = subprocess.run(["halcmd", "-s", "getp", f"{os.environ['KINGEN_MODULE']}.load.{index}"],
                              capture_output=True, text=True)
        if read.returncode != 0:
            return loads
        loads.append(float(read.stdout))
        index += 1


def jog_joint(joint, increment):
    """Jog ``joint`` by ``increment`` in joint (free) mode; (before, after) positions."""
    command.mode(linuxcnc.MODE_MANUAL)
    command.wait_complete()
    command.teleop_enable(0)
    command.traj_mode(linuxcnc.TRAJ_MODE_FREE)
    time.sleep(0.2)
    before = settled()
    command.jog(linuxcnc.JOG_INCREMENT, True, joint, 10.0, increment)  # units/s
    time.sleep(0.2)
    return {"before": before, "after": settled()}


try:
    if os.environ.get("KINGEN_PAYLOAD"):  # the payload's mass (kg) at the platform origin, for the load pins
        subprocess.run(["halcmd", "setp", f"{os.environ['KINGEN_MODULE']}.payload.mass", os.environ["KINGEN_PAYLOAD"]],
                       check=True)
    power_on_and_home()
    result["homed"] = settled()
    if os.environ.get("KINGEN_FIRST_JOG"):  # "joint increment": off a home where world moves cannot start
        joint, increment = os.environ["KINGEN_FIRST_JOG"].split()
        result["first_jog"] = jog_joint(int(joint), float(increment))
    command.mode(linuxcnc.MODE_MDI)
    command.wait_complete()
    for pose in json.loads(os.environ["KINGEN_MOVES"]):
        axes = os.environ.get("KINGEN_AXES", "XYZABC")
        command.mdi("G90 G0 " + " ".join(f"{axis}{value:.12f}" for axis, value in zip(axes, pose)))
        command.wait_complete(60)
        result["moves"].append({"pose": pose, **settled(), "loads": load_pins()})
    result["jog"] = jog_joint(0, float(os.environ["KINGEN_JOG"]))
    pins = subprocess.run(["halcmd", "-s", "show", "pin", os.environ["KINGEN_MODULE"]], capture_output=True, text=True)
    result["pins"] = pins.stdout
except Exception as error:
    result["log"].append(repr(error))
finally:
    channel, result["errors"] = linuxcnc.error_channel(), []
    while True:  # what LinuxCNC reported (a kinematics failure stops motion without an exception here)
        message = channel.poll()
        if not message:
            break
        result["errors"].append(message[1])
    with open(os.environ["KINGEN_RESULT"], "w") as stream:
        json.dump(result, stream)
