"""A robot seen at one posture: what a host that answers a single assembly mode (a machine
controller's inverse kinematics has one answer) is verified against.

``at_posture(robot, k)`` is the same robot file with every two-branch limb held on the
branch posture ``k`` takes: one posture, numbered 0, whose joints, warnings, force lines and
direct index are posture ``k``'s of the full robot (docs/explanation/conventions.md, 'Postures').
"""

from dataclasses import replace

import numpy as np



class OneBranch:
    """A two-branch limb held on one branch: ``solve`` gives that branch's joint in both
    columns; everything else (geometry, closure, force lines from the joint) is the limb's."""

    branches = 1

    def __init__(self, limb, branch):
        self._limb, self.branch = limb, branch

    def __getattr__(self, name):
        return getattr(self._limb, name)

    def solve(self, platform_point):
        solution = self._limb.solve(platform_point)
        value = solution.values[..., self.branch]
        return replace(solution, values=np.stack([value, value], axis=-1))

    def model_copy(self, **changes):
        return OneBranch(self._limb.model_copy(**changes), self.branch)


def at_posture(robot, posture):
    """``robot`` with one posture: its posture ``posture`` (golden entries of that posture only);
    with a wrist, its parallel part at posture ``posture // 2`` and the wrist held on branch
    ``posture % 2``."""
    limbs = tuple(limb if bit < 0 else OneBranch(limb, branch)
                  for limb, bit, branch in zip(robot.limbs, robot.branch_bits, robot.posture_branches(posture)))
    golden = tuple(entry.model_copy(update={"posture": 0}) for entry in robot.golden if entry.posture == posture)
    other = [index for index, entry in enumerate(robot.golden) if entry.posture != posture]
    left_out = (f"golden {', '.join(f'[{index}]' for index in other)} not checked: at other postures than {posture}, "
                "the one the routine answers",) if other else ()
    held = {}
    if robot.wrist is not None:
        held = {"wrist": replace(robot.wrist, branch=posture % 2),
                "parallel_part": at_posture(robot.parallel, posture // 2)}
    return replace(robot, limbs=limbs, golden=golden, working_posture=0, left_out=robot.left_out + left_out, **held)
