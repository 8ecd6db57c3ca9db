"""A check's path for the report's 3D view (kingen.view's scene overlays ``frames`` and
``markers``, plain JSON data): the machine's poses along the program with the joints kingen
computed there, and each problem of the table marked at its own place.

Frames: ``{t, pose, joints, warning, line, label}``; ``t`` where the frame stands along the
program in regular samples (the figures' x axis), ``line`` its program line, ``label`` both in
words, ``pose`` the machine's pose (mm, degrees, base frame: a wrist machine's tool pose, a
constrained machine's on its manifold), ``joints`` in the routine's units (mm, radians; None
where a limb has no solution), ``warning`` the routine's warning name (WARN_*). At most
FRAMES frames of the path, evenly thinned from the findings' trace (its first and last kept),
plus one frame at each problem's own place (at most findings.MAX_PROBLEMS), in the order of ``t``.

Travel: per joint the travel the check judged (the robot file's and the .ini's), ``[lower,
upper]`` in the robot file's units (mm, degrees), a side without a limit None (None where neither
side has one): the view colours a limb beyond it; ``travel_from`` where it came from, in words
(the robot file, the .ini).

Markers: ``{frame, label}``, one per problem of the report's table (report.problem_rows), in
its order; ``frame`` indexes ``frames``: the problem's own place, or, for one with no joints
(a CSV row off a constrained machine's manifold), the first frame of the path on its line.
"""

import numpy as np

from ..conventions import pose_from_t6
from ..kinematics.routine import answer_frame
from ..units import travel_ends
from .program import is_gcode
from .report import problem_rows

FRAMES = 2000
"""The path's frames at most (every problem's place comes on top)."""


def machine_poses(outcome, poses):
    """The machine's poses (n, 6; mm, degrees, base frame) for the checked samples' ``poses``:
    a wrist machine's tool pose for a G-code program's five-axis world X Y Z A B C, else as given."""
    poses = np.asarray(poses, dtype=float).reshape(-1, 6)
    if outcome.five_axis is None or not is_gcode(outcome.program) or not len(poses):
        return poses
    return pose_from_t6(outcome.five_axis.t6(poses))


def path_frames(outcome):
    """The path's frames (module docstring): at most FRAMES, evenly spaced over the trace."""
    trace = outcome.findings.trace_arrays()
    count = len(trace["sample"])
    if not count:
        return []
    kept = np.unique(np.round(np.linspace(0, count - 1, min(count, FRAMES))).astype(int))
    poses = machine_poses(outcome, trace["poses"][kept])
    joints = trace["joints"][kept] / outcome.findings.display_scale
    return [_frame(trace["sample"][at], pose, values, trace["warnings"][at], int(trace["line"][at]))
            for at, pose, values in zip(kept, poses, joints)]


def _frame(t, pose, joints, warning, line):
    """A frame (module docstring) at sample ``t`` on program ``line``."""
    sample = f"{float(t):.0f}" if float(t).is_integer() else f"{float(t):.2f}"
    return answer_frame(t, pose, joints, warning, line=line, label=f"line {line}, sample {sample}")


def travel(outcome):
    """Each joint's judged travel (module docstring)."""
    scale = outcome.findings.display_scale
    return [travel_ends(low, high, factor) for low, high, factor in zip(outcome.limits.lower, outcome.limits.upper, scale)]


def playback(outcome):
    """{"frames": [...], "markers": [...], "travel": [...], "travel_from": "..."} of ``outcome``
    (module docstring)."""
    path = path_frames(outcome)
    problems = outcome.findings.sorted_problems()
    own = [place for place in problems if place.sample is not None and np.all(np.isfinite(place.joints))]
    poses = machine_poses(outcome, [place.pose for place in own])
    scale = outcome.findings.display_scale
    at_places = {id(place): _frame(place.sample, pose, np.asarray(place.joints) / scale, place.warning, place.line)
                 for place, pose in zip(own, poses)}
    ordered = sorted([(frame["t"], 0, index, frame) for index, frame in enumerate(path)]
                     + [(frame["t"], 1, index, frame) for index, frame in enumerate(at_places.values())])
    frames = [entry[3] for entry in ordered]
    number = {id(frame): index for index, frame in enumerate(frames)}
    markers = []
    for place, row in zip(problems, problem_rows(outcome)[1:]):
        frame = at_places.get(id(place))
        index = number[id(frame)] if frame is not None else _on_line(frames, place.line)
        if index is not None:
            markers.append({"frame": index, "label": _label(row)})
    return {"frames": frames, "markers": markers, "travel": travel(outcome),
            "travel_from": " and ".join(outcome.limits.sources)}


def _on_line(frames, line):
    """The first frame on program ``line`` (None: none)."""
    return next((index for index, frame in enumerate(frames) if frame["line"] == line), None)


def _label(row):
    """A marker's words from its row of report.problem_rows: line, problem, joint, value, limit."""
    line, kind, joint, value, limit = row[:5]
    what = kind if joint == "-" else f"{kind} {joint}"
    return f"line {line}: {what} {value} (limit {limit})"
