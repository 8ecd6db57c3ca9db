"""The serial wrist's part of every host's view-model (templates/wrist.c.j2): its table as C
text, and the whole machine's joints (the legs', then the wrist's) for a routine of all
postures. Pure, like kingen.hosts.render."""

import numpy as np

from ..robot.constraints import family, platform_axes
from ..robot.limbs import c_double, c_vector
from ..robot.limbs.base import axis_words

IN_PLANE = 1e-9
"""The tool's zero-joint axis lies in the plane of the wrist's axes when its part along their
normal is at most this: then each branch is one sign of the second wrist joint."""


def turned_axis(wrist):
    """(3,) z0, the unit axis (platform frame, every wrist joint at 0) the wrist's first two
    joints turn: the tool's z axis for two joints, the third joint's axis for three
    (kingen.kinematics.hybrid.wrist)."""
    return wrist.axes[2] if wrist.whole_pose else wrist.tool[:3, 2]


def wrist_table(robot, mm_per_unit=1.0):
    """The wrist's table of ``robot`` (with a wrist) as C text, its lengths in a unit of
    ``mm_per_unit`` mm (1: mm; 25.4: a LinuxCNC machine in inches): ``axes`` (two or three rows,
    unit, platform frame), ``start`` the axis z0 the first two joints turn (:func:`turned_axis`) and
    ``reach`` (that unit) the tool tip's distance along the tool's z axis from the wrist centre, every
    wrist joint at 0 (kingen.robot.wrist.Wrist), ``three`` whether it has three joints (then
    :func:`_third_table`'s entries too), then what follows from
    them alone, by kingen.kinematics.hybrid.wrist's operations: a1.a2, 1 - (a1.a2)^2, z0.a2, a1 x a2,
    its length and z0's part normal to a2; and the tool frame (``tool_rotation`` rows,
    ``tool_offset``, that unit) in the platform frame at zero, for the wrist's forward; ``zero`` the
    joints' zero offsets (rad, kingen.robot.wrist.Wrist.zero), empty when all are 0 (the C is
    then as without them)."""
    wrist = robot.wrist
    first, second = wrist.axes[:2]
    three, start = wrist.whole_pose, turned_axis(wrist)
    cosine, normal, onto_second = first @ second, np.cross(first, second), start @ second
    table = {"axes": [c_vector(axis) for axis in wrist.axes], "start": c_vector(start),
             "reach": c_double(wrist.reach / mm_per_unit),
             "cosine": c_double(cosine), "denominator": c_double(1.0 - cosine * cosine),
             "onto_second": c_double(onto_second), "normal": c_vector(normal),
             "normal_length": c_double(np.linalg.norm(normal)), "start_normal": c_vector(start - onto_second * second),
             "tool_rotation": [c_vector(row) for row in wrist.tool[:3, :3]],
             "tool_offset": c_vector(wrist.tool[:3, 3] / mm_per_unit),
             "three": three, "zero": [c_double(zero) for zero in wrist.zero] if np.any(wrist.zero) else []}
    return {**table, **_third_table(wrist, mm_per_unit)} if three else table


def _third_table(wrist, mm_per_unit):
    """What a three-axis wrist adds to its table (C text): ``tip`` t (kingen.robot.wrist.Wrist.tip,
    in a unit of ``mm_per_unit`` mm, the tool frame: the wrist centre is p = q - R t for the tool
    pose R, q), ``axis_tool`` R0^T a3 (R0 the tool's rotation at zero) and ``second_normal`` a2's
    part normal to a3, on which the third angle is measured (templates/wrist.c.j2,
    kingen_wrist_third)."""
    second, third = wrist.axes[1], wrist.axes[2]
    return {"tip": c_vector(wrist.tip / mm_per_unit), "axis_tool": c_vector(wrist.tool[:3, :3].T @ third),
            "second_normal": c_vector(second - (second @ third) * third)}


def platform_constraints(robot):
    """The parallel part's three constraint wrenches of ``robot`` (task coordinates x, y, z: a
    platform revolute axis per leg, or a passive tube), numbers: (e, b, weight) each, e a
    platform axis (platform frame, unit), b a base point or axis (base frame), weight 1 or 0;
    at platform rotation R the wrench is [weight R e; b x R e] (base frame, moment about the
    base origin): a force along R e through the base point b (weight 1), or a couple b x R e
    (weight 0). The same wrenches as kingen.kinematics.hybrid.parasitic_axes.axes_wrenches (the
    platform revolute axes, through their legs' base points) and
    kingen.kinematics.hybrid.parasitic_tube.tube_wrenches (the tube's two forces, its couple)."""
    parallel = robot.parallel
    if family(parallel) == "tube":
        leg = parallel.passive_leg
        return [(leg.second_axis, leg.base_point, 1.0), (leg.frame[:, 2], leg.base_point, 1.0),
                (leg.second_axis, leg.first_axis, 0.0)]
    return [(axis, base, 1.0) for _, (axis, base, _) in platform_axes(parallel.limbs)]


