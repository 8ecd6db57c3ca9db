"""The C host's own verify checks, and ``CHECKS``: every check a C host library gets, in
report order (the shared ones of :mod:`kingen.verify.checks` and these three).

- ``forward``: the library's forward kinematics, given the reference's joints of a sampled
  pose's regular posture and started a servo cycle away (0.01 mm, 0.01 degree along random
  directions of the free coordinates) and far away (10 mm, 5 degrees), returns that pose
  within the value bound or what the posture's conditioning explains; near starts must all
  return it where Newton's convergence from them is assured (Kantorovich's condition,
  kingen.verify.checks.round_trip.newton_assured; a machine with a wrist: every one), far ones
  may fail or return another assembly mode (a pose the reference gives these
  joints, within a thousand times the value bounds) but never a pose without these joints. A
  machine with task coordinates is started off in those only, and the whole pose it writes
  (its parasitic coordinates too) is compared; a machine with a wrist is started off in every
  coordinate, and the tool's tip and axis it writes are compared (the turn about the axis is free).
- ``c jacobian``: the library's analytic Jacobian against kingen's
  (:func:`kingen.kinematics.singularity.jacobian`) on regular postures of the sample (a machine
  with task coordinates: the limbs' rows at the machine's pose, which the regular sampled poses
  are, those off its manifold being unreachable; a machine with a wrist: the legs' and the wrist's
  rates per tool twist, :func:`kingen.kinematics.hybrid.wrist_rates.tool_jacobian`).
- ``c direct index``: for six-limb robots, the library's direct index against kingen's
  (:func:`kingen.kinematics.singularity.direct_index`) on regular postures of the sample.
- ``c machine pose``: for a machine with task coordinates and no wrist, the library's machine
  pose and its status against kingen's (:func:`kingen.kinematics.hybrid.parasitic.solve_parasitic`) on
  the sampled poses, those off the machine's manifold and those beside the warnings' boundaries
  among them.
- ``c loads``: the library's static loads (a wrist's joints' torques after the legs' loads)
  against kingen's (:func:`kingen.kinematics.loads.loads`) on regular postures of the sample,
  holding the robot file's payload (or, where it gives none, a stand-in: 10 kg whose centre lies
  a tenth of the robot's size off the platform origin, so that every term is exercised); not
  exercised for a library that does not export it (optional in a hand-written one) or where
  kingen's loads hold no load on any of the postures.
"""

from dataclasses import replace

import numpy as np

from ...conventions import matrix_from_t6, pose_from_t6, wrap_difference
from ...kinematics.forward import free_mask, t6_of
from ...kinematics.loads import loads, without_parts
from ...kinematics.hybrid.parasitic import solve_parasitic
from ...kinematics.reference import solve
from ...kinematics.routine import SINGULAR_TOLERANCE, VALUE_TOLERANCE_RAD, WARNING_BAND, WARNINGS, warning_codes
from ...kinematics.singularity import direct_index, jacobian, posture_wrenches
from ...kinematics.hybrid.wrist_rates import tool_jacobian
from ...verify.checks import (Check, Closure, Definition, Determinism, Golden, Jacobian, Machine, RoundTrip, Snapshot,
                              Values, VerifyCheck, Warnings)
from ...verify.checks.jacobian import JACOBIAN_MIN_RADICAND, JACOBIAN_MIN_TRANSMISSION
from ...verify.checks.round_trip import (ROUND_TRIP_MIN_CONDITIONING, forward_seeds, newton_assured, pose_conditioning,
                                         seed_offsets)
from ...verify.options import CONDITIONING_FACTOR, report_tolerance_mm
from ...verify.report import not_exercised
from ..loads import checked_payload, payload_words
from .render import has_machine_pose

