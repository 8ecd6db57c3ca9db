"""``inverse refusal``: kinematicsInverse returns non-zero (LinuxCNC then stops with a
kinematics error) for a pose holding NaN or infinity and, for robots with a limb that can be
out of reach (rails, cranks), for a pose a hundred robot sizes away that the reference proves
out of reach in every posture (a 3-PRS on vertical rails reaches any z: its carriages move up)."""

import numpy as np

from ....conventions import t6_from_pose
from ....kinematics.hybrid.parasitic import on_manifold
from ....kinematics.reference import solve
from ....kinematics.routine import WARNINGS
from ....verify.checks.base import Check, VerifyCheck


def far_pose(robot):
    """(the pose (6,) mm and degrees, its text) a hundred robot sizes from the verification home
    along x, y or z (a machine with task coordinates: along one it commands, the pose then put
    on its manifold), the first the reference answers WARN_UNREACHABLE in every posture for;
    (None, the directions tried) when it reaches them all."""
    home = np.array(robot.verification.home, dtype=float)
    distance = 100.0 * robot.size_mm
    axes = [axis for axis, name in enumerate("xyz") if name in robot.task] if robot.task else [0, 1, 2]
    tried = []
    for axis in axes:
        for sign in (1.0, -1.0):
            pose = home.copy()
            pose[axis] += sign * distance
            if robot.task and robot.wrist is None:
                pose = on_manifold(robot, pose[None])[0]
            text = f"{'xyz'[axis]} {'+' if sign > 0 else '-'} {distance:g} mm"
            tried.append(text)
            warnings = solve(robot, t6_from_pose(pose[None])).warnings[0]
            if np.all(np.isfinite(pose)) and np.all(warnings == WARNINGS["WARN_UNREACHABLE"]):
                return pose, text
    return None, ", ".join(tried)


class Refusal(VerifyCheck, name="inverse refusal", needs="routine", item="interface"):
    def run(self, context):
        robot, module = context.robot, context.routine
        home = np.array(robot.verification.home, dtype=float)
        cases = ["x = NaN", "x = inf"]
        far, tried = far_pose(robot) if any(limb.has_radicand for limb in robot.limbs) else (None, None)
        if far is not None:
            cases.append(f"{tried} (out of every limb's reach, as the reference answers)")
        world = np.zeros((len(cases), 9))
        world[:, :3] = home[:3] / module.scale
        world[:, 3:6] = home[3:]
        world[0, 0], world[1, 0] = np.nan, np.inf
        if far is not None:
            world[2, :3], world[2, 3:6] = far[:3] / module.scale, far[3:]
        _, returns, _ = module.inverse(world)
        accepted = [case for case, code in zip(cases, returns) if code == 0]
        detail = (f"returns 0 for {', '.join(accepted)}" if accepted else
                  f"returns non-zero for all {len(cases)} cases ({', '.join(cases)}): {', '.join(map(str, returns))}")
        if tried is None:
            detail += "; out of reach: not exercised (legs reach every pose; travel limits are LinuxCNC's joint limits)"
        elif far is None:
            detail += f"; out of reach: not exercised (the reference reaches {tried} in some posture)"
        return [Check("inverse refusal", not accepted, detail)]
