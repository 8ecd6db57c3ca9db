"""analyze's tilt limits for the report's 3D view (kingen.view's scene overlays, plain JSON
data, base frame, mm).

- ``surface``: the tilt limits as a fan around the machine: its apex at home's tool point (the
  T6 origin, which a tilt does not move), one vertex at the tip of the tool axis (the T6's z
  axis, drawn AXIS_SHARE of the robot's size long, pointing away from the base: +z at home for
  a platform above its base, -z for one hanging below) tilted to each azimuth's limit,
  triangles between neighbouring azimuths, the last closing on the first.
- ``points``: those tips; labelled (its azimuth, its limit and what stops it there) where the
  cause differs from the previous azimuth's, and at the least tilt, so that the labels do not
  hide one another; every tip's words are its frame's label.
- ``frames``: the machine at each azimuth's limit (the largest tilt that passes; joints from the
  numpy reference in the analysed posture, mm and radians), labelled as its point, so that the
  view's timeline shows the pose each limit stops.
"""

import numpy as np

from ..conventions import matrix_from_t6, pose_from_t6
from ..kinematics.reference import solve
from ..kinematics.routine import answer_frame
from ..robot.placement import base_joints
from .analysis import tilted_t6
from .figures import LABELS

AXIS_SHARE = 1.0
"""The drawn tool axis' length, as a share of the robot's size (robot.size_mm)."""


def limit_t6(robot, rows, convention):
    """T6 (n, 4, 4) of home tilted to each row's limit (rows of analysis' tilt_limits:
    ``azimuth_deg``, ``max_tilt_deg``) in tilt ``convention`` (analysis.TILT_CONVENTIONS)."""
    return np.concatenate([tilted_t6(robot, [row["azimuth_deg"]], [row["max_tilt_deg"]], convention)
                           for row in rows]) if rows else np.empty((0, 4, 4))


def _label(row):
    """A limit's words: its azimuth, its tilt and what stops it."""
    stop = "not stopped" if row["cause"] == "none" else LABELS.get(row["cause"], row["cause"])
    return f"{row['azimuth_deg']:g}°: {row['max_tilt_deg']:g}°, {stop}"


def _labelled(rows):
    """Per row whether its point is labelled: its cause differs from the previous row's (the
    first row's from the last's), or it has the least tilt (the first such)."""
    least = min(range(len(rows)), key=lambda index: rows[index]["max_tilt_deg"])
    return [index == least or row["cause"] != rows[index - 1]["cause"]
            for index, row in enumerate(rows)]


def away_from_base(robot, home):
    """+1 when the T6 z axis at ``home`` (4, 4 matrix) points away from the base (from the limbs'
    base joints' centre towards the tool point, or across it), else -1."""
    centre = base_joints(robot.parallel).mean(axis=0)
    return 1.0 if (home[:3, 3] - centre) @ home[:3, 2] >= 0.0 else -1.0


def tilt_overlays(robot, analysis, convention):
    """{surface, points, frames} of ``analysis`` (analysis.analyze's, its tilt limits found in
    tilt ``convention``) for ``robot``; {} when it has no tilt limits."""
    rows = analysis["tilt_limits"]
    if not rows:
        return {}
    posture = analysis["posture"]
    t6 = limit_t6(robot, rows, convention)
    matrices = matrix_from_t6(t6)
    apex = matrices[0, :3, 3]
    length = away_from_base(robot, matrix_from_t6(tilted_t6(robot, [0.0], [0.0], convention)[0])) * AXIS_SHARE * \
        robot.size_mm
    tips = apex + length * matrices[:, :3, 2]
    count = len(rows)
    triangles = [[0, 1 + index, 1 + (index + 1) % count] for index in range(count)]
    solution = solve(robot, t6)
    joints = solution.joints[:, :, posture]
    warnings = solution.warnings[:, posture]
    frames = [answer_frame(row["azimuth_deg"], pose, values, warning, label=_label(row))
              for row, pose, values, warning in zip(rows, pose_from_t6(t6), joints, warnings)]
    return {"surface": {"vertices": [[float(v) for v in point] for point in np.vstack([apex, tips])],
                        "triangles": triangles,
                        "label": f"tilt limits: the tool axis ({abs(length):.0f} mm drawn) at its largest tilt "
                                 "towards each azimuth"},
            "points": [{"position": [float(v) for v in tip], "label": _label(row) if shown else ""}
                       for row, tip, shown in zip(rows, tips, _labelled(rows))],
            "frames": frames}