def constraint_rows(robot):
    """:func:`platform_constraints` of ``robot`` (with a wrist) as C text, for the C library's
    Jacobian (templates/wrist.c.j2, ``wrist_rates``): ``axis`` e, ``base`` b, ``weight``."""
    return [{"axis": c_vector(axis), "base": c_vector(base), "weight": c_double(weight)}
            for axis, base, weight in platform_constraints(robot)]


def wrist_joint_rows(robot):
    """Per wrist joint of ``robot``, what every host's view shows of it: its ``index`` after the
    legs', ``name``, ``model`` 'wrist', ``limited`` (0 or 1: a travel given) and ``travel_text``
    (degrees, empty without travel)."""
    wrist = robot.wrist
    limited = np.isfinite(wrist.lower) | np.isfinite(wrist.upper)
    return [{"index": robot.dof + index, "name": name, "model": "wrist", "limited": int(limited[index]),
             "travel_text": f"[{np.degrees(wrist.lower[index]):.10g}, {np.degrees(wrist.upper[index]):.10g}] degrees"
             if limited[index] else ""} for index, name in enumerate(wrist.names)]


def whole_view(robot, parallel_view, build_info):
    """The shared view-model (kingen.hosts.render.robot_view) of ``robot`` (with a wrist) from its
    parallel part's ``parallel_view``: joints the legs' (their posture digits one up: the wrist's
    branch is the last digit) then the wrist's (digit 0, radians, travel in degrees), the joint
    and posture counts, the wrist's table and ``build_info`` the library's build information."""
    legs = [{**joint, "bit": joint["bit"] + 1 if joint["bit"] >= 0 else -1} for joint in parallel_view["joints"]]
    wrist = robot.wrist
    joints = legs + [{
        **row, "units": "radians", "bit": 0,
        "lower": c_double(wrist.lower[index] if row["limited"] else 0.0),
        "upper": c_double(wrist.upper[index] if row["limited"] else 0.0),
    } for index, row in enumerate(wrist_joint_rows(robot))]
    wrist_terms = [f"joints[{joint['index']}].value[0] + joints[{joint['index']}].value[1]" for joint in joints[robot.dof:]]
    return {**parallel_view, "dof": robot.joint_count, "postures": robot.postures, "joints": joints,
            "two_branch_count": parallel_view["two_branch_count"] + 1,
            "joint_sum": parallel_view["joint_sum"] + wrist_terms,
            "any_limits": any(joint["limited"] for joint in joints), "wrist": wrist_table(robot),
            "constraint_rows": constraint_rows(robot),
            "build_info": build_info}


def branch_words(robot):
    """(branch 0, branch 1) of ``robot``'s wrist in words, exact for every tool axis it reaches:
    branch 0 takes the intermediate axis c = Rot(a2, t2) z0 on the side of a1 x a2
    (kingen.kinematics.hybrid.wrist), branch 1 the other (the head's flip). Where z0 lies in the plane
    of a1 and a2, c.(a1 x a2) = sin(t2) (a2 x z0).(a1 x a2), so a branch is a sign of t2. z0 is
    the tool axis of a two-axis wrist, the third joint's axis of a three-axis one (:func:`turned_axis`)."""
    wrist = robot.wrist
    first, second = wrist.names[:2]
    normal, start = np.cross(*wrist.axes[:2]), turned_axis(wrist)
    turned = f"the axis of {wrist.names[2]}" if wrist.whole_pose else "the tool axis"
    if abs(start @ normal) <= IN_PLANE:
        sign = np.sign(np.cross(wrist.axes[1], start) @ normal)
        return (f"{second} >= 0" if sign > 0 else f"{second} <= 0",
                f"{second} < 0 (the head's flip)" if sign > 0 else f"{second} > 0 (the head's flip)")
    return (f"{turned} turned by {second} on the side of {first} x {second}",
            f"{turned} turned by {second} on the other side (the head's flip)")


def sheet_words(robot):
    """What every host's setup sheet says of ``robot``'s wrist (it has one): ``joints`` its two
    or three joints (name, axis in words in the platform frame at zero, travel in degrees or None),
    ``chain`` them in words, ``branches`` (branch 0, branch 1) in words, ``tool`` the tool tip
    (mm) and the tool axis in the platform frame with every wrist joint at 0, ``reach`` (mm) and
    ``three`` whether the wrist has three joints (the tool pose read whole)."""
    wrist = robot.wrist
    limited = np.isfinite(wrist.lower) | np.isfinite(wrist.upper)
    joints = [{"name": name, "axis": axis_words(axis),
               "travel": (f"{np.degrees(lower):.10g}", f"{np.degrees(upper):.10g}") if bounded else None}
              for name, axis, lower, upper, bounded in zip(wrist.names, wrist.axes, wrist.lower, wrist.upper, limited)]
    tip = ", ".join(f"{value + 0.0:.10g}" for value in wrist.tool[:3, 3])
    return {"joints": joints, "branches": branch_words(robot), "reach": f"{wrist.reach:.10g}", "three": wrist.whole_pose,
            "chain": ", then ".join(f"{joint['name']} about {joint['axis']}" for joint in joints),
            "tool": f"tool tip at ({tip}) mm, tool axis {axis_words(wrist.tool[:3, 2])}"}
