"""A robot at a pose as plain JSON data: what the view (kingen.view.page) draws.

``scene(robot, pose, posture)`` is the whole contract between Python and the page's script.
Every length is in mm and every point in the base frame unless a key says otherwise; a joint's
value is in the routine's units (mm, or radians for a revolute joint), its travel in the robot
file's (mm, or degrees). A matrix is a column-form homogeneous 4x4 H, row by row: H[r][3] the
origin (mm), H[0..2][0..2] the rotation (kingen.conventions.matrix_from_pose; not a T6).

Keys: ``robot`` and ``description``; ``coordinates`` (x y z roll pitch yaw) and ``free`` (those
the page's fields set: a machine with task coordinates, its task coordinates); ``region`` {home,
range} (the verification region, mm and degrees: the sliders' span); ``joint_names``,
``joint_units`` ("mm" or "rad"), ``travel`` ([lower, upper] in mm or degrees, a side without a
limit None; None where neither side has one), ``travel_from`` (where that travel comes from, in
words: "the robot file", or a check's robot file and LinuxCNC .ini);
``postures``, ``posture_branches`` (per posture, its branches as `kingen solve` prints them) and
``posture``; ``pose`` (6), ``t6`` (4 x 4, DELMIA's layout), ``joints`` and
``warning`` (the reference's there); ``size`` (mm, the robot's largest length: the drawing's
scale); ``singular_across`` (the cosine of the angle between a limb's link and its base side's
motion within which the page colours it singular: sqrt of the singular tolerance on its
normalised radicand, which is that cosine squared); ``model`` and ``machine`` (below); ``no_routine`` (set by kingen.view.page: what the
sliders need, on a page without the routine).

What the page needs to draw the machine at a pose of its own is ``model``: per limb its
platform point (platform frame), where its passive link starts on the base side as a function of
its joint q, B(q) = c + q a + cos(q) u + sin(q) v (derived here from the limb model's
``base_side_point``, so the page knows no limb model by name), its passive link's length
l0 + l1 q, and whether these forms are the model's (``exact``); the wrist's axes and tool; the passive leg's base point. ``machine`` is that drawing
computed here, with the reference (kingen.kinematics.reference), at the scene's pose:
``{platform (H), limbs: [{base_side, platform_point, status}], tool (H, or None without a wrist),
status (the posture's warning)}``, a limb's status "good", "limits" (beyond its travel),
"singular" or "unreachable". A ghost overlay has the same keys as ``machine``.

Optional overlays (kingen.view.page draws each one it finds): ``frames`` [{t, pose: [6], joints,
warning, label?}] (a path played on a timeline; ``label`` shown beside it, else ``t`` in s),
``start_frame`` (the frame the timeline opens at), ``markers`` [{frame, label}] (findings on
that timeline, numbered on it, each label shown at its frame),
``arrows`` [{origin: [3], vector: [3], label}], ``ghost`` {label, scale, platform, limbs, tool},
``surface`` {vertices: [[3]...], triangles: [[3]...], label}, ``points`` [{position: [3], label}].
:func:`machine_at` gives a ghost's or a frame's drawing.
"""

import math

import numpy as np

from ..conventions import branch_of_posture, matrix_from_t6, pose_from_t6, t6_from_pose
from ..errors import KingenError
from ..units import travel_ends
from ..kinematics.reference import solve
from ..kinematics.routine import SINGULAR_TOLERANCE, WARNING_NAMES
from ..kinematics.hybrid.wrist import rotation_about

COORDINATES = ("x", "y", "z", "roll", "pitch", "yaw")
"""The pose's coordinates, in order: mm, then degrees (R = Rz(yaw) Ry(pitch) Rx(roll))."""
FIT = 1e-9
"""How far (relative to the robot's size) the drawing's forms may miss a limb model's base-side
point and passive length at the test joints and platform points and still be exact."""
TEST_JOINTS = (-2.3, 0.7, 41.0)
"""Joints (mm or rad) the forms are checked at, none of those they are fitted on."""


