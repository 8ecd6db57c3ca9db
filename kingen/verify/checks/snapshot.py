"""``snapshot``: the routine against a recorded snapshot (:mod:`kingen.verify.snapshot`): joints
where the recording solved the posture, warnings everywhere; the detail names the worst."""

import numpy as np

from ...kinematics.routine import WARNING_NAMES, WARNINGS
from .base import Check, VerifyCheck

WORST_SHOWN = 3


def check(robot, snapshot, call):
    """The ``snapshot`` check: ``call(t6)`` gives the routine's (solutions, warnings) for the
    snapshot's T6; joints are compared where the recording solved the posture, warnings
    everywhere. The detail names the worst entries."""
    t6 = np.array([entry.t6 for entry in snapshot.entries], dtype=float).reshape(-1, 4, 4)
    recorded = np.array([[[np.nan if v is None else v for v in row] for row in entry.joints]
                         for entry in snapshot.entries], dtype=float).reshape(len(t6), robot.dof, robot.postures)
    recorded_warnings = np.array([entry.warnings for entry in snapshot.entries], dtype=int).reshape(len(t6), -1)
    solutions, warnings = call(t6)
    units = np.array(snapshot.joint_units)
    tolerance = np.where(units == "rad", snapshot.tolerance.rad, snapshot.tolerance.mm)[None, :, None]
    difference = solutions - recorded
    difference[:, units == "rad"] = difference[:, units == "rad"] - 2 * np.pi * np.rint(
        difference[:, units == "rad"] / (2 * np.pi))
    error = np.where(np.isfinite(difference), np.abs(difference), np.inf)
    solved = (recorded_warnings != WARNINGS["WARN_UNREACHABLE"])[:, None, :]
    excess = np.where(solved, error / tolerance, 0.0)
    wrong_values = int(np.count_nonzero(excess > 1.0))
    wrong_warnings = int(np.count_nonzero(warnings != recorded_warnings))
    detail = (f"{len(t6)} recorded poses x {robot.postures} postures ({snapshot.recorded_from}, kingen "
              f"{snapshot.kingen}): {wrong_values} joints beyond {snapshot.tolerance.mm:g} mm / "
              f"{snapshot.tolerance.rad:g} rad, {wrong_warnings} warnings differ")
    worst = []
    for flat in np.argsort(excess, axis=None)[::-1][:WORST_SHOWN]:
        pose, joint, posture = np.unravel_index(flat, excess.shape)
        if excess[pose, joint, posture] > 1.0:
            worst.append(f"pose {pose} posture {posture} {snapshot.joint_names[joint]}: recorded "
                         f"{recorded[pose, joint, posture]:.9g}, now {solutions[pose, joint, posture]:.9g} "
                         f"{units[joint]}")
    for pose, posture in list(zip(*np.nonzero(warnings != recorded_warnings)))[:WORST_SHOWN]:
        worst.append(f"pose {pose} posture {posture}: recorded warning {WARNING_NAMES.get(recorded_warnings[pose, posture])}, "
                     f"now {WARNING_NAMES.get(int(warnings[pose, posture]), warnings[pose, posture])}")
    result = Check("snapshot", not wrong_values and not wrong_warnings, detail, worst)
    if snapshot.definition_sha256 != robot.sha256:
        result.diagnoses.append(f"recorded from another definition (sha256 {snapshot.definition_sha256[:16]}; "
                                f"the robot file has {robot.sha256[:16]}): record it again if the change was meant")
    return result


class Snapshot(VerifyCheck, name="snapshot", needs="snapshot", item="snapshot"):
    def run(self, context):
        def call(t6):
            calls = context.call(t6)
            return calls.solutions, calls.warnings

        return [check(context.robot, context.options.snapshot, call)]
