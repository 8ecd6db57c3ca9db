"""``round trip``: forward kinematics from the routine's joints of regular postures returns
the sampled pose (:mod:`kingen.kinematics.forward`), within what the joints explain."""

import numpy as np

from ...conventions import joint_errors
from ...kinematics.forward import closure, free_mask, manifold_poses, newton, poses_of, scaled_closure_derivative, t6_of
from ...kinematics.reference import solve
from ...kinematics.routine import SINGULAR_TOLERANCE, VALUE_TOLERANCE_RAD, WARNINGS
from ...kinematics.singularity import posture_wrenches
from ...kinematics.hybrid.wrist import orientation_rows
from ...kinematics.hybrid.wrist_forward import tool_forward
from ..options import CONDITIONING_FACTOR, report_tolerance_mm
from ..tally import closure_miss
from ..report import not_exercised
from .base import Check, VerifyCheck
from .closure import CLOSURE_TOLERANCE
from .jacobian import JACOBIAN_MIN_RADICAND, JACOBIAN_MIN_TRANSMISSION

ROUND_TRIP_POSES = 1000
ROUND_TRIP_POSTURES = 4096
"""At most about this many regular (pose, posture) pairs of those poses go round: every one for
robots with few postures, a diagonal selection covering every posture for many (CEART: 64)."""
ROUND_TRIP_MIN_CONDITIONING = 1e-4
"""Postures whose closure derivative with respect to the free pose coordinates (rotations per
mm of arc at the robot's size) has a smallest singular value below this are near a
singularity: their pose is not determined by the joints (pose_conditioning)."""
def round_trip_check(robot, plugin, options, t6):
    """Forward kinematics seeded at each sampled pose, from the routine's joints of its
    regular postures (about ROUND_TRIP_POSTURES in all), must return that pose: within the
    value bound (mm) and 1e-9 rad, or within what the joints explain through the posture's
    conditioning (pose_conditioning): their closure residual at that pose, as far as the
    closure check accepts it (CLOSURE_TOLERANCE), plus rounding (CONDITIONING_FACTOR x
    size), over the conditioning. Joints a few units in the last place from the reference's
    thus go round as well as its own; joints the closure check refuses do not."""
    if not robot.has_forward:
        return not_exercised("round trip", f"forward kinematics needs free pose coordinates for a "
                                         f"robot with {robot.dof} limbs (forward: {{free: [...]}})")
    calibrated = robot.calibrated(options.link_lengths, options.link_offsets)
    expected = solve(robot, t6, options.link_lengths, options.link_offsets)
    plugin.reset_host()
    joints = plugin.call(t6, options.link_lengths, options.link_offsets).solutions
    if robot.wrist is not None:
        return wrist_round_trip(calibrated, options, t6, expected, joints)
    wrenches, transmissions = posture_wrenches(calibrated, expected.points, joints)
    candidates = regular_postures(expected, transmissions)
    # About ROUND_TRIP_POSTURES of them, along diagonals of (pose, posture), so that every posture takes part.
    stride = max(1, -(-int(np.count_nonzero(candidates)) // ROUND_TRIP_POSTURES))
    pose_number, posture_number = np.indices(candidates.shape)
    pose_index, posture = np.nonzero(candidates & ((pose_number + posture_number) % stride == 0))
    start = poses_of(t6)[pose_index]
    free = free_mask(calibrated)
    conditioning = pose_conditioning(robot, wrenches[pose_index, posture], start, free)
    regular = conditioning > ROUND_TRIP_MIN_CONDITIONING
    pose_index, posture, conditioning, start = (kept[regular] for kept in (pose_index, posture, conditioning, start))
    if not len(pose_index):
        return not_exercised("round trip", f"no regular posture among the {len(t6)} sampled poses to go round")
    routine_joints = joints[pose_index, :, posture]
    residual = np.zeros(len(pose_index))  # the joints' closure residual, as far as the closure check accepts it
    for index, limb in enumerate(calibrated.limbs):
        miss, length = closure_miss(limb, expected.points[pose_index, index], routine_joints[:, index])
        residual = np.fmax(residual, np.fmin(miss, CLOSURE_TOLERANCE * length))
    found, _ = newton(calibrated, start, routine_joints, free)
    position = np.max(np.abs(found[:, :3] - start[:, :3]), axis=1)
    rotation = np.max(np.abs(t6_of(found)[:, :3, :3] - t6_of(start)[:, :3, :3]), axis=(1, 2))
    explained_mm = 2.0 * (np.sqrt(robot.dof) * residual + CONDITIONING_FACTOR * robot.size_mm) / conditioning
    allowed_mm = np.maximum(report_tolerance_mm(robot), explained_mm)
    allowed_rad = np.maximum(VALUE_TOLERANCE_RAD, explained_mm / robot.size_mm)
    passed = bool(np.all(position <= allowed_mm) and np.all(rotation <= allowed_rad))
    worst_mm, worst_rad = float(np.max(position)), float(np.max(rotation))
    return Check("round trip", passed, judged=len(pose_index), detail=
                 f"forward kinematics from the routine's joints of {len(pose_index)} regular postures of {len(t6)} "
                 f"poses returns each pose within {worst_mm:.3g} mm and {worst_rad:.3g} rad (bounds "
                 f"{report_tolerance_mm(robot):.3g} mm, {VALUE_TOLERANCE_RAD:g} rad, or what the joints' closure "
                 f"residual and rounding explain through the posture's conditioning; postures near a singularity, "
                 f"where the pose is ill-conditioned, are left out)")


def wrist_round_trip(robot, options, t6, expected, joints):
    """``round trip`` of a machine with a wrist (``robot`` calibrated): from the routine's
    ``joints`` (n, joint_count, postures) of every regular posture (regular_postures, the
    parallel part's conditioning above ROUND_TRIP_MIN_CONDITIONING),
    the machine's forward (kingen.kinematics.hybrid.wrist_forward: the parallel part's Newton seeded at
    the reference's platform pose, then the wrist) gives a tool T6 whose tip and axis (with
    three wrist joints: whole frame) must be the sampled one's, and the reference's inverse of that T6 must give the joints back in the
    same posture: within the value bounds (mm, rad)."""
    parallel = robot.parallel
    wrenches, transmissions = posture_wrenches(robot, expected.points, joints)
    pose_index, posture = np.nonzero(regular_postures(expected, transmissions))
    near = poses_of(expected.platform)[pose_index]
    conditioning = pose_conditioning(parallel, wrenches[pose_index, posture], near, free_mask(parallel))
    regular = conditioning > ROUND_TRIP_MIN_CONDITIONING
    pose_index, posture, near = pose_index[regular], posture[regular], near[regular]
    if not len(pose_index):
        return not_exercised("round trip", f"no regular posture among the {len(t6)} sampled poses to go round")
    routine_joints = joints[pose_index, :, posture]
    tool, _, _ = tool_forward(robot, routine_joints, near)
    asked = t6[pose_index]
    rows = list(orientation_rows(robot.wrist))
    tip = float(np.max(np.abs(tool[:, 3, :3] - asked[:, 3, :3])))
    axis = float(np.max(np.abs(tool[:, rows, :3] - asked[:, rows, :3])))
    back = solve(robot, tool, options.link_lengths, options.link_offsets).joints[np.arange(len(pose_index)), :, posture]
    error = joint_errors(back[:, :, None], routine_joints[:, :, None], robot.revolute)[:, :, 0]
    worst_mm = float(np.max(error[:, ~robot.revolute], initial=0.0))
    worst_rad = float(np.max(error[:, robot.revolute], initial=0.0))
    bound_mm = report_tolerance_mm(robot)
    detail = (f"the machine's forward (the parallel part's Newton, then the wrist) from the routine's joints of "
              f"{len(pose_index)} regular postures of {len(t6)} poses gives each asked tool tip within {tip:.3g} mm "
              f"and {'tool frame' if robot.wrist.whole_pose else 'tool axis'} within {axis:.3g}, and the inverse of that tool pose the joints back within "
              f"{worst_mm:.3g} mm and {worst_rad:.3g} rad (bounds {bound_mm:.3g} mm, {VALUE_TOLERANCE_RAD:g} rad; "
              f"postures near a singularity are left out)")
    passed = max(tip, worst_mm) <= bound_mm and max(axis, worst_rad) <= VALUE_TOLERANCE_RAD
    return Check("round trip", passed, detail, judged=len(pose_index))


def regular_postures(expected, transmissions):
    """(n, postures) the postures the reference reaches without warning, every radicand above
    JACOBIAN_MIN_RADICAND and every limb's transmission (n, postures, dof) above JACOBIAN_MIN_TRANSMISSION."""
    return ((expected.warnings == WARNINGS["WARN_GOOD_SOLUTION"])
            & np.all(np.abs(transmissions) > JACOBIAN_MIN_TRANSMISSION, axis=2)
            & np.all(expected.radicands > JACOBIAN_MIN_RADICAND, axis=1)[:, None])


def pose_conditioning(robot, wrenches, poses, free):
    """The smallest singular value (m,) of the closure's derivative with respect to the free
    pose coordinates (what forward kinematics solves for) at poses (m, 6) (mm, radians):
    forward.scaled_closure_derivative of the limbs' unit wrenches (m, dof, 6), the matrix Newton
    solves with, rotations per mm of arc at the robot's size. Dimensionless (mm of closure per mm of pose); 0 at a singularity and
    where the free coordinates are not all determined; non-finite counts as 0."""
    with np.errstate(all="ignore"):  # a constrained machine's joints move along its manifold
        matrix = scaled_closure_derivative(robot, wrenches, poses, free)
    finite = np.all(np.isfinite(matrix), axis=(1, 2))
    matrix = np.where(finite[:, None, None], matrix, 0.0)
    return np.where(finite, np.linalg.svd(matrix, compute_uv=False)[:, -1], 0.0)


class RoundTrip(VerifyCheck, name="round trip", needs="compared poses"):
    def run(self, context):
        t6 = context.tally.first[0]
        return [round_trip_check(context.robot, context.routine, context.options, t6[:ROUND_TRIP_POSES])]


FORWARD_SEEDS = {"a servo cycle away": (0.01, 0.01), "far away": (10.0, 5.0)}
"""Where a host's own forward kinematics is started from, by label: mm along a random direction
of x y z and degrees along a random direction of roll pitch yaw (the free coordinates only)."""
FAR_AT_MOST = 0.01
"""A seed "far away" is at most this fraction of the machine's size away (10 mm is a third of a
machine 30 mm across, where another assembly mode may lie nearer than the pose)."""


NEWTON_ASSURED = 0.5
"""Kantorovich's bound: Newton's method started where h = beta eta L is at most this converges
to the root within 2 eta of the start, the only one that near (newton_assured)."""


def newton_assured(robot, seeds, poses, joints, free):
    """(n,) bool: whether Newton's method on the closure equations of ``joints`` (n, dof; mm,
    radians), started at ``seeds`` (n, 6; mm, radians; a machine with task coordinates: its pose
    for their task coordinates), is assured to converge to ``poses`` (n, 6), the reference's
    poses for these joints, by Kantorovich's condition h = beta eta L <= NEWTON_ASSURED: beta
    1 / the smallest singular value of the closure's derivative at the seed (over the free
    coordinates, angles in mm of arc at the robot's size: scaled_closure_derivative), eta the
    length of Newton's first step, L the derivative's change per unit of that length between
    the seed and the pose (a secant's estimate of its Lipschitz constant). Its iterates then stay
    within 2 eta of the seed; every limb's radicand must stay above the singular band
    (SINGULAR_TOLERANCE) there too, as it changes between the seed and the pose, since a host's
    Newton stops at an iterate inside it. Near a singularity a start a servo cycle away may lie
    beyond either (h of 5 on a machine 36 mm across): there Newton may stop or jump to another
    assembly mode without a fault of its own. A seed or pose where the derivative is not finite
    or singular is not assured."""
    seeds = manifold_poses(robot, np.asarray(seeds, dtype=float))
    with np.errstate(all="ignore"):
        residual, seed_wrenches = closure(robot, seeds, joints)
        _, pose_wrenches = closure(robot, poses, joints)
        at_seed = scaled_closure_derivative(robot, seed_wrenches, seeds, free)
        at_pose = scaled_closure_derivative(robot, pose_wrenches, poses, free)
        finite = np.all(np.isfinite(at_seed), axis=(1, 2)) & np.all(np.isfinite(at_pose), axis=(1, 2))
        finite &= np.all(np.isfinite(residual), axis=1)
        at_seed = np.where(finite[:, None, None], at_seed, np.eye(*at_seed.shape[1:]))
        at_pose = np.where(finite[:, None, None], at_pose, 0.0)
        units = np.array([1.0] * 3 + [robot.size_mm] * 3)[free]
        apart = np.linalg.norm((seeds - poses)[:, free] * units, axis=1)
        values = np.linalg.svd(at_seed, compute_uv=False)
        residual = np.where(finite[:, None], residual, 0.0)
        step = np.linalg.norm(np.linalg.pinv(at_seed) @ residual[..., None], axis=(1, 2))
        change = np.linalg.norm(at_seed - at_pose, ord=2, axis=(1, 2)) / apart
        assured = step * change / values[:, -1] <= NEWTON_ASSURED
        seed_radicands = solve(robot, t6_of(seeds)).radicands
        slope = np.abs(seed_radicands - solve(robot, t6_of(poses)).radicands) / apart[:, None]
        lowest = np.where(np.isfinite(seed_radicands), seed_radicands - slope * 2.0 * step[:, None], np.inf)
        assured &= np.all(lowest > SINGULAR_TOLERANCE, axis=1)
    return finite & (values[:, -1] > 0.0) & np.where(apart > 0.0, assured, True)


def forward_seeds(robot):
    """FORWARD_SEEDS for ``robot``: the far seeds' distance at most FAR_AT_MOST of its size (mm)."""
    return {label: (min(distance_mm, FAR_AT_MOST * robot.size_mm) if distance_mm > 1.0 else distance_mm, distance_deg)
            for label, (distance_mm, distance_deg) in FORWARD_SEEDS.items()}


def seed_offsets(generator, count, distance_mm, distance_deg, free):
    """(count, 6) offsets of the start from each pose: ``distance_mm`` along a random unit
    direction of x y z, then ``distance_deg`` (degrees) along one of roll pitch yaw, both drawn
    from ``generator`` in that order; 0 for the coordinates ``free`` (6,) leaves fixed."""
    offset = np.concatenate([_unit_directions(generator, count) * distance_mm,
                             _unit_directions(generator, count) * distance_deg], axis=1)
    offset[:, ~free] = 0.0
    return offset


def _unit_directions(generator, count):
    """``count`` random unit 3-vectors."""
    direction = generator.normal(size=(count, 3))
    return direction / np.linalg.norm(direction, axis=1, keepdims=True)