def _forms(limb, size):
    """(base_side, passive, exact): {c, a, u, v} (3 each, mm, base frame) with B(q) = c + q a +
    cos(q) u + sin(q) v the limb's base-side point (kingen.robot.limbs.base.LimbModel.base_side_point),
    [l0, l1] with l0 + l1 q its passive link's length (mm), fitted on a few joints; ``exact`` whether
    both hold at TEST_JOINTS for platform points at the origin and off it (a model whose base side
    follows the platform point, or whose link's length is no line in q, is drawn from these forms
    without the page judging its closure)."""
    def at(q, point=np.zeros(3)):
        return np.asarray(limb.base_side_point(point[None], np.array([float(q)])), dtype=float).reshape(3)

    def length(q):
        return float(np.asarray(limb.passive_length(np.array([float(q)]))).reshape(-1)[0])

    if limb.joint_type.wraps:
        c = (at(0.0) + at(math.pi)) / 2.0
        form = {"c": c, "a": np.zeros(3), "u": at(0.0) - c, "v": at(math.pi / 2.0) - c}
    else:
        form = {"c": at(0.0), "a": at(1.0) - at(0.0), "u": np.zeros(3), "v": np.zeros(3)}
    passive = [length(0.0), length(1.0) - length(0.0)]
    off = np.array([size / 3.0, -size / 5.0, size / 7.0])
    exact = all(np.linalg.norm(form["c"] + q * form["a"] + math.cos(q) * form["u"] + math.sin(q) * form["v"]
                               - at(q, point)) <= FIT * size
                and abs(passive[0] + passive[1] * q - length(q)) <= FIT * size
                for q in TEST_JOINTS for point in (np.zeros(3), off))
    return {key: value.tolist() for key, value in form.items()}, passive, exact


def posture_branches(robot):
    """Per posture, its branches as `kingen solve` prints them: each two-branch limb's digit (0 or 1)
    in the robot file's order, then a wrist's branch; "-" for a robot of one posture's limbs."""
    digits = [bit for bit in robot.branch_bits if bit >= 0]
    words = []
    for k in range(robot.postures):
        wrist = str(k % 2) if robot.wrist is not None and robot.wrist.branch is None else ""
        limbs = k // 2 if wrist else k
        words.append("".join(str(branch_of_posture(limbs, bit)) for bit in digits) + wrist or "-")
    return words


def model(robot):
    """What the page draws the machine from at any pose (module docstring): plain data."""
    parallel = robot.parallel
    limbs = []
    for index, limb in enumerate(parallel.limbs):
        form, passive, exact = _forms(limb, parallel.size_mm)
        moving = np.linalg.norm(form["a"]) + np.linalg.norm(form["u"]) > 0.0
        limbs.append({"name": robot.joint_names[index], "platform_point": [float(v) for v in limb.platform_point],
                      "base_side": form, "passive": passive, "exact": exact,
                      "pivot": np.asarray(limb.base_joint(), dtype=float).tolist(),
                      "actuator": "arm" if limb.joint_type.wraps and moving else
                      ("carriage" if moving else "telescopic")})
    drawn = {"limbs": limbs, "passive_leg": None, "wrist": None}
    if parallel.passive_leg is not None:
        drawn["passive_leg"] = {"base_point": parallel.passive_leg.base_point.tolist()}
    if robot.wrist is not None:
        wrist = robot.wrist
        drawn["wrist"] = {"axes": wrist.axes.tolist(), "zero": wrist.zero.tolist(), "tool": wrist.tool.tolist(),
                          "reach": float(wrist.reach), "tip": wrist.tip.tolist(), "whole_pose": wrist.whole_pose}
    return drawn


def _limb_statuses(robot, solution, joints, lower, upper):
    """Per limb of the parallel part, its colour key at the first pose of ``solution``: "unreachable"
    (no real solution), "singular" (within the singular tolerance of its own singularity: a rail's
    or a crank's radicand), "limits" (beyond its travel) or "good"."""
    statuses = []
    for index in range(robot.parallel.dof):
        radicand = solution.radicands[0, index]
        if radicand < -SINGULAR_TOLERANCE:
            statuses.append("unreachable")
        elif abs(radicand) <= SINGULAR_TOLERANCE:
            statuses.append("singular")
        elif not lower[index] <= joints[index] <= upper[index]:
            statuses.append("limits")
        else:
            statuses.append("good")
    return statuses