FORWARD_POSES = 500
JACOBIAN_PAIRS = 200
C_JACOBIAN_TOLERANCE = 1e-9
"""Relative to the largest entry of the joint's row (rotations as mm of arc at the robot's size)."""
C_DIRECT_INDEX_TOLERANCE = 1e-9
C_LOADS_TOLERANCE = 1e-9
"""Relative to the posture's largest actuator load."""
DIRECT_INDEX_FLOOR = 1e-6
"""The library's direct index (an eigenvalue in closed form) against kingen's (LAPACK's), relative
to the index, or to this fraction of the robot's size where the index is smaller: the closed
form's error is about eps times the largest eigenvalue, which a small index magnifies."""


def regular_pairs(robot, t6):
    """(pose index, posture, reference joints (m, dof), conditioning (m,), wrench rows (m, dof, 6),
    transmissions (m, dof)) of one regular posture per pose of ``t6`` where it has one:
    reachable, good, away from limb singularities and well conditioned for the forward."""
    expected = solve(robot, t6)
    wrenches, transmissions = _legs_wrenches(robot, expected)
    good = ((expected.warnings == WARNINGS["WARN_GOOD_SOLUTION"])
            & np.all(np.abs(transmissions) > JACOBIAN_MIN_TRANSMISSION, axis=2)
            & np.all(expected.radicands > JACOBIAN_MIN_RADICAND, axis=1)[:, None])
    pose_index = np.nonzero(np.any(good, axis=1))[0]
    # One posture per pose, taken round the postures so that each takes part.
    posture = np.array([np.nonzero(good[index])[0][index % np.count_nonzero(good[index])] for index in pose_index],
                       dtype=int)
    sampled = pose_from_t6(t6[pose_index] if robot.wrist is None else expected.platform[pose_index])
    start = np.concatenate([sampled[:, :3], np.radians(sampled[:, 3:])], axis=1)
    conditioning = pose_conditioning(robot.parallel, wrenches[pose_index, posture], start, free_mask(robot.parallel))
    keep = conditioning > ROUND_TRIP_MIN_CONDITIONING
    pose_index, posture = pose_index[keep], posture[keep]
    return (pose_index, posture, expected.joints[pose_index, :, posture], conditioning[keep],
            wrenches[pose_index, posture], transmissions[pose_index, posture])


def _legs_wrenches(robot, expected):
    """(wrenches (n, postures, dof, 6), transmissions (n, postures, dof)) of the limbs in the
    reference's ``expected`` solution: a wrist's from its parallel part at the platform's pose
    (the legs' joints are the same in both wrist branches, posture = 2 * parallel + branch)."""
    if robot.wrist is None:
        return posture_wrenches(robot, expected.points, expected.joints)
    wrenches, transmissions = posture_wrenches(robot.parallel, expected.points, expected.joints[:, :robot.dof, ::2])
    return np.repeat(wrenches, 2, axis=1), np.repeat(transmissions, 2, axis=1)


def _same_joints(robot, t6, posture, joints):
    """(n,) whether the reference gives ``joints`` (n, dof) at ``t6`` (n, 4, 4) in ``posture`` (n,),
    within the value bounds: the pose is one the forward may return (an assembly mode)."""
    finite = np.all(np.isfinite(t6), axis=(1, 2))
    solved = solve(robot, np.where(finite[:, None, None], t6, np.eye(4)))
    values = solved.joints[np.arange(len(t6)), :, posture]
    difference = np.abs(np.where(robot.revolute, wrap_difference(values - joints), values - joints))
    bound = np.where(robot.revolute, VALUE_TOLERANCE_RAD, report_tolerance_mm(robot)) * 1e3
    return finite & np.all(difference <= bound, axis=1)


class OnRegularPairs(VerifyCheck):
    """A check judging the library on one regular posture per sampled pose (the first
    ``poses`` of the sample, :func:`regular_pairs`): ``judge(context, t6, pairs)``."""

    poses = FORWARD_POSES

    def refusal(self, context):
        """Why this check does not apply to the context's robot, or None."""
        return None

    def run(self, context):
        reason = self.refusal(context)
        if reason is not None:
            return [not_exercised(self.name, reason)]
        t6 = context.tally.first[0][:self.poses]
        pairs = regular_pairs(context.robot, t6)
        if not len(pairs[0]):
            return [not_exercised(self.name, f"no regular, reachable posture among the {len(t6)} sampled poses")]
        return [self.judge(context, t6, pairs)]


