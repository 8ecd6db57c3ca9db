"""What ``analyze`` judges differently on a machine with a serial wrist (kingen.robot.wrist).

Its poses are tool poses (mm, degrees; the tool tip and the tool axis, the turn about the axis
free; with a three-axis wrist the whole pose), solved by the numpy reference from the tool's T6 (kingen.kinematics.hybrid.wrist): joints the
legs', then the wrist's. The parallel part is judged at the platform pose the machine takes for
each tool pose, the wrist by its radicands (the first wrist joint's 1 - (a1.w_p)^2 and the
branches' D). An A/C head's usual home has its tool axis along the first wrist axis (the
head's pole, where the first joint's angle is lost but the tool points there all the same):
when the verification home lies there, the poses in that band are not stopped by it, so that a
tilt walk can leave home; a pole met away from such a home stops a pose as unreachable.
"""

import numpy as np

from ..conventions import matrix_from_pose, t6_from_matrix
from ..kinematics.reference import solve
from ..kinematics.routine import SINGULAR_TOLERANCE
from ..kinematics.hybrid.wrist import orientation_rows

TURN_PROBE_DEG = 1.0
"""A coordinate moved by this much at home that moves neither the tool tip nor the tool axis
by more than TURN_FREE only turns the tool about its axis: analyze does not sweep it."""
TURN_FREE = 1e-9


def home_t6(robot):
    """(1, 4, 4) the T6 of the robot's verification home (for a wrist: the tool's home pose)."""
    return t6_from_matrix(matrix_from_pose(np.array([robot.verification.home], dtype=float)))


def at_pole(robot):
    """Whether the wrist's radicands at the verification home are within SINGULAR_TOLERANCE of
    zero (the tool axis along the first wrist axis, or the branches meeting); False without a
    wrist. Both branches share these radicands, so the posture does not matter."""
    if robot.wrist is None:
        return False
    radicands = solve(robot, home_t6(robot)).radicands[0, robot.dof:]
    return bool(np.min(np.abs(radicands)) <= SINGULAR_TOLERANCE)


def radicand_stops(robot, solution, pole):
    """(n,) bool: poses a radicand stops as unreachable: a leg's within SINGULAR_TOLERANCE of
    zero; with a wrist also the parallel part's constraint radicand (the parasitic motion's)
    and, unless ``pole`` (at_pole of the home), the wrist's."""
    judged = solution.radicands if robot.wrist is None or not pole else solution.radicands[:, :robot.dof]
    stops = np.min(np.abs(judged), axis=1) <= SINGULAR_TOLERANCE
    if robot.wrist is not None and solution.constraint is not None:
        stops |= np.abs(solution.constraint) <= SINGULAR_TOLERANCE
    return stops


def beyond_travel(robot, joints):
    """(n,) bool: with a wrist, some joint of ``joints`` (n, joint_count; mm, rad) outside its
    travel (the pole's singular warning outranks the joint limits' in the reference's answer);
    all False without a wrist, whose warnings say it."""
    if robot.wrist is None:
        return np.zeros(len(joints), dtype=bool)
    lower, upper = robot.travel_limits()
    return np.any((joints < lower) | (joints > upper), axis=1)


def tool_moving(robot, free):
    """The indices of ``free`` (into kingen.kinematics.forward.COORDINATES) whose change by
    TURN_PROBE_DEG (or mm) at the home moves the tool tip or the tool axis (a three-axis wrist:
    any tool axis, so all of them); all of them without a wrist."""
    if robot.wrist is None:
        return list(free)
    start = np.array(robot.verification.home, dtype=float)
    poses = np.tile(start, (len(free) + 1, 1))
    poses[np.arange(1, len(free) + 1), free] += TURN_PROBE_DEG
    t6 = t6_from_matrix(matrix_from_pose(poses))
    rows = [*orientation_rows(robot.wrist), 3]
    moved = np.max(np.abs(t6[1:, rows, :3] - t6[0, rows, :3]), axis=(1, 2))
    return [axis for axis, distance in zip(free, moved) if distance > TURN_FREE]


def wrist_available(robot, free, swept, pole, tilted):
    """analyze's ``available`` entries that differ on a machine with a wrist: what is judged,
    what is not exercised and why (``free``/``swept``: the coordinates' names; ``tilted``:
    whether tilt limits were found)."""
    names = ", ".join(robot.wrist.names)
    read, aligned = (("the whole pose: tool tip and tool frame", f"{robot.wrist.names[-1]}'s axis")
                     if robot.wrist.whole_pose else
                     ("the tool tip and the tool axis; the turn about the axis is free", "the tool axis"))
    unswept = [name for name in free if name not in swept]
    return {
        "poses": f"tool poses ({read}); joints: the legs', then the wrist's ({names})",
        "direct_index": f"not available: the parallel part's {robot.dof} legs (its constraints are not in the index); "
                        "a direct singularity is found from its closure Jacobian instead (direct singularity below)",
        "direct_singularity": "crossings only: the sign of the parallel part's closure Jacobian over the wrist "
                              "centre's x, y, z at the platform pose the machine takes (the tool's motion moves "
                              "the wrist centre; the wrist's own determinant changes sign only where its radicand "
                              "D crosses 0, which stops a pose as unreachable)",
        "collision": ("legs only: the wrist and the tool have no collision geometry (not exercised)"
                      if robot.collision is not None else
                      "not available: the robot file gives no collision radii (collision: leg_radius, rod_radius, "
                      "crank_radius); "
                      "the wrist and the tool have no collision geometry (not exercised)"),
        "wrist_singularity": (f"stops a pose as unreachable: a wrist radicand within {SINGULAR_TOLERANCE:g} of 0 "
                              f"({aligned} along {robot.wrist.names[0]}'s axis, or the branches meeting)"
                              + ("; home lies there (the head's pole): poses in that band are judged through "
                                 f"({robot.wrist.names[0]}'s angle there is arbitrary)" if pole else "")),
        "tilt_limits": ("available: the tool frame turned about a horizontal axis through the tool tip, the tilt "
                        "the tool axis's angle from its home axis" if tilted else
                        "not analysed: roll and pitch do not both move the tool axis at home"),
        "sweeps": "available" if not unswept else
        f"{', '.join(unswept)} not swept: at home it only turns the tool about its axis (free)",
    }
