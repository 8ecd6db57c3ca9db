"""``forward``: kinematicsForward, given the joints of a sampled pose and started a servo cycle
away (0.01 mm, 0.01 degree) and far away (10 mm, 5 degrees), returns the sampled pose within
the value bounds, or fails; it never returns another pose (another assembly mode). Judged on
the regular poses of the sample (a servo cycle's failure only from a seed where the reference is
regular too and Newton's convergence is assured: kingen.verify.checks.round_trip.newton_assured)
(as the round trip: away from singularities, where the pose
is not determined by the joints); the report gives the failure rates and Newton's iterations,
and what the first call after loading returned (LinuxCNC's switchable modules start it from
the all-zero pose: on a mm machine genhexkins' max-error, sized for inches, stops it)."""

import numpy as np

from ....conventions import pose_from_t6, t6_from_pose
from ....kinematics.forward import free_mask
from ....kinematics.reference import solve
from ....kinematics.routine import VALUE_TOLERANCE_RAD, WARNINGS
from ....kinematics.singularity import posture_wrenches
from ....verify.report import not_exercised
from ....verify.checks.base import Check, VerifyCheck
from ....verify.checks.round_trip import (ROUND_TRIP_MIN_CONDITIONING, forward_seeds, newton_assured, pose_conditioning,
                                          seed_offsets)
from ....verify.options import value_tolerance_mm

FORWARD_POSES = 1000


def regular_mask(robot, poses):
    """(n,) which poses (n, 6) (mm, degrees) are reachable and regular at the robot's one
    posture (a one-posture view, no wrist), and the reference's joints (n, dof) mm and radians."""
    expected = solve(robot, t6_from_pose(poses))
    good = expected.warnings[:, 0] == WARNINGS["WARN_GOOD_SOLUTION"]
    joints = expected.joints[:, :, 0]
    if not np.any(good):
        return good, joints
    wrenches, _ = posture_wrenches(robot, expected.points[good], expected.joints[good])
    start = np.concatenate([poses[good, :3], np.radians(poses[good, 3:])], axis=1)
    good[good] = pose_conditioning(robot, wrenches[:, 0], start, free_mask(robot)) > ROUND_TRIP_MIN_CONDITIONING
    return good, joints


def regular_poses(robot, poses):
    """The poses (m, 6) (mm, degrees) of ``poses`` that are reachable and regular at the
    robot's one posture (a one-posture view), with their reference joints (m, dof), mm and radians."""
    regular, joints = regular_mask(robot, poses)
    return poses[regular], joints[regular]


class Forward(VerifyCheck, name="forward", needs="compared poses"):
    def run(self, context):
        robot, module = context.robot, context.routine
        poses = pose_from_t6(context.tally.first[0][:FORWARD_POSES])
        poses, joints = regular_poses(robot, poses)
        if not len(poses):
            return [not_exercised("forward", "no regular, reachable pose among the sampled ones (the working "
                                             "posture is never regular in the verification region)")]
        free = free_mask(robot)
        machine_joints = np.full((len(poses), 16), 0.0)
        machine_joints[:, :robot.dof] = joints / module.joint_scale()
        bound_mm, bound_deg = value_tolerance_mm(robot), np.degrees(VALUE_TOLERANCE_RAD)
        generator = np.random.default_rng(context.options.seed)
        passed, parts, failed_codes = True, [], set()
        for label, (distance_mm, distance_deg) in forward_seeds(robot).items():
            offset = seed_offsets(generator, len(poses), distance_mm, distance_deg, free)
            seeds = np.zeros((len(poses), 9))
            seeds[:, :3] = (poses[:, :3] + offset[:, :3]) / module.scale
            seeds[:, 3:6] = poses[:, 3:] + offset[:, 3:]
            found, returns, iterations = module.forward(machine_joints, seeds)
            position = np.max(np.abs(found[:, :3] * module.scale - poses[:, :3]), axis=1)
            angle = np.max(np.abs(found[:, 3:6] - poses[:, 3:]), axis=1) if np.any(free[3:]) else np.zeros(len(poses))
            converged = returns == 0
            right = converged & (position <= bound_mm) & (angle <= bound_deg)
            wrong = converged & ~right
            failed = ~converged
            # A seed where the reference is not regular (a limb within its singular band, or out of
            # reach: the module's closure refuses it), or one Newton's convergence from is not
            # assured, is no premise for a servo cycle's failure.
            seeded = np.concatenate([seeds[:, :3] * module.scale, seeds[:, 3:6]], axis=1)
            premise = solve(robot, t6_from_pose(seeded)).warnings[:, 0] == WARNINGS["WARN_GOOD_SOLUTION"]
            radians = np.concatenate([poses[:, :3], np.radians(poses[:, 3:])], axis=1)
            premise &= newton_assured(robot, np.concatenate([seeded[:, :3], np.radians(seeded[:, 3:])], axis=1),
                                      radians, joints, free)
            unjudged = (f"; {np.count_nonzero(failed & ~premise)} from a seed the reference finds singular or out "
                        "of reach, or Newton is not assured to converge from, not judged"
                        if np.any(failed & ~premise) else "")
            failed_codes.update(int(code) for code in returns[failed])
            counted = iterations[converged & np.isfinite(iterations)]
            statistics = (f"iterations mean {counted.mean():.2f}, max {int(counted.max())}" if len(counted)
                          else "no iteration count (no pin <module>.iterations)" if np.any(converged) else "")
            parts.append(f"{label}: {int(np.count_nonzero(right))} of {len(poses)} returned the pose, "
                         f"{int(np.count_nonzero(failed))} failed ({codes_text(returns[failed])}{unjudged}), "
                         f"{int(np.count_nonzero(wrong))} returned another pose"
                         f"{f' (up to {float(np.max(position[wrong])):.3g} mm away)' if np.any(wrong) else ''}"
                         f"{'; ' + statistics if statistics else ''}")
            passed = passed and not np.any(wrong) and (label != "a servo cycle away" or not np.any(failed & premise))
        if module.first_forward is not None:
            parts.insert(0, f"the first call after loading (a switchable module starts it from the all-zero "
                            f"pose, not the one passed in; not judged) returned {module.first_forward}")
            if module.first_forward != 0:
                failed_codes.add(module.first_forward)
        detail = (f"{'; '.join(parts)} (bounds {bound_mm:.3g} mm, {bound_deg:.3g} degrees; "
                  f"{len(poses)} regular poses of the sample)")
        return [Check("forward", passed, detail, _diagnoses(module, failed_codes), judged=2 * len(poses))]


def _diagnoses(module, codes):
    """What a module's failures point at: genhexkins' max-error, sized for inch machines."""
    limit = module.parameter(f"{module.routine}.max-error")
    if limit is None or -2 not in codes:
        return []
    unit = "inch" if module.scale != 1.0 else "mm"
    return [f"{module.routine}.max-error is {limit:g} {unit}: the forward gives up (-2) once the joints' error "
            f"exceeds it, a bound sized for inch machines; on a mm machine set it about 25.4 times larger "
            f"(setp {module.routine}.max-error {limit * 25.4:g})" if unit == "mm" else
            f"{module.routine}.max-error is {limit:g} {unit}: the forward gives up (-2) once the joints' error exceeds it"]


def codes_text(returns):
    values, counts = np.unique(returns, return_counts=True)
    return ", ".join(f"{count} x {value}" for value, count in zip(values, counts)) or "none"
