"""Lengths in other units than kingen's mm: a robot file written in metres or inches (``units: m``,
``units: inch``), read into mm once; a machine whose controller works in inches (LinuxCNC's
LINEAR_UNITS), whose module's tables hold the robot's lengths in its units; and numbers written
for people (reports and terminal lines): lengths in mm, um, nm or pm, no exponent, no -0, zero
as 0. Angles stay degrees (files) and radians (inside)."""

import math
from dataclasses import replace

LENGTH_UNITS = {"mm": 1.0, "m": 1000.0, "inch": 25.4}
"""mm per unit of length."""


def _scaled(value, scale):
    return [v * scale for v in value] if isinstance(value, (list, tuple)) else value * scale


def scaled_limbs(limbs, scale):
    """``limbs`` with every length field (:attr:`LimbModel.length_fields`), their parts' centres
    and the travel, top speed and top acceleration of prismatic joints multiplied by ``scale``."""
    converted = []
    for limb in limbs:
        update = {name: _scaled(getattr(limb, name), scale) for name in limb.length_fields}
        if not limb.joint_type.wraps:
            update.update({name: _scaled(getattr(limb, name), scale) for name in ("travel", "max_speed", "max_acceleration")
                           if getattr(limb, name) is not None})
        if limb.parts is not None:
            update["parts"] = limb.parts.scaled(scale)
        converted.append(limb.model_copy(update=update))
    return converted


def document_in_mm(document, limbs, scale):
    """A validated robot file and its limbs with every length (limb geometry, prismatic travel,
    the verification region's position, golden positions, prismatic joints and tolerances, the
    direct-index threshold, collision radii) multiplied by ``scale``, mm per the file's unit. A
    golden tolerance is scaled for robots whose joints are all prismatic (for revolute joints it
    is degrees); model.py refuses golden values in a file that mixes both."""
    prismatic = [not limb.joint_type.wraps for limb in limbs]
    region = document.verification
    region = region.model_copy(update={"home": [*_scaled(region.home[:3], scale), *region.home[3:]],
                                       "range": [*_scaled(region.range[:3], scale), *region.range[3:]]})
    # A golden tolerance is in the joints' units: inches for prismatic, degrees for revolute ones.
    tolerance_scale = scale if all(prismatic) else 1.0
    golden = [entry.model_copy(update={
        "pose": [*_scaled(entry.pose[:3], scale), *entry.pose[3:]],
        "joints": [value * scale if linear else value for value, linear in zip(entry.joints, prismatic)],
        "tolerance": entry.tolerance * tolerance_scale}) for entry in document.golden]
    update = {"verification": region, "golden": golden}
    if document.singularity is not None:
        update["singularity"] = document.singularity.model_copy(
            update={"direct_index_min": document.singularity.direct_index_min * scale})
    if document.collision is not None:
        update["collision"] = document.collision.model_copy(update={
            name: _scaled(value, scale) for name, value in document.collision.model_dump(exclude_none=True).items()})
    return document.model_copy(update=update), scaled_limbs(limbs, scale)


def robot_in_units(robot, units):
    """``robot`` with its lengths (limb geometry, prismatic travel, the direct-index threshold)
    in ``units`` ('mm' or 'inch') instead of mm: what a machine's controller computes with."""
    scale = 1.0 / LENGTH_UNITS[units]
    if scale == 1.0:
        return robot
    minimum = robot.direct_index_min * scale if robot.direct_index_min is not None else None
    return replace(robot, limbs=tuple(scaled_limbs(robot.limbs, scale)), direct_index_min=minimum)


NEGLIGIBLE = 1e-12
"""Magnitudes at or below this (mm or degrees) are written as 0: a thousandth of a picometre,
below the rounding of double precision on a metre-sized machine (about 1e-13 mm)."""

LENGTH_STEPS = (("mm", 1.0), ("um", 1e-3), ("nm", 1e-6), ("pm", 1e-9))
"""The units a length is written in, mm each: the first in which it reads at least 0.1."""


def number_text(value, digits=3, zero=NEGLIGIBLE):
    """``value`` written without an exponent: rounded to ``digits`` significant digits, or to a
    whole number when it has more digits before the point (``0.000123``, ``7.3``, ``1235``),
    trailing zeros dropped; ``0`` when its magnitude is at most ``zero`` (never ``-0``);
    ``nan``, ``inf`` and ``-inf`` as such."""
    value = float(value)
    if not math.isfinite(value):
        return str(value)
    if abs(value) <= zero:
        return "0"
    decimals = max(digits - 1 - math.floor(math.log10(abs(value))), 0)
    text = f"{round(value, decimals) + 0.0:.{decimals}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def fixed_text(value, decimals, sign=False):
    """``value`` with ``decimals`` decimals, for columns that line up; a value that rounds to
    zero is written as zero, never ``-0.000000``; ``sign``: a ``+`` before positive values
    and zero."""
    rounded = round(float(value), decimals) + 0.0  # -0.0 + 0.0 is 0.0
    return f"{rounded:{'+' if sign else ''}.{decimals}f}"


def length_text(mm, digits=3):
    """A length given in mm, written for people with its unit: in the first of mm, um, nm and
    pm in which it reads at least 0.1 (0.5 mm, 7.28 um, 0.73 nm, 1235 mm), as number_text
    writes it; ``0 mm`` at or below NEGLIGIBLE."""
    mm = float(mm)
    if not math.isfinite(mm) or abs(mm) <= NEGLIGIBLE:
        return f"{number_text(mm, digits)} mm"
    unit, scale = next(((unit, scale) for unit, scale in LENGTH_STEPS if abs(mm) / scale >= 0.1), LENGTH_STEPS[-1])
    return f"{number_text(mm / scale, digits)} {unit}"


def travel_ends(lower, upper, factor):
    """A joint's travel for people and pages: [lower, upper] (``lower`` and ``upper`` in the
    routine's units, mm or rad, times ``factor``: mm, or degrees), a side without a limit
    (-inf or +inf) as None; None when neither side is limited."""
    ends = [float(end * factor) if math.isfinite(end) else None for end in (lower, upper)]
    return None if ends == [None, None] else ends
