"""``golden[i]``: each golden value of the robot file (published joints for a pose) against
the routine and the reference, in the file's units, with empty calibration fields. Its line
names the entry by the start of its source (the JSON report keeps the whole text) and shows
numbers to the tolerance's precision; a failure names the joints that are off."""

import math

import numpy as np

from ...conventions import t6_from_pose
from ...kinematics.reference import solve
from ..report import GoldenResult
from ...units import LENGTH_UNITS
from .base import Check, VerifyCheck

SOURCE_CHARACTERS = 38
"""How much of a golden entry's source its line shows (an ellipsis marks the cut)."""
NAMED_JOINTS = 2
"""How many failing joints a line names (it counts the others)."""


def short_source(source):
    """``source`` cut to SOURCE_CHARACTERS characters, its last an ellipsis where text was cut."""
    return source if len(source) <= SOURCE_CHARACTERS else source[:SOURCE_CHARACTERS - 1].rstrip() + "\u2026"


def decimals(tolerance):
    """The decimals that show ``tolerance``'s leading digit: 0.0003 -> 4, 0.02 -> 2, 5 -> 0."""
    return max(0, -math.floor(math.log10(tolerance))) if tolerance > 0 else 6


def golden_detail(robot, result):
    """One line for ``result``, in the robot file's units: its source's start, its posture, and
    either the worst joint's error (passed) or each joint off by more than the tolerance,
    named by the robot's joint names, with its error and who is off (routine, reference)."""
    prismatic = not robot.joint_types[0].wraps
    scale = LENGTH_UNITS[robot.length_unit] if prismatic else 1.0
    unit = robot.length_unit if prismatic else "degrees"
    tolerance = result.tolerance / scale
    places = decimals(tolerance)
    expected, routine, reference = (np.asarray(values) / scale for values in (result.expected, result.plugin, result.reference))
    routine_off, reference_off = np.abs(routine - expected), np.abs(reference - expected)
    head = f"{short_source(result.source)}: posture {result.posture}: "
    if result.passed:
        worst = int(np.argmax(routine_off))
        return (f"{head}within {tolerance:.{places}f} {unit}, worst {robot.joint_names[worst]} by "
                f"{routine_off[worst]:.{places}f}")
    failing = [index for index in range(len(expected)) if max(routine_off[index], reference_off[index]) > tolerance]
    words = []
    for index in failing[:NAMED_JOINTS]:
        who = ("" if routine_off[index] > tolerance and reference_off[index] > tolerance
               else "routine's " if routine_off[index] > tolerance else "reference's ")
        off = max(routine_off[index], reference_off[index])
        value = routine[index] if routine_off[index] > tolerance else reference[index]
        words.append(f"{who}{robot.joint_names[index]} off by {off:.{places}f} {unit} "
                     f"({value:.{places}f} for {expected[index]:.{places}f})")
    more = f" and {len(failing) - NAMED_JOINTS} more" if len(failing) > NAMED_JOINTS else ""
    return f"{head}{'; '.join(words)}{more} (tolerance {tolerance:.{places}f})"


def check_golden(robot, plugin):
    """Each golden value of the robot against the plugin and the reference, in YAML units."""
    results = []
    scale = robot.joint_scale()
    for golden in robot.golden:
        t6 = t6_from_pose(np.asarray([golden.pose]))
        plugin.reset_host()
        from_plugin = plugin.call(t6).solutions[0, :, golden.posture] / scale
        from_reference = solve(robot, t6).joints[0, :, golden.posture] / scale
        expected = np.asarray(golden.joints)
        passed = bool(
            np.all(np.abs(from_plugin - expected) <= golden.tolerance)
            and np.all(np.abs(from_reference - expected) <= golden.tolerance)
        )
        results.append(GoldenResult(
            source=" ".join(golden.source.split()), pose=list(golden.pose), posture=golden.posture,
            expected=list(golden.joints), plugin=[float(v) for v in from_plugin],
            reference=[float(v) for v in from_reference], tolerance=golden.tolerance, passed=passed,
        ))
    return results


class Golden(VerifyCheck, name="golden", needs="golden values"):
    def run(self, context):
        context.report.golden = check_golden(context.robot, context.routine)
        return [Check(f"golden[{i}]", result.passed, golden_detail(context.robot, result))
                for i, result in enumerate(context.report.golden)]
