"""The serial wrist's part of every host's view-model (templates/wrist.c.j2): its table as C
text, and the whole machine's joints (the legs', then the wrist's) for a routine of all
postures. Pure, like kingen.hosts.render."""

import numpy as np

from ..robot.constraints import family, platform_axes
from ..robot.limbs import c_double, c_vector


def wrist_table(robot):
    """The wrist's table of ``robot`` (with a wrist) as C text: ``axes`` (two rows, unit, platform
    frame), ``start`` the tool's z axis and ``reach`` (mm) the tool tip's distance along it from
    the wrist centre, every wrist joint at 0 (kingen.robot.wrist.Wrist), then what follows from
    them alone, by kingen.kinematics.wrist's operations: a1.a2, 1 - (a1.a2)^2, z0.a2, a1 x a2,
    its length and z0's part normal to a2; and the tool frame (``tool_rotation`` rows,
    ``tool_offset`` mm) in the platform frame at zero, for the wrist's forward."""
    wrist = robot.wrist
    first, second = wrist.axes
    start = wrist.tool[:3, 2]
    cosine, normal, onto_second = first @ second, np.cross(first, second), start @ second
    return {"axes": [c_vector(axis) for axis in wrist.axes], "start": c_vector(start), "reach": c_double(wrist.reach),
            "cosine": c_double(cosine), "denominator": c_double(1.0 - cosine * cosine),
            "onto_second": c_double(onto_second), "normal": c_vector(normal),
            "normal_length": c_double(np.linalg.norm(normal)), "start_normal": c_vector(start - onto_second * second),
            "tool_rotation": [c_vector(row) for row in wrist.tool[:3, :3]], "tool_offset": c_vector(wrist.tool[:3, 3])}


def constraint_rows(robot):
    """The parallel part's three constraint wrenches of ``robot`` (with a wrist) as C text, for
    the C library's Jacobian (templates/wrist.c.j2, ``wrist_rates``): each row a platform axis
    ``axis`` e (platform frame, unit), a base point or axis ``base`` b (base frame) and a
    ``weight``; at platform rotation R the wrench is [weight R e; b x R e] (base frame, moment
    about the base origin): a force along R e through the base point b (weight 1), or a couple
    b x R e (weight 0). The same wrenches as kingen.kinematics.parasitic_axes.axes_wrenches
    (the platform revolute axes, through their legs' base points) and
    kingen.kinematics.parasitic_tube.tube_wrenches (the tube's two forces, its couple)."""
    parallel = robot.parallel
    if family(parallel) == "tube":
        leg = parallel.passive_leg
        rows = [(leg.second_axis, leg.base_point, 1.0), (leg.frame[:, 2], leg.base_point, 1.0),
                (leg.second_axis, leg.first_axis, 0.0)]
    else:
        rows = [(axis, base, 1.0) for _, (axis, base, _) in platform_axes(parallel.limbs)]
    return [{"axis": c_vector(axis), "base": c_vector(base), "weight": c_double(weight)} for axis, base, weight in rows]


def whole_view(robot, parallel_view, build_info):
    """The shared view-model (kingen.hosts.render.robot_view) of ``robot`` (with a wrist) from its
    parallel part's ``parallel_view``: joints the legs' (their posture digits one up: the wrist's
    branch is the last digit) then the wrist's (digit 0, radians, travel in degrees), the joint
    and posture counts, the wrist's table and ``build_info`` the library's build information."""
    legs = [{**joint, "bit": joint["bit"] + 1 if joint["bit"] >= 0 else -1} for joint in parallel_view["joints"]]
    wrist = robot.wrist
    joints = legs + [{
        "index": robot.dof + index,
        "name": name,
        "model": "wrist",
        "units": "radians",
        "bit": 0,
        "limited": int(bool(limited)),
        "lower": c_double(wrist.lower[index] if limited else 0.0),
        "upper": c_double(wrist.upper[index] if limited else 0.0),
        "travel_text": f"[{np.degrees(wrist.lower[index]):.10g}, {np.degrees(wrist.upper[index]):.10g}] degrees"
        if limited else "",
    } for index, name, limited in zip(range(len(wrist.names)), wrist.names,
                                      np.isfinite(wrist.lower) | np.isfinite(wrist.upper))]
    wrist_terms = [f"joints[{joint['index']}].value[0] + joints[{joint['index']}].value[1]" for joint in joints[robot.dof:]]
    return {**parallel_view, "dof": robot.joint_count, "postures": robot.postures, "joints": joints,
            "two_branch_count": parallel_view["two_branch_count"] + 1,
            "joint_sum": parallel_view["joint_sum"] + wrist_terms,
            "any_limits": any(joint["limited"] for joint in joints), "wrist": wrist_table(robot),
            "constraint_rows": constraint_rows(robot),
            "build_info": build_info}