class Forward(OnRegularPairs, name="forward", needs="compared poses"):
    def judge(self, context, t6, pairs):
        robot, library = context.robot, context.routine
        pose_index, posture, joints, conditioning, _, _ = pairs
        sampled = pose_from_t6(t6[pose_index])
        start = np.concatenate([sampled[:, :3], np.radians(sampled[:, 3:])], axis=1)
        free = free_mask(robot)
        allowed_mm = np.maximum(report_tolerance_mm(robot), 2.0 * CONDITIONING_FACTOR * robot.size_mm / conditioning)
        allowed_rad = np.maximum(VALUE_TOLERANCE_RAD, allowed_mm / robot.size_mm)
        generator = np.random.default_rng(context.options.seed)
        passed, parts = True, []
        for label, (distance_mm, distance_deg) in forward_seeds(robot).items():
            offset = seed_offsets(generator, len(start), distance_mm, distance_deg, free)
            offset[:, 3:] = np.radians(offset[:, 3:])
            found, iterations, returns = library.forward(joints, posture, matrix_from_t6(t6_of(start + offset)).reshape(-1, 16))
            found_t6 = np.swapaxes(found.reshape(-1, 4, 4), 1, 2)
            position = np.max(np.abs(found_t6[:, 3, :3] - t6[pose_index, 3, :3]), axis=1)
            # A wrist's tool pose is its tip and axis: the turn about the axis is free.
            rows = slice(0, 3) if robot.wrist is None else slice(2, 3)
            rotation = np.max(np.abs(found_t6[:, rows, :3] - t6[pose_index, rows, :3]), axis=(1, 2))
            converged = returns == 0
            right = converged & (position <= allowed_mm) & (rotation <= allowed_rad)
            wrong, failed = converged & ~right, ~converged
            other_mode = wrong & _same_joints(robot, found_t6, posture, joints)
            if label != "a servo cycle away":  # a far start may lie nearer another assembly mode
                wrong &= ~other_mode
            codes, counts = np.unique(returns[failed], return_counts=True)
            steps = iterations[converged]
            # A failure from a seed Newton's convergence is not assured from is no premise for a fault.
            premise = (np.ones(len(start), dtype=bool) if robot.wrist is not None
                       else newton_assured(robot, start + offset, start, joints, free))
            unjudged = (f"; {np.count_nonzero(failed & ~premise)} from a seed Newton is not assured to converge "
                        f"from, not judged" if np.any(failed & ~premise) else "")
            listed = ", ".join(f"{n} x {c}" for c, n in zip(codes, counts)) or "none"
            parts.append(f"{label}: {int(right.sum())} of {len(start)} returned the pose, {int(failed.sum())} failed"
                         f" ({listed}{unjudged}), {int(wrong.sum())}"
                         f" returned a wrong pose, {int(other_mode.sum())} another assembly mode (a pose with these "
                         f"joints)" + (f"; Newton steps mean {steps.mean():.2f}, max {steps.max()}" if len(steps) else ""))
            passed = passed and not np.any(wrong) and (label != "a servo cycle away" or not np.any(failed & premise))
        return Check("forward", passed, f"{'; '.join(parts)} (bounds {report_tolerance_mm(robot):.3g} mm, "
                                        f"{VALUE_TOLERANCE_RAD:g} rad, or what the posture's conditioning explains; "
                                        f"{len(start)} regular postures of {len(t6)} poses)", judged=2 * len(start))


