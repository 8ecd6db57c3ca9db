"""A calibration drawn in the report's 3D view (kingen.view's scene overlays, plain JSON data,
base frame, mm).

- ``arrows``: each measured pose's residual after calibration, predicted minus measured (what
  the calibrated robot predicts from the read joints, less what the device measured), rotated
  from the device's frame into the base frame by the identified measuring frame, drawn at the
  measured point (the target's origin, in the base frame through the identified measuring
  frame), magnified by one round factor stated in the view's description; the LABELLED longest
  labelled with their measurement's line and length (the rest would hide one another).
- the ghost: the calibrated machine with its geometry changes (limbs, constraints, wrist; not the
  measuring frame or the target) magnified by one round factor stated in its label, so that
  changes of a few hundredths of a millimetre show beside the nominal machine.

A round factor is 1, 2 or 5 times a power of ten, at least 1.
"""

import math

import numpy as np

from ..units import length_text

ARROW_SHARE = 0.1
"""The longest residual arrow is drawn at most this share of the robot's size (robot.size_mm) long."""
LABELLED = 3
"""The residual arrows labelled, the longest."""
GHOST_SHARE = 0.1
"""The ghost's largest magnified change is at most this share of the robot's size (mm, or
mm-equivalents: degrees turned at the robot's size)."""
FRAME_GROUPS = ("frame", "target")
"""Parameter groups that are not the machine's geometry."""


ROUND = (1.0, 2.0, 5.0)
"""A round factor's leading digits."""


def magnification(largest, room):
    """The largest round factor (module docstring) that keeps ``largest`` times it within
    ``room`` (1 when ``largest`` is 0 or not finite, or ``room`` less than ``largest``)."""
    if not np.isfinite(largest) or largest <= 0.0 or room < largest:
        return 1.0
    power = 10.0 ** math.floor(math.log10(room / largest))
    return float(max(digit * power for digit in ROUND if digit * power * largest <= room))


def residual_arrows(problem, values):
    """({"origin", "vector", "label"} per measured pose, factor) for the identification Problem
    ``problem`` (its poses: the outliers left out) at parameter ``values`` (mm, degrees): see
    the module docstring; ``vector`` is the residual (mm, base frame) times ``factor``, the
    ``label`` the measurement's line and the residual's length ("" but for the LABELLED longest)."""
    data = problem.measurements
    predicted, _ = problem.predicted(values)
    frame = problem.parameters.frame(values)
    points = data.measured[:, :3] @ frame[:3, :3].T + frame[:3, 3]
    residuals = (predicted[:, :3] - data.measured[:, :3]) @ frame[:3, :3].T
    sizes = np.linalg.norm(residuals, axis=1)
    factor = magnification(float(np.max(sizes, initial=0.0)), ARROW_SHARE * problem.parameters.robot.size_mm)
    longest = set(np.argsort(-sizes, kind="stable")[:LABELLED].tolist())
    arrows = [{"origin": [float(v) for v in point], "vector": [float(v) * factor for v in residual],
               "label": f"line {line}: {length_text(size)}" if row in longest else ""}
              for row, (point, residual, size, line) in enumerate(zip(points, residuals, sizes, data.lines))]
    return arrows, factor


def magnified_robot(parameters, values):
    """(robot, factor): the robot (calibrate.parameters.Parameters.robot_of) with the nominal
    geometry plus ``factor`` times its identified changes ``values`` - nominal (mm, degrees; the
    measuring frame and the target at nominal), a round factor (module docstring);
    (None, None) when no geometry changed."""
    geometry = ~np.isin(parameters.groups, FRAME_GROUPS)
    change = np.where(geometry, parameters.deviations(values), 0.0)
    largest = float(np.max(np.abs(change), initial=0.0))
    if not largest > 0.0:
        return None, None
    factor = magnification(largest, GHOST_SHARE * parameters.robot.size_mm)
    return parameters.robot_of(parameters.values(change * factor)), factor