def machine_at(robot, t6, posture):
    """The machine's drawing (module docstring's ``machine``) at the T6 ``t6`` (4, 4) of
    ``robot`` in ``posture``, with the joints and warning the reference gives there:
    (drawing, joints (mm, rad), warning name)."""
    t6 = np.asarray(t6, dtype=float).reshape(1, 4, 4)
    solution = solve(robot, t6)
    joints = solution.joints[0, :, posture]
    warning = WARNING_NAMES[int(solution.warnings[0, posture])]
    parallel = robot.parallel
    if solution.platform is not None:
        platform = matrix_from_t6(solution.platform[0])
    elif parallel.task:
        platform = matrix_from_t6(solution.machine[0])
    else:
        platform = matrix_from_t6(t6[0])
    lower, upper = robot.travel_limits()
    statuses = _limb_statuses(robot, solution, joints, lower, upper)
    limbs = []
    for index, limb in enumerate(parallel.limbs):
        q = np.array([joints[index]])
        point = platform[:3, :3] @ np.asarray(limb.platform_point, dtype=float) + platform[:3, 3]
        limbs.append({"base_side": np.asarray(limb.base_side_point(point[None], q), dtype=float).reshape(3).tolist(),
                      "platform_point": point.tolist(), "status": statuses[index]})
    tool = None
    if robot.wrist is not None:
        turned = platform[:3, :3]
        for index, axis in enumerate(robot.wrist.axes):
            turned = turned @ rotation_about(axis, [joints[robot.dof + index] + robot.wrist.zero[index]])[0]
        tool = np.eye(4)
        tool[:3, :3] = turned @ robot.wrist.tool[:3, :3]
        tool[:3, 3] = platform[:3, 3] + turned @ robot.wrist.tool[:3, 3]
        tool = tool.tolist()
    drawing = {"platform": platform.tolist(), "limbs": limbs, "tool": tool, "status": warning}
    return drawing, joints, warning


def scene(robot, pose=None, posture=None):
    """The scene of ``robot`` at ``pose`` (6: x y z mm, roll pitch yaw degrees; default the
    verification home) in ``posture`` (default the working posture): plain JSON data (module
    docstring). A machine with task coordinates takes the pose its constraints give for the
    pose's task coordinates, as its routine does (kingen.kinematics.hybrid.parasitic)."""
    pose = np.asarray(robot.verification.home if pose is None else pose, dtype=float)
    if pose.shape != (6,) or not np.all(np.isfinite(pose)):
        raise KingenError(f"pose: expected six finite numbers (x y z mm, roll pitch yaw degrees), got {pose.tolist()}")
    posture = robot.working_posture if posture is None else int(posture)
    if not 0 <= posture < robot.postures:
        raise KingenError(f"posture {posture} does not exist (the robot has {robot.postures})")
    t6 = t6_from_pose(pose)
    if robot.task:
        from ..kinematics.hybrid.parasitic import solve_parasitic

        t6 = solve_parasitic(robot, t6[None]).t6[0]
        pose = pose_from_t6(t6)
    drawing, joints, warning = machine_at(robot, t6, posture)
    limits = robot.travel_limits()
    scales = robot.joint_scale()
    region = robot.verification
    return {
        "robot": robot.name,
        "description": " ".join(robot.description.split()),
        "coordinates": list(COORDINATES),
        "free": [name for name in COORDINATES if not robot.task or name in robot.task],
        "region": {"home": [float(v) for v in region.home], "range": [float(v) for v in region.range]},
        "joint_names": list(robot.joint_names),
        "joint_units": ["rad" if t.wraps else "mm" for t in robot.joint_types],
        "travel": [travel_ends(limits[0][index], limits[1][index], 1.0 / scales[index]) for index in range(robot.joint_count)],
        "travel_from": "the robot file",
        "postures": robot.postures,
        "posture_branches": posture_branches(robot),
        "posture": posture,
        "pose": [float(v) for v in pose],
        "t6": t6.tolist(),
        "joints": [float(v) for v in joints],
        "warning": warning,
        "size": float(robot.size_mm),
        "singular_across": math.sqrt(SINGULAR_TOLERANCE),
        "model": model(robot),
        "machine": drawing,
    }