class CJacobian(OnRegularPairs, name="c jacobian", needs="compared poses"):
    poses = JACOBIAN_PAIRS

    def judge(self, context, t6, pairs):
        robot, library = context.robot, context.routine
        pose_index, posture, joints, _, wrenches, transmissions = pairs
        expected = jacobian(wrenches, transmissions)
        if robot.wrist is not None:
            expected = tool_jacobian(robot, t6[pose_index], solve(robot, t6[pose_index]).platform, joints, expected)
        units = np.array([1.0] * 3 + [1.0 / robot.size_mm] * 3)
        poses, worst, warned = matrix_from_t6(t6[pose_index]).reshape(-1, 16), 0.0, 0
        for number, (pose, k) in enumerate(zip(poses, posture)):
            rows, warning = library.jacobian(pose, int(k))
            warned += warning != WARNINGS["WARN_GOOD_SOLUTION"]
            with np.errstate(all="ignore"):
                relative = (np.max(np.abs(rows - expected[number]) * units, axis=1)
                            / np.max(np.abs(expected[number]) * units, axis=1))
            worst = max(worst, float(np.max(np.where(np.isfinite(relative), relative, np.inf))))
        passed = worst <= C_JACOBIAN_TOLERANCE and not warned
        where = (" (the legs' and the wrist's rates per tool twist)" if robot.wrist is not None
                 else " (the limbs' rows at the machine's pose)" if robot.task else "")
        return Check("c jacobian", passed, f"the library's Jacobian against kingen's{where} on {len(poses)} regular postures "
                                           f"of {len(t6)} poses: max relative difference {worst:.3g} (at most "
                                           f"{C_JACOBIAN_TOLERANCE:g}); {warned} answered another warning than good",
                     judged=len(poses))


class CDirectIndex(OnRegularPairs, name="c direct index", needs="compared poses"):
    poses = JACOBIAN_PAIRS

    def refusal(self, context):
        if context.robot.dof != 6:
            return f"the direct index is defined for six force lines; {context.robot.name} has {context.robot.dof} limbs"
        return None

    def judge(self, context, t6, pairs):
        robot, library = context.robot, context.routine
        pose_index, posture, _, _, wrenches, _ = pairs
        expected = direct_index(np.einsum("mdi,mdj->mij", wrenches, wrenches))
        found = np.array([library.direct_index(pose, int(k))[0] for pose, k in
                          zip(matrix_from_t6(t6[pose_index]).reshape(-1, 16), posture)])
        scale = np.maximum(expected, DIRECT_INDEX_FLOOR * robot.size_mm)
        worst = float(np.max(np.abs(found - expected) / scale))
        return Check(self.name, worst <= C_DIRECT_INDEX_TOLERANCE,
                     f"the library's direct index against kingen's (LAPACK's eigenvalue) on {len(found)} regular "
                     f"postures of {len(t6)} poses: max relative difference {worst:.3g} (at most "
                     f"{C_DIRECT_INDEX_TOLERANCE:g}; indices {float(expected.min()):.4g} to {float(expected.max()):.4g} mm)",
                     judged=len(found))


def constraint_statuses(radicand):
    """(statuses (n,), judged (n,) bool) the WARN_* code of each constraint radicand D (n,), as the
    library classifies it (unreachable below -SINGULAR_TOLERANCE or not a number, singular
    within it), and whether D lies farther than WARNING_BAND from both thresholds (where
    library and reference must agree)."""
    statuses = warning_codes(False, radicand <= SINGULAR_TOLERANCE, ~(radicand >= -SINGULAR_TOLERANCE))
    with np.errstate(invalid="ignore"):
        edge = np.minimum(np.abs(radicand - SINGULAR_TOLERANCE), np.abs(radicand + SINGULAR_TOLERANCE))
    return statuses, ~(edge <= WARNING_BAND)


