"""The field types robot files are made of, with their ranges, shared by every schema.

Units: mm for lengths and coordinates, degrees for angles (see docs/explanation/conventions.md).
The ranges are the stated geometry range of docs/reference/limits.md.
"""

import math
from typing import Annotated

from pydantic import AfterValidator, BaseModel, ConfigDict, Field

from ..defaults import MAX_MM

MIN_LENGTH_MM = 1e-3
MAX_DEGREES = 720.0
"""Angles in robot files (directions, offsets, poses) are within +/- two turns."""
UNIT_TOLERANCE = 2e-4
"""How far from 1 the norm of a declared direction may be; it is then normalised exactly. A unit
vector written to 4 decimals (each component within 5e-5) has a norm within 1e-4 of 1."""


def _check_pose(pose):
    if any(abs(value) > MAX_MM for value in pose[:3]) or any(abs(value) > MAX_DEGREES for value in pose[3:]):
        raise ValueError(f"x, y, z must be within +/-{MAX_MM:g} mm and angles within +/-{MAX_DEGREES:g} degrees")
    return pose


def _check_travel(travel):
    if not travel[0] < travel[1]:
        raise ValueError(f"lower limit {travel[0]} must be below upper limit {travel[1]}")
    return travel


def _check_unit(vector):
    norm = math.sqrt(sum(component * component for component in vector))
    if norm == 0.0:
        raise ValueError("direction is the zero vector")
    if abs(norm - 1.0) > UNIT_TOLERANCE:
        raise ValueError(f"direction must be a unit vector, its norm is {norm:.9g}")
    return [component / norm for component in vector]


MAX_NAME = 63
"""Characters in a robot's or joint's name at most."""
Identifier = Annotated[str, Field(pattern=rf"^[A-Za-z_][A-Za-z0-9_]{{0,{MAX_NAME - 1}}}$")]
Coordinate = Annotated[float, Field(ge=-MAX_MM, le=MAX_MM)]
"""mm, or for travel limits of revolute joints degrees."""
Angle = Annotated[float, Field(ge=-MAX_DEGREES, le=MAX_DEGREES)]
Vec3 = Annotated[list[Coordinate], Field(min_length=3, max_length=3)]
UnitVec3 = Annotated[Vec3, AfterValidator(_check_unit)]
Pose = Annotated[list[float], Field(min_length=6, max_length=6), AfterValidator(_check_pose)]
SixAngles = Annotated[list[Angle], Field(min_length=6, max_length=6)]
Length = Annotated[float, Field(ge=MIN_LENGTH_MM, le=MAX_MM)]
ReferenceLength = Annotated[float, Field(ge=-MAX_MM, le=MAX_MM)]
"""A leg's length at joint value 0 (mm), signed: 0 makes the joint the leg's absolute length, and
near 0 it is that encoder's offset (a joint that reads 0.26 mm more than the length: -0.26)."""
Travel = Annotated[list[Coordinate], Field(min_length=2, max_length=2), AfterValidator(_check_travel)]
PositiveRate = Annotated[float, Field(gt=0, le=MAX_MM)]
"""A joint's top speed or acceleration: mm/s or degrees/s (per s for an acceleration), above 0."""
CalibrationField = Annotated[str, Field(pattern=r"^(length|offset)[1-6]$")]
"""A calibration field, read by the routine at run time: length1..length6 (link_lengths[0..5]),
offset1..offset6 (link_offsets[0..5]). A host names them in its own words
(kingen.hosts.base.Host.calibration_label)."""
CALIBRATION_FIELDS = tuple(f"{kind}{number}" for kind in ("length", "offset") for number in range(1, 7))
"""Every calibration field, in the order of :func:`calibration_index`."""


def calibration_index(field):
    """length1..6 -> 0..5, offset1..6 -> 6..11: the encoding the generated C uses."""
    number = int(field[-1]) - 1
    return number if field.startswith("length") else 6 + number


def calibration_value(field, link_lengths, link_offsets):
    """The number given for that field (0 when none is given): link_lengths[i] for length i+1,
    link_offsets[i] for offset i+1."""
    index = calibration_index(field)
    values = link_lengths if index < 6 else link_offsets
    return 0.0 if values is None else float(values[index % 6])


class Strict(BaseModel):
    """Every schema object: unknown keys refused, no type coercion, immutable, finite numbers."""

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True, allow_inf_nan=False)


