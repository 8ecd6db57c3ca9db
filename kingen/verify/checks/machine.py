"""``machine``: whether the robot itself can work at its verification home, by the numpy
reference alone (:mod:`kingen.kinematics.home`): a routine equal to the reference proves
nothing of a machine whose legs cannot reach home or whose design is singular there, nor of one
under 10 mm across whose file states no units (read in mm, its lengths are likely metres). A robot
whose file states its units and that is implausibly small or large across gets a notice naming them."""

import math
from dataclasses import replace

from ...conventions import wrap_angle
from ...kinematics.home import home_problem, judged_posture, scale_notice, size_problem
from ...kinematics.loads import held_problem, held_text
from .base import Check, VerifyCheck


def machine_check(robot):
    """``machine``: fails a machine whose units are in doubt (:func:`kingen.kinematics.home.size_problem`);
    passes when the judged posture (the working posture when the file gives one,
    else some posture) can be the machine's home (:func:`kingen.kinematics.home.home_problem`:
    reachable, within travel, not singular, its payload held within every actuator's force limit
    and every passive joint within its limit: kingen.kinematics.loads.held_problem); the failure
    says why, in the robot file's units.
    A machine with a wrist is judged by its parallel part at the platform's home, and its wrist
    joints at 0 (the home's tool pose) within their travel."""
    if robot.wrist is not None:  # the payload sits on the tool: kingen loads judges it, not the parallel part alone
        return _with_wrist(robot, machine_check(replace(robot.parallel, payload=None)))
    size = size_problem(robot)
    if size is not None:
        return Check("machine", False, size)
    home = judged_posture(robot)
    problem = home_problem(robot, home) or (held_problem(robot, home.posture) if home.reachable else None)
    if problem is not None:
        if robot.working_posture_given:
            problem += " (the file's working_posture)"
        elif robot.postures > 1:
            problem += f"; none of its {robot.postures} postures can be its home"
        return Check("machine", False, f"{problem}: the machine cannot work there")
    index = "" if math.isnan(home.direct_index) else f", direct index {home.direct_index:.3g} mm"
    return Check("machine", True, f"posture {home.posture} reaches the verification home within travel{index}"
                                  f"{held_text(robot)}")


def _with_wrist(robot, parallel):
    """The ``machine`` Check of a robot with a wrist from its parallel part's ``parallel``: the
    wrist's readings at the verification home's tool pose (every geometric angle 0: each joint
    reads -zero_offset, wrapped) within travel."""
    wrist = robot.wrist
    readings = wrap_angle(0.0 - wrist.zero)  # not -zero: a zero offset of 0 reads 0, not -0
    read = f"reading {', '.join(f'{math.degrees(r):g}' for r in readings)} deg"
    outside = [name for name, reading, low, high in zip(wrist.names, readings, wrist.lower, wrist.upper)
               if not low <= reading <= high]
    if outside:
        return Check("machine", False, f"the wrist joints {', '.join(outside)} at the verification home's tool pose "
                                       f"({read}) lie beyond travel: the machine cannot work there")
    return Check("machine", parallel.passed, f"the parallel part at the platform's home: {parallel.detail}; "
                                              f"the wrist joints at the home's tool pose ({read}) lie within travel")


class Machine(VerifyCheck, name="machine", needs="golden values"):
    def run(self, context):
        notice = scale_notice(context.robot)
        if notice is not None:
            context.report.notices.append(notice)
        return [machine_check(context.robot)]