class CMachinePose(VerifyCheck, name="c machine pose", needs="compared poses"):
    def run(self, context):
        robot, library, tally = context.robot, context.routine, context.tally
        if not has_machine_pose(robot):
            return [not_exercised(self.name, f"{robot.name} has no task coordinates" if not robot.task else
                                  f"{robot.name} has a wrist: its pose is the tool's")]
        t6 = np.concatenate([tally.first[0][:FORWARD_POSES]]
                            + ([tally.boundary_first[0]] if tally.boundary_first is not None else []))
        t6 = t6[np.all(np.isfinite(t6), axis=(1, 2))]
        found, statuses = library.machine_pose(matrix_from_t6(t6).reshape(-1, 16))
        expected = solve_parasitic(robot, t6)
        expected_statuses, judged = constraint_statuses(expected.radicand)
        wrong = judged & (statuses != expected_statuses)
        good = judged & (expected_statuses == WARNINGS["WARN_GOOD_SOLUTION"]) & ~wrong
        found_t6 = np.swapaxes(found.reshape(-1, 4, 4), 1, 2)[good]
        position = float(np.max(np.abs(found_t6[:, 3, :3] - expected.t6[good, 3, :3]), initial=0.0))
        rotation = float(np.max(np.abs(found_t6[:, :3, :3] - expected.t6[good, :3, :3]), initial=0.0))
        bound_mm = report_tolerance_mm(robot)
        passed = not np.any(wrong) and position <= bound_mm and rotation <= VALUE_TOLERANCE_RAD
        counts = ", ".join(f"{int(np.count_nonzero(expected_statuses[judged] == code))} {name[5:].lower().replace('_', ' ')}"
                           for name, code in WARNINGS.items() if code != WARNINGS["WARN_JOINT_LIMITS_EXCEEDED"])
        return [Check(self.name, passed,
                      f"the library's machine pose against kingen's (its parasitic coordinates in closed form) on "
                      f"{len(t6)} poses, {int(np.count_nonzero(expected.off))} of them off the manifold: statuses "
                      f"({counts}) {int(np.count_nonzero(wrong))} wrong, {int(np.count_nonzero(~judged))} within "
                      f"{WARNING_BAND:g} of a threshold not judged; on the good ones max difference {position:.3g} mm "
                      f"(at most {bound_mm:.3g}), {rotation:.3g} in the rotation (at most {VALUE_TOLERANCE_RAD:g})",
                      judged=int(np.count_nonzero(judged)))]


class CLoads(OnRegularPairs, name="c loads", needs="compared poses"):
    poses = JACOBIAN_PAIRS

    def refusal(self, context):
        if "static_loads" not in context.routine.functions:
            return f"the library does not export {context.routine.routine}_static_loads (optional)"
        return None

    def judge(self, context, t6, pairs):
        robot, library = context.robot, context.routine
        pose_index, posture, _, _, _, _ = pairs
        payload = checked_payload(robot)
        expected = loads(replace(without_parts(robot), payload=payload),  # the library holds the payload alone
                         t6[pose_index]).forces[np.arange(len(pose_index)), posture]
        given = [payload.mass, *payload.centre, *robot.gravity]
        worst, refused, compared = 0.0, 0, 0
        for number, (pose, k) in enumerate(zip(matrix_from_t6(t6[pose_index]).reshape(-1, 16), posture)):
            forces, returned = library.static_loads(pose, int(k), given)
            refused += returned < 0
            scale = np.max(np.abs(expected[number]))
            if returned >= 0 and np.isfinite(scale) and scale > 0:
                compared += 1
                worst = max(worst, float(np.max(np.abs(forces - expected[number])) / scale))
        if not compared and not refused:
            return not_exercised(self.name, f"kingen's loads hold no load on the {len(pose_index)} regular postures of "
                                            f"{len(t6)} poses: nothing compared")
        return Check(self.name, worst <= C_LOADS_TOLERANCE and not refused,
                     f"the library's static loads against kingen's holding {payload_words(robot)} on {compared} of "
                     f"{len(pose_index)} regular postures of {len(t6)} poses: max relative difference {worst:.3g} (at most "
                     f"{C_LOADS_TOLERANCE:g}); {refused} refused", judged=compared)


CHECKS = (Definition(), Values(), Warnings(), Closure(), Jacobian(), CJacobian(), CDirectIndex(), CLoads(), RoundTrip(),
          Forward(), CMachinePose(), Determinism(), Machine(), Golden(), Snapshot())
"""Every check a C host library gets, in report order."""
