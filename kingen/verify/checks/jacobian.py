"""``jacobian``: finite differences of the routine's own joints against the analytic Jacobian
of the limbs' constraint geometry (:mod:`kingen.kinematics.singularity`), on regular postures."""

import numpy as np

from ...conventions import joint_errors
from ...kinematics.hybrid.parasitic import task_rows, task_twists
from ...kinematics.reference import solve
from ...kinematics.routine import VALUE_TOLERANCE_RAD, WARNINGS
from ...kinematics.singularity import finite_difference_jacobian, jacobian, posture_wrenches
from ...kinematics.hybrid.wrist import rotation_about
from ...kinematics.forward import poses_of
from ...kinematics.hybrid.wrist_forward import tool_rates
from ...runtime.text import counted
from ..options import report_tolerance_mm
from ..report import not_exercised
from .base import Check, VerifyCheck

JACOBIAN_POSES = 200
JACOBIAN_STEP = 1e-6
"""Central-difference steps: this fraction of the robot's size (mm), and this many radians:
small enough for the curvature near (not in) a singular band, large against rounding."""
JACOBIAN_TOLERANCE = 1e-6
"""Relative to the largest entry of the joint's Jacobian row (rotations weighed as mm of arc
at the robot's size); Richardson-extrapolated central differences with these steps agree
with the analytic Jacobian to about 1e-9 on every shipped robot."""
JACOBIAN_MIN_TRANSMISSION = 0.05
JACOBIAN_MIN_RADICAND = 1e-3
"""Only regular postures are compared: away from limb singularities, where differences
of an ill-conditioned joint would measure the conditioning, not the formula."""


IRREGULAR_WORDS = (("WARN_UNREACHABLE", "unreachable"), ("WARN_SINGULAR_SOLUTION", "singular"),
                   ("WARN_JOINT_LIMITS_EXCEEDED", "beyond travel"),
                   ("WARN_GOOD_SOLUTION", "near a limb singularity"))
"""Why a posture is not differentiated, by the reference's warning (a good one: ill-conditioned)."""


def irregular_reasons(warnings):
    """Why no posture of the reference's ``warnings`` (n, postures) was differentiated: their
    count per warning, in words ('2006 beyond travel, 6 near a limb singularity')."""
    counts = [(int(np.count_nonzero(warnings == WARNINGS[name])), words) for name, words in IRREGULAR_WORDS]
    return ", ".join(f"{count} {words}" for count, words in counts if count)


