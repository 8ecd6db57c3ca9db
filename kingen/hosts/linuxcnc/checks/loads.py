"""``hal loads``: the pins load.N a module writes in each kinematicsInverse (a wrist's joints after the legs)
against kingen's static loads (:func:`kingen.kinematics.loads.loads`, at rest) at the regular
poses of the sample, holding the robot file's payload (or a stand-in,
kingen.hosts.loads.checked_payload) set through the module's payload parameters: within
LOAD_TOLERANCE of the pose's largest load. Not exercised for a module without the pins (a
stock module, a hand-written one)."""

from dataclasses import replace

import numpy as np

from ....conventions import pose_from_t6, t6_from_pose
from ....kinematics.loads import loads
from ....kinematics.reference import solve
from ....kinematics.routine import WARNINGS
from ....verify.checks.base import Check, VerifyCheck
from ....verify.report import not_exercised
from ...loads import checked_payload, payload_words
from .forward import regular_poses

LOAD_POSES = 300
LOAD_TOLERANCE = 1e-9
"""Relative to the pose's largest actuator load."""


class HalLoads(VerifyCheck, name="hal loads", needs="compared poses"):
    def run(self, context):
        robot, module = context.robot, context.routine
        if module.parameter(f"{module.routine}.load.0") is None:
            return [not_exercised(self.name, f"the module has no load pins ({module.routine}.load.0)")]
        t6 = context.tally.first[0][:LOAD_POSES]
        if robot.wrist is None:
            t6 = t6_from_pose(regular_poses(robot, pose_from_t6(t6))[0])
        else:  # the legs' conditioning is judged by the loads' own scale below
            t6 = t6[solve(robot, t6).warnings[:, 0] == WARNINGS["WARN_GOOD_SOLUTION"]]
        if not len(t6):
            return [not_exercised(self.name, "no regular, reachable pose among the sampled ones")]
        payload = checked_payload(robot)
        expected = loads(replace(robot, payload=payload), t6).forces[:, 0]
        found, returns = module.static_loads(module.emc_poses(t6), (payload.mass, np.asarray(payload.centre) / module.scale,
                                                                     robot.gravity))
        scale = np.max(np.abs(expected), axis=1)
        judged = np.isfinite(scale) & (scale > 0) & (returns == 0)
        worst = float(np.max(np.max(np.abs(found - expected), axis=1)[judged] / scale[judged], initial=0.0))
        missing = int(np.count_nonzero(np.isnan(found).any(axis=1)))
        passed = worst <= LOAD_TOLERANCE and not missing and bool(np.any(judged))
        return [Check(self.name, passed,
                      f"the pins load.0 .. load.{robot.joint_count - 1} after each inverse against kingen's static loads holding "
                      f"{payload_words(robot)}, set through the module's payload parameters, on {int(np.count_nonzero(judged))} "
                      f"regular poses of {len(t6)}: max relative difference {worst:.3g} (at most {LOAD_TOLERANCE:g})"
                      f"{f'; {missing} poses without the pins' if missing else ''}", judged=int(np.count_nonzero(judged)))]
