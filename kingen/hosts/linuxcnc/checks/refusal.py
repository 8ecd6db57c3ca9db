"""``inverse refusal``: kinematicsInverse returns non-zero (LinuxCNC then stops with a
kinematics error) for a pose holding NaN or infinity and, for robots with a limb that can be
out of reach (rails, cranks), for a pose a hundred robot sizes away."""

import numpy as np

from ....verify.checks.base import Check, VerifyCheck


class Refusal(VerifyCheck, name="inverse refusal", needs="routine", item="interface"):
    def run(self, context):
        robot, module = context.robot, context.routine
        home = np.array(robot.verification.home, dtype=float)
        cases = ["x = NaN", "x = inf"]
        can_miss = any(limb.has_radicand for limb in robot.limbs)
        axis = 2 if robot.task else 0  # a constrained machine's module reads z, not x
        if can_miss:
            cases.append(f"{'xyz'[axis]} + {100 * robot.size_mm:g} mm (out of every limb's reach)")
        world = np.zeros((len(cases), 9))
        world[:, :3] = home[:3] / module.scale
        world[:, 3:6] = home[3:]
        world[0, 0], world[1, 0] = np.nan, np.inf
        if can_miss:
            world[2, axis] += 100.0 * robot.size_mm / module.scale
        _, returns, _ = module.inverse(world)
        accepted = [case for case, code in zip(cases, returns) if code == 0]
        detail = (f"returns 0 for {', '.join(accepted)}" if accepted else
                  f"returns non-zero for all {len(cases)} cases ({', '.join(cases)}): {', '.join(map(str, returns))}")
        if not can_miss:
            detail += "; out of reach: not exercised (legs reach every pose; travel limits are LinuxCNC's joint limits)"
        return [Check("inverse refusal", not accepted, detail)]
