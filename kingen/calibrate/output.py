"""The calibrated robot file: the robot file with every limb written out (a layout expanded to
explicit limbs) with the identified values in the file's own length unit, renamed ``<name>_calibrated``, its ``source``
naming the measurement file; golden values are dropped (they were published for the
drawing). A machine with task coordinates keeps its task and passive leg: the identified
constraint axes are written in its limbs, the passive leg's identified geometry in
``passive_leg``, and its verification home is moved onto the calibrated machine's manifold (its
task coordinates kept), so that it is a pose the calibrated machine takes. A machine with a
serial wrist keeps ``wrist`` and ``tool`` with the identified zero offsets, axes and the tool's
origin moved along its z axis to the identified reach. A leg's reference length is written
signed (an absolute-length strut's encoder offset may be below 0). The robot file's writer is the design
optimiser's (kingen.design.problem)."""

import copy
import math

from ..kinematics.hybrid.parasitic import on_manifold

from ..design.problem import robot_yaml, suffixed_name
from ..units import LENGTH_UNITS, scaled_limbs

CALIBRATED = "_calibrated"


def calibrated_name(name):
    """``<name>_calibrated``, cut to stay a name kingen accepts."""
    return suffixed_name(name, CALIBRATED)


def calibrated_yaml(data, parameters, values, header):
    """The calibrated robot file's text from the robot file's plain ``data``, Parameters
    ``parameters`` and identified ``values`` (mm, degrees); ``header`` lines on top and as
    the file's ``source``."""
    data = copy.deepcopy(data)
    for key in ("layout", "golden", "optimize"):
        data.pop(key, None)
    robot = parameters.robot_of(values)
    limbs = scaled_limbs(robot.limbs, 1.0 / LENGTH_UNITS[robot.length_unit])
    data["limbs"] = [limb.model_dump(mode="json", exclude_defaults=True) | {"model": limb.model} for limb in limbs]
    if robot.parallel.task:
        _constrained(data, robot.parallel)
    if robot.wrist is not None:
        _wrist(data, robot.wrist)
    data["name"] = calibrated_name(data["name"])
    data["description"] = f"{' '.join(str(data.get('description', '')).split())} Calibrated by kingen."
    data["source"] = " ".join(header)
    return robot_yaml(data, header)


def _constrained(data, robot):
    """Put ``robot``'s passive leg and its verification home on its own manifold into the robot
    file's plain ``data`` (the file's length unit)."""
    scale = 1.0 / LENGTH_UNITS[robot.length_unit]
    leg = robot.passive_leg
    if leg is not None:
        data["passive_leg"] = {"base_point": [float(value) * scale for value in leg.base_point],
                               "first_axis": [float(value) for value in leg.first_axis],
                               "tube_axis": [float(value) for value in leg.tube_axis]}
    home = on_manifold(robot, [robot.verification.home])[0]
    data.setdefault("verification", {})["home"] = [float(value) * scale for value in home[:3]] + \
        [float(value) for value in home[3:]]


def _wrist(data, wrist):
    """Put the identified ``wrist``'s zero offsets and axes and its tool frame's origin (mm: a
    wrist's robot file is in mm) into the robot file's plain ``data``."""
    for joint, axis, zero in zip(data["wrist"], wrist.axes, wrist.zero):
        joint["axis"] = [float(value) for value in axis]
        joint["zero_offset"] = math.degrees(zero)
    data["tool"] = [float(value) for value in wrist.tool[:3, 3]] + [float(value) for value in data["tool"][3:]]