def jacobian_check(robot, plugin, options, t6):
    """Finite differences of the routine's own joints along the six unit twists, against
    the analytic Jacobian of the limbs' constraint geometry (kingen.kinematics.singularity), on the
    reachable, regular postures of ``t6``: catches a formula mistake the routine and the
    reference share."""
    calibrated = robot.calibrated(options.link_lengths, options.link_offsets)
    expected = solve(robot, t6, options.link_lengths, options.link_offsets)
    plugin.reset_host()
    center = plugin.call(t6, options.link_lengths, options.link_offsets).solutions
    wrenches, transmissions = posture_wrenches(calibrated, expected.points, center)
    if robot.wrist is not None:  # the forward map's rates, inverted (the tool's driven directions)
        transmissions = np.concatenate([transmissions, np.ones(transmissions.shape[:2] + (robot.joint_count - robot.dof,))],
                                       axis=2)
    regular = ((expected.warnings == WARNINGS["WARN_GOOD_SOLUTION"])[:, None, :]
               & (np.abs(np.swapaxes(transmissions, 1, 2)) > JACOBIAN_MIN_TRANSMISSION)
               & np.all(expected.radicands > JACOBIAN_MIN_RADICAND, axis=1)[:, None, None])
    if robot.wrist is not None:
        analytic = wrist_rates(calibrated, expected, center, np.any(regular, axis=1))
    else:
        analytic = np.swapaxes(jacobian(wrenches, transmissions), 1, 2)
    if robot.task:  # a constrained machine answers a twist with its task coordinates' motion on its manifold
        on_manifold = task_twists(calibrated, t6) @ task_rows(t6, robot.task)
        analytic = np.einsum("npkj,nji->npki", analytic, on_manifold)
        regular &= np.all(np.isfinite(on_manifold), axis=(1, 2))[:, None, None]  # no tangent: nothing to compare

    def joints_of(moved):
        plugin.reset_host()
        return plugin.call(moved, options.link_lengths, options.link_offsets).solutions

    # Richardson's extrapolation of central differences at h and h/2: truncation error O(h^4).
    coarse, fine = (finite_difference_jacobian(joints_of, t6, JACOBIAN_STEP * robot.size_mm / halving,
                                               JACOBIAN_STEP / halving, robot.revolute) for halving in (1, 2))
    numeric = (4.0 * fine - coarse) / 3.0
    # Rotations in mm of arc at the robot's size, so that all six twists weigh alike; only the
    # pose coordinates the routine answers to (a translating platform's controller ignores rotations).
    units = np.array([1.0] * 3 + [1.0 / robot.size_mm] * 3) * np.asarray(getattr(plugin, "pose_coordinates", True))
    with np.errstate(all="ignore"):
        relative = (np.max(np.abs(numeric - analytic) * units, axis=-1)
                    / np.max(np.abs(analytic) * units, axis=-1))
    relative = np.where(regular, np.where(np.isfinite(relative), relative, np.inf), 0.0)
    worst, compared = float(relative.max(initial=0.0)), int(np.count_nonzero(regular))
    if not compared:
        return not_exercised("jacobian", f"no reachable, regular joint-posture among the {counted(len(t6), 'pose')} "
                                         f"to differentiate: of their {counted(expected.warnings.size, 'posture')}, "
                                         f"{irregular_reasons(expected.warnings)}")
    passed = worst <= JACOBIAN_TOLERANCE
    against = ("the inverted central differences of the machine's forward (legs by Newton, then the wrist)"
               if robot.wrist is not None else "the analytic Jacobian")
    detail = (f"finite differences of the routine's joints against {against} on {compared} "
              f"regular joint-postures of {len(t6)} poses: max relative difference {worst:.3g} "
              f"(at most {JACOBIAN_TOLERANCE:g})")
    if robot.wrist is not None and not robot.wrist.whole_pose:  # a three-axis wrist reads the turn too
        reached = expected.warnings != WARNINGS["WARN_UNREACHABLE"]
        moved_mm, moved_rad = turn_change(robot, joints_of, t6, center, reached)
        bound_mm = report_tolerance_mm(robot)
        passed = passed and moved_mm <= bound_mm and moved_rad <= VALUE_TOLERANCE_RAD
        detail += (f"; turning the tool {TURN_RAD:g} rad about its axis changes no joint: at most {moved_mm:.3g} mm "
                   f"(at most {bound_mm:g}) and {moved_rad:.3g} rad (at most {VALUE_TOLERANCE_RAD:g})")
    return Check("jacobian", passed, detail, judged=compared)


TURN_RAD = 0.5
"""A machine with a two-axis wrist: the sampled tool frames are also turned by this about the tool axis."""


def wrist_rates(robot, expected, joints, wanted):
    """(n, joint_count, postures, 6) the joint rates per tool twist of ``robot`` (with a wrist)
    at each posture's ``joints`` (n, joint_count, postures), the platform near the reference's
    (kingen.kinematics.hybrid.wrist_forward.tool_rates), where ``wanted`` (n, postures); NaN elsewhere
    and where that posture has no finite joints."""
    count, total, postures = joints.shape
    near = poses_of(expected.platform)
    usable = np.all(np.isfinite(joints), axis=1) & wanted
    rates = np.full((count, total, postures, 6), np.nan)
    for posture in range(postures):
        rows = usable[:, posture]
        if np.any(rows):
            rates[rows, :, posture] = tool_rates(robot, joints[rows, :, posture], near[rows],
                                                 WRIST_STEP * robot.size_mm, WRIST_STEP)
    return rates


WRIST_STEP = 1e-5
"""The forward map's central-difference steps: this fraction of the robot's size (mm, legs)
and this many radians (wrist): large against Newton's convergence (1e-13 of the size)."""


def turn_change(robot, joints_of, t6, joints, reached):
    """(mm, rad) the largest change of the routine's prismatic and revolute joints of postures
    the reference reaches (``reached`` (n, postures)) when each tool T6 turns TURN_RAD about its
    own tool axis: a five-axis reading ignores that turn."""
    turned = np.array(t6, dtype=float)
    rotation = rotation_about(np.array([0.0, 0.0, 1.0]), np.full(len(t6), TURN_RAD))
    turned[:, :3, :3] = np.swapaxes(rotation, 1, 2) @ turned[:, :3, :3]  # rows n, o turn about a
    change = np.where(reached[:, None, :], joint_errors(joints_of(turned), joints, robot.revolute), 0.0)
    return tuple(float(np.max(change[:, robot.revolute == revolute], initial=0.0)) for revolute in (False, True))


class Jacobian(VerifyCheck, name="jacobian", needs="compared poses", item="jacobian"):
    def run(self, context):
        t6 = context.tally.first[0]
        return [jacobian_check(context.robot, context.routine, context.options, t6[:JACOBIAN_POSES])]
