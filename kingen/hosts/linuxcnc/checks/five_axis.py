"""``forward``, for a five-axis module (a robot with a wrist): kinematicsForward, given the
reference's joints of a sampled tool pose and started a servo cycle away (0.01 mm, 0.01 degree
in A and C) and far away (10 mm, 5 degrees), returns the tool tip within the value bound and
the tool axis within the angle bound (A, C compared through the axis they give: an axis has two
pairs), or fails; a six-axis module (a three-axis wrist) is started off in A, B and C and judged
on the whole tool frame (the angle of the rotation between the asked and the returned); then kinematicsInverse of what it returned gives the joints back within the
value bounds (forward then inverse). Judged on the sampled poses whose reference posture is
good and whose platform pose is regular for the parallel part (as the round trip)."""

import numpy as np

from ....conventions import pose_from_t6, t6_from_pose
from ....kinematics.reference import solve
from ....kinematics.routine import VALUE_TOLERANCE_RAD
from ....verify.checks.base import Check, VerifyCheck
from ....verify.checks.round_trip import forward_seeds
from ....verify.options import value_tolerance_mm
from ....verify.report import not_exercised
from ..five_axis import axis_of_world, home_axis
from .forward import FORWARD_POSES, codes_text, regular_mask


def _regular(robot, t6):
    """(n,) which tool T6 (n, 4, 4) have a good reference posture and a regular platform pose,
    and the reference's joints (n, joint_count) mm and radians."""
    expected = solve(robot, t6)
    regular, _ = regular_mask(robot.parallel, pose_from_t6(expected.platform))
    return regular & (expected.warnings[:, 0] == 0), expected.joints[:, :, 0]


def _seeds(generator, world, distance_mm, distance_deg, scale, angles):
    """The worlds (n, 9) started from: ``distance_mm`` along a random direction of X Y Z and
    ``distance_deg`` along one of the world's ``angles`` (indices: A C, or A B C)."""
    directions = generator.normal(size=(len(world), 3 + len(angles)))
    directions[:, :3] /= np.linalg.norm(directions[:, :3], axis=1)[:, None]
    directions[:, 3:] /= np.linalg.norm(directions[:, 3:], axis=1)[:, None]
    seeds = world.copy()
    seeds[:, :3] += directions[:, :3] * distance_mm / scale
    seeds[:, list(angles)] += directions[:, 3:] * distance_deg
    return seeds


def _turn(robot, w0, found, t6):
    """(n,) rad: how far the world ``found`` (n, 9) is turned from the tool T6 ``t6`` (n, 4, 4):
    the angle between the tool axes (a two-axis wrist), or of the rotation between the tool
    frames (a three-axis wrist, the whole pose read)."""
    if not robot.wrist.whole_pose:
        axis = axis_of_world(w0, found[:, 3], found[:, 5])
        return np.arctan2(np.linalg.norm(np.cross(axis, t6[:, 2, :3]), axis=1), np.sum(axis * t6[:, 2, :3], axis=1))
    frames = t6_from_pose(np.concatenate([np.zeros((len(found), 3)), found[:, 3:6]], axis=1))[:, :3, :3]
    between = np.einsum("nij,nkj->nik", frames, t6[:, :3, :3])
    skew = np.stack([between[:, 1, 2] - between[:, 2, 1], between[:, 2, 0] - between[:, 0, 2],
                     between[:, 0, 1] - between[:, 1, 0]], -1)
    return np.arctan2(np.linalg.norm(skew, axis=1) / 2.0, (np.trace(between, axis1=1, axis2=2) - 1.0) / 2.0)


class FiveAxisForward(VerifyCheck, name="forward", needs="compared poses"):
    def run(self, context):
        robot, module = context.robot, context.routine
        t6 = context.tally.first[0][:FORWARD_POSES]
        regular, joints = _regular(robot, t6)
        if not np.any(regular):
            return [not_exercised("forward", "no sampled pose with a good posture and a regular platform pose")]
        t6, joints = t6[regular], joints[regular]
        world, w0 = module.emc_poses(t6), home_axis(robot)
        machine_joints = np.zeros((len(t6), 16))
        machine_joints[:, :robot.joint_count] = joints / module.joint_scale()
        bound_mm, bound_rad = value_tolerance_mm(robot), VALUE_TOLERANCE_RAD
        generator = np.random.default_rng(context.options.seed)
        passed, parts, worst = True, [], [0.0, 0.0, 0.0, 0.0]
        angles, what = ((3, 4, 5), "tool frame") if robot.wrist.whole_pose else ((3, 5), "tool axis")
        for label, (distance_mm, distance_deg) in forward_seeds(robot).items():
            found, returns, iterations = module.forward(machine_joints, _seeds(generator, world, distance_mm,
                                                                               distance_deg, module.scale, angles))
            converged = returns == 0
            tip = np.max(np.abs(found[:, :3] * module.scale - t6[:, 3, :3]), axis=1)
            turn = _turn(robot, w0, found, t6)
            back, back_returns, _ = module.inverse(found)
            error = (back[:, :robot.joint_count] - machine_joints[:, :robot.joint_count]) * module.joint_scale()
            error = np.where(robot.revolute, np.angle(np.exp(1j * np.nan_to_num(error))), error)
            length = np.max(np.where(robot.revolute, 0.0, np.abs(error)), axis=1)
            angle = np.max(np.where(robot.revolute, np.abs(error), 0.0), axis=1)
            right = converged & (tip <= bound_mm) & (turn <= bound_rad)
            inverted = right & (back_returns == 0) & (length <= bound_mm) & (angle <= bound_rad)
            wrong = converged & ~right
            for index, values in enumerate((tip, turn, length, angle)):
                if np.any(right):
                    worst[index] = max(worst[index], float(np.max(values[right])))
            counted = iterations[converged & np.isfinite(iterations)]
            parts.append(f"{label}: {int(np.count_nonzero(right))} of {len(t6)} returned the tool tip and {what.split()[1]}, "
                         f"{int(np.count_nonzero(~converged))} failed ({codes_text(returns[~converged])}), "
                         f"{int(np.count_nonzero(wrong))} returned another pose; the inverse of those returned "
                         f"gave the joints back for {int(np.count_nonzero(inverted))}"
                         f"{f'; iterations mean {counted.mean():.2f}, max {int(counted.max())}' if len(counted) else ''}")
            passed = (passed and not np.any(wrong) and np.count_nonzero(inverted) == np.count_nonzero(right)
                      and (label != "a servo cycle away" or np.all(converged)))
        detail = (f"{'; '.join(parts)}; worst tool tip {worst[0]:.3g} mm, {what} {worst[1]:.3g} rad, joints back "
                  f"{worst[2]:.3g} mm, {worst[3]:.3g} rad (bounds {bound_mm:.3g} mm, {bound_rad:.3g} rad; "
                  f"{len(t6)} poses of the sample with a good posture and a regular platform pose)")
        return [Check("forward", passed, detail, judged=2 * len(t6))]
