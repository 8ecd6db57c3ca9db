"""Robot definitions: load a YAML file, validate it once, expand layouts.

``load_robot(spec)`` is the only entry point the other modules need. It returns
a frozen :class:`Robot` or raises one :class:`~kingen.errors.KingenError` whose
message names the file, the line, the field and the problem. Geometry in the
YAML is in mm and degrees (see :mod:`kingen.conventions`); the Robot exposes
travel limits in internal units (mm, radians).
"""

import hashlib
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Annotated, ClassVar, Literal, Optional, Union

import numpy as np
from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError, field_validator

from . import abi
from .errors import KingenError, located
from .resources import robots_dir
from .robot_file import dotted, read_robot_file

MAX_MM = 1e6
"""Coordinates and lengths are within +/- 1 km (mm): the stated geometry range, inside which
double precision keeps plugin and reference within verify's bound (see verify.value_tolerance_mm)."""
MIN_LENGTH_MM = 1e-3
MAX_DEGREES = 720.0
"""Angles in robot files (directions, offsets, poses) are within +/- two turns."""
MAX_GOLDEN = 1000
MAX_LIMBS = 64
MAX_TWO_BRANCH_LIMBS = 8
"""At most 2**8 = 256 postures: the solutions array is NUM_DOFS x NUM_SOLUTIONS doubles."""
UNIT_TOLERANCE = 1e-6
"""How far from 1 the norm of a declared direction may be; it is then normalised exactly."""

PRISMATIC = "prismatic"
REVOLUTE = "revolute"


def _check_c_names(name):
    """The robot's own name may be anything identifier-shaped ('int' gives kin_int); the C
    names made from it must not collide with a C keyword or a name the vendor header defines."""
    for made in (f"kin_{name}", f"lib{name}"):
        if made in abi.RESERVED_NAMES:
            raise ValueError(f"gives the C name '{made}', which the DELMIA header or the C language already uses")
    return name


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


def _check_non_negative(values):
    if any(value < 0 for value in values):
        raise ValueError("ranges must not be negative")
    return values


Identifier = Annotated[str, Field(pattern=r"^[A-Za-z_][A-Za-z0-9_]{0,62}$")]
Coordinate = Annotated[float, Field(ge=-MAX_MM, le=MAX_MM)]
"""mm, or for travel limits of revolute joints degrees."""
Angle = Annotated[float, Field(ge=-MAX_DEGREES, le=MAX_DEGREES)]
Vec3 = Annotated[list[Coordinate], Field(min_length=3, max_length=3)]
UnitVec3 = Annotated[Vec3, AfterValidator(_check_unit)]
Pose = Annotated[list[float], Field(min_length=6, max_length=6), AfterValidator(_check_pose)]
SixAngles = Annotated[list[Angle], Field(min_length=6, max_length=6)]
Length = Annotated[float, Field(ge=MIN_LENGTH_MM, le=MAX_MM)]
Travel = Annotated[list[Coordinate], Field(min_length=2, max_length=2), AfterValidator(_check_travel)]
DialogField = Annotated[str, Field(pattern=r"^(length|offset)[1-6]$")]
"""A Solver Attributes field: length1..length6 (link_lengths[0..5]), offset1..offset6 (link_offsets[0..5])."""


def field_index(dialog_field):
    """length1..6 -> 0..5, offset1..6 -> 6..11: the encoding the generated C uses."""
    number = int(dialog_field[-1]) - 1
    return number if dialog_field.startswith("length") else 6 + number


def dialog_label(dialog_field):
    """length3 -> 'Length 3', as the Solver Attributes tab labels it."""
    return f"{dialog_field[:-1].capitalize()} {dialog_field[-1]}"


def calibration_unit(parameter):
    """The unit a dialog value for ``parameter`` is read in: degrees for zero_offset, else mm."""
    return "degrees" if parameter == "zero_offset" else "mm"


def dialog_value(dialog_field, link_lengths, link_offsets):
    """The number the user typed into that field (0 when left empty)."""
    index = field_index(dialog_field)
    values = link_lengths if index < 6 else link_offsets
    return 0.0 if values is None else float(values[index % 6])


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, frozen=True, allow_inf_nan=False)


class _Limb(_Strict):
    name: Optional[Identifier] = None
    travel: Optional[Travel] = None
    """[lower, upper] in mm (prismatic) or degrees (revolute); absent: no limits."""
    calibrate: dict[str, DialogField] = {}
    """Parameter -> dialog field read at run time; a zero field keeps the built-in value."""
    calibratable: ClassVar[tuple] = ()

    @field_validator("calibrate")
    @classmethod
    def _check_calibratable(cls, calibrate):
        for parameter in calibrate:
            if parameter not in cls.calibratable:
                raise ValueError(f"'{parameter}' cannot be calibrated on a {cls.__name__.lower()} "
                                 f"(choose from {', '.join(cls.calibratable)})")
        return calibrate


class Leg(_Limb):
    """S-P-S / U-P-S leg: q = |R t + p - b| - L0 (mm). One branch."""

    model: Literal["leg"]
    base_point: Vec3
    platform_point: Vec3
    reference_length: Length
    branches: ClassVar[int] = 1
    joint_type: ClassVar[str] = PRISMATIC
    calibratable: ClassVar[tuple] = ("reference_length",)
    length_fields: ClassVar[tuple] = ("base_point", "platform_point", "reference_length")


class Rail(_Limb):
    """P-S-S carriage on a rail: q = u.w -/+ sqrt(l^2 - |w|^2 + (u.w)^2) (mm). Two branches."""

    model: Literal["rail"]
    rail_point: Vec3
    direction: UnitVec3
    carriage_offset: Vec3
    platform_point: Vec3
    link_length: Length
    origin: Coordinate = 0.0
    """Carriage position reported as 0 (mm along the direction from rail_point): q -= origin."""
    branches: ClassVar[int] = 2
    joint_type: ClassVar[str] = PRISMATIC
    calibratable: ClassVar[tuple] = ("origin", "link_length")
    length_fields: ClassVar[tuple] = ("rail_point", "carriage_offset", "platform_point", "link_length", "origin")


class Crank(_Limb):
    """R-U-S crank: theta = phi +/- acos(K / rho) (radians). Two branches.

    ``crank_direction`` (beta) is in degrees in the YAML.
    """

    model: Literal["crank"]
    pivot: Vec3
    crank_direction: Angle
    crank_length: Length
    rod_length: Length
    platform_point: Vec3
    zero_offset: Angle = 0.0
    """Geometric crank angle (degrees) reported as joint 0: theta -= zero_offset."""
    branches: ClassVar[int] = 2
    joint_type: ClassVar[str] = REVOLUTE
    calibratable: ClassVar[tuple] = ("zero_offset", "crank_length", "rod_length")
    length_fields: ClassVar[tuple] = ("pivot", "crank_length", "rod_length", "platform_point")


Limb = Annotated[Union[Leg, Rail, Crank], Field(discriminator="model")]


class _Layout(_Strict):
    """A generator of six limbs of one model; ``calibrate`` maps a parameter to six fields."""

    travel: Optional[Travel] = None
    calibrate: dict[str, Annotated[list[DialogField], Field(min_length=6, max_length=6)]] = {}
    limb_class: ClassVar[type] = None

    @field_validator("calibrate")
    @classmethod
    def _check_calibratable(cls, calibrate):
        for parameter in calibrate:
            if parameter not in cls.limb_class.calibratable:
                raise ValueError(f"'{parameter}' cannot be calibrated "
                                 f"(choose from {', '.join(cls.limb_class.calibratable)})")
        return calibrate

    def _shared(self, index):
        """The keys every generated limb takes from the layout: travel and its calibration fields."""
        return {"travel": self.travel,
                "calibrate": {parameter: fields[index] for parameter, fields in self.calibrate.items()}}


class StewartGoughLayout(_Layout):
    """Six legs on the controller thesis's parametric layout (points at z = heights)."""

    type: Literal["stewart_gough"]
    base_radius: Length
    platform_radius: Length
    base_pair_angle: Annotated[float, Field(gt=0, lt=120)]
    platform_pair_angle: Annotated[float, Field(gt=0, lt=120)]
    base_height: Coordinate = 0.0
    platform_height: Coordinate = 0.0
    reference_length: Length
    limb_class: ClassVar[type] = Leg

    def limbs(self):
        """The six legs; point angles lambda_1 = 60 - pair/2, lambda_2 = lambda_1 + pair, ... (degrees)."""
        legs = []
        for index in range(6):
            pair, second = divmod(index, 2)
            centre = 60.0 + 120.0 * pair
            base_angle = math.radians(centre + (second - 0.5) * self.base_pair_angle)
            platform_angle = math.radians(centre + (second - 0.5) * self.platform_pair_angle)
            legs.append(Leg(
                model="leg",
                name=f"leg{index + 1}",
                base_point=[self.base_radius * math.cos(base_angle),
                            self.base_radius * math.sin(base_angle), self.base_height],
                platform_point=[self.platform_radius * math.cos(platform_angle),
                                self.platform_radius * math.sin(platform_angle), self.platform_height],
                reference_length=self.reference_length,
                **self._shared(index),
            ))
        return legs


class Rus6Layout(_Layout):
    """Six cranks on the 6-RUS flight-simulator layout (robots.md, '6-RUS family')."""

    type: Literal["rus6"]
    base_radius: Length
    platform_radius: Length
    base_half_distance: Annotated[float, Field(ge=0, le=MAX_MM)]
    platform_half_distance: Annotated[float, Field(ge=0, le=MAX_MM)]
    crank_length: Length
    rod_length: Length
    pair_angles: SixAngles
    crank_directions: SixAngles
    limb_class: ClassVar[type] = Crank

    def limbs(self):
        """The six cranks: A_i and c_i from chi_i with m, n = (-1)^(i-1) times the half-distances."""
        cranks = []
        for index, (chi_deg, beta) in enumerate(zip(self.pair_angles, self.crank_directions)):
            chi = math.radians(chi_deg)
            sign = 1.0 if index % 2 == 0 else -1.0
            m, n = sign * self.base_half_distance, sign * self.platform_half_distance
            cranks.append(Crank(
                model="crank",
                name=f"crank{index + 1}",
                pivot=[self.base_radius * math.cos(chi) - m * math.sin(chi),
                       self.base_radius * math.sin(chi) + m * math.cos(chi), 0.0],
                crank_direction=beta,
                crank_length=self.crank_length,
                rod_length=self.rod_length,
                platform_point=[self.platform_radius * math.cos(chi) - n * math.sin(chi),
                                self.platform_radius * math.sin(chi) + n * math.cos(chi), 0.0],
                **self._shared(index),
            ))
        return cranks


Layout = Annotated[Union[StewartGoughLayout, Rus6Layout], Field(discriminator="type")]


class Region(_Strict):
    """Verification region: poses drawn uniformly in home +/- range (mm, degrees)."""

    home: Pose
    range: Annotated[Pose, AfterValidator(_check_non_negative)]


class Golden(_Strict):
    """A published (or independently derived) pose -> joints pair, with its source."""

    source: Annotated[str, Field(min_length=1)]
    pose: Pose
    posture: Annotated[int, Field(ge=0)] = 0
    joints: Annotated[list[Coordinate], Field(max_length=MAX_LIMBS)]
    """mm for prismatic joints, degrees for revolute joints."""
    tolerance: Annotated[float, Field(gt=0, le=MAX_MM)]
    """In the units of ``joints``: half a unit of the last published digit is typical."""


class RobotFile(_Strict):
    """The YAML schema; documented field by field in README.md ('Robot definitions')."""

    name: Annotated[Identifier, AfterValidator(_check_c_names)]
    description: Annotated[str, Field(min_length=1)]
    source: Optional[str] = None
    limbs: Optional[Annotated[list[Limb], Field(min_length=1, max_length=MAX_LIMBS)]] = None
    layout: Optional[Layout] = None
    verification: Region
    golden: Annotated[list[Golden], Field(max_length=MAX_GOLDEN)] = []


@dataclass(frozen=True)
class Robot:
    """A validated robot. Limbs are in joint order: limb i drives solutions row i."""

    name: str
    description: str
    path: Path
    sha256: str
    limbs: tuple
    verification: Region
    golden: tuple

    @property
    def routine(self):
        return f"kin_{self.name}"

    @property
    def library(self):
        return f"lib{self.name}"

    @property
    def dof(self):
        return len(self.limbs)

    @property
    def branch_bits(self):
        """Per limb: its binary digit in the posture number (most significant first), or -1."""
        two_branch = [i for i, limb in enumerate(self.limbs) if limb.branches == 2]
        bits = [-1] * self.dof
        for rank, index in enumerate(two_branch):
            bits[index] = len(two_branch) - 1 - rank
        return tuple(bits)

    @property
    def postures(self):
        return 2 ** sum(1 for bit in self.branch_bits if bit >= 0)

    @property
    def joint_names(self):
        return tuple(limb.name or f"joint{i + 1}" for i, limb in enumerate(self.limbs))

    @property
    def joint_types(self):
        return tuple(limb.joint_type for limb in self.limbs)

    @property
    def models(self):
        return tuple(dict.fromkeys(limb.model for limb in self.limbs))

    def travel_limits(self):
        """(lower, upper) arrays in internal units (mm, rad); -inf/+inf where no limit is set."""
        lower = np.full(self.dof, -np.inf)
        upper = np.full(self.dof, np.inf)
        for i, limb in enumerate(self.limbs):
            if limb.travel is not None:
                scale = math.pi / 180.0 if limb.joint_type == REVOLUTE else 1.0
                lower[i], upper[i] = limb.travel[0] * scale, limb.travel[1] * scale
        return lower, upper

    def calibration(self):
        """Per calibrated parameter: (joint index, parameter, dialog field, built-in value in YAML units)."""
        return [
            (index, parameter, dialog_field, getattr(limb, parameter))
            for index, limb in enumerate(self.limbs)
            for parameter, dialog_field in limb.calibrate.items()
        ]

    def calibrated(self, link_lengths=None, link_offsets=None):
        """This robot with the dialog's values applied: a zero or non-finite field keeps the
        built-in value, any other replaces it (mm, or degrees for a crank's zero_offset)."""
        limbs = list(self.limbs)
        for index, parameter, dialog_field, _ in self.calibration():
            value = dialog_value(dialog_field, link_lengths, link_offsets)
            if value != 0.0 and math.isfinite(value):
                limbs[index] = limbs[index].model_copy(update={parameter: value})
        return replace(self, limbs=tuple(limbs))

    @property
    def size_mm(self):
        """The largest magnitude of any length or coordinate of the robot and its verification
        region, mm: the scale floating-point rounding is relative to."""
        values = [abs(h) + abs(r) for h, r in zip(self.verification.home[:3], self.verification.range[:3])]
        for limb in self.limbs:
            for name in limb.length_fields:
                value = getattr(limb, name)
                values.extend(abs(v) for v in (value if isinstance(value, list) else [value]))
        return max(values)

    @property
    def revolute(self):
        """(dof,) bool: which joints are revolute (compared modulo 2 pi)."""
        return np.array([t == REVOLUTE for t in self.joint_types])

    def joint_scale(self):
        """Per joint: factor from YAML units (mm, degrees) to internal units (mm, radians)."""
        return np.array([math.pi / 180.0 if t == REVOLUTE else 1.0 for t in self.joint_types])


def shipped_robots():
    """Names of the shipped robots, sorted."""
    return sorted(path.stem for path in robots_dir().glob("*.yaml"))


def resolve_robot_path(spec):
    """A YAML path as given, or the shipped robot of that name."""
    path = Path(spec)
    if path.is_file():
        return path
    shipped = robots_dir() / f"{spec}.yaml"
    if path.suffix == "" and shipped.is_file():
        return shipped
    raise KingenError(
        f"{spec}: no such robot file, and no shipped robot of that name "
        f"(shipped: {', '.join(shipped_robots())})"
    )


def load_robot(spec):
    """Load, validate and expand a robot definition (path or shipped name)."""
    path = resolve_robot_path(spec)
    shown = str(path)
    data, lines, raw = read_robot_file(path)
    locate = _Locator(shown, lines)
    try:
        document = RobotFile.model_validate(data)
    except ValidationError as error:
        raise _diagnostic(error, locate) from None
    limbs = _expand_limbs(document, locate)
    robot = Robot(
        name=document.name,
        description=document.description,
        path=path,
        sha256=hashlib.sha256(raw).hexdigest(),
        limbs=tuple(limbs),
        verification=document.verification,
        golden=tuple(document.golden),
    )
    _check_golden(robot, locate)
    return robot


class _Locator:
    """Turns a field path into 'file:line: field: problem' using the YAML's key lines."""

    def __init__(self, source, lines):
        self.source = source
        self.lines = lines

    def error(self, path, problem):
        line = None
        for cut in range(len(path), -1, -1):
            if tuple(path[:cut]) in self.lines:
                line = self.lines[tuple(path[:cut])]
                break
        return located(self.source, line, dotted(path), problem)


_UNION_TAGS = {"leg", "rail", "crank", "stewart_gough", "rus6"}
_FRIENDLY = {"extra_forbidden": "unknown key", "missing": "required key missing"}


def _diagnostic(error, locate):
    """The first pydantic error as a located one-line KingenError."""
    first = error.errors(include_url=False)[0]
    path = []
    for part in first["loc"]:
        if isinstance(part, str) and part in _UNION_TAGS and path and (
            isinstance(path[-1], int) or path[-1] == "layout"
        ):
            continue
        path.append(part)
    if first["type"] in ("union_tag_invalid", "union_tag_not_found"):
        path.append(first["ctx"]["discriminator"].strip("'"))
    problem = _FRIENDLY.get(first["type"], first["msg"])
    if problem.startswith("Value error, "):
        problem = problem[len("Value error, "):]
    value = first.get("input")
    if first["type"] not in _FRIENDLY and not isinstance(value, (dict, list)) and len(repr(value)) < 40:
        problem += f" (got {value!r})"
    return locate.error(path, problem)


def _expand_limbs(document, locate):
    if (document.limbs is None) == (document.layout is None):
        raise locate.error(["limbs"], "give exactly one of 'limbs' and 'layout'")
    limbs = document.limbs if document.limbs is not None else document.layout.limbs()
    names = [limb.name or f"joint{i + 1}" for i, limb in enumerate(limbs)]
    for index, name in enumerate(names):
        if names.index(name) != index:
            raise locate.error(["limbs", index, "name"], f"joint name '{name}' is used twice")
    used = {}
    for index, limb in enumerate(limbs):
        for parameter, dialog_field in limb.calibrate.items():
            if dialog_field in used:
                raise locate.error(["limbs", index, "calibrate", parameter],
                                   f"dialog field {dialog_field} is already read for {used[dialog_field]}")
            used[dialog_field] = f"{names[index]}.{parameter}"
    two_branch = sum(1 for limb in limbs if limb.branches == 2)
    if two_branch > MAX_TWO_BRANCH_LIMBS:
        raise locate.error(
            ["limbs"], f"{two_branch} two-branch limbs; at most {MAX_TWO_BRANCH_LIMBS} (256 postures)"
        )
    return limbs


def _check_golden(robot, locate):
    for index, golden in enumerate(robot.golden):
        if len(golden.joints) != robot.dof:
            raise locate.error(
                ["golden", index, "joints"], f"expected {robot.dof} joint values, got {len(golden.joints)}"
            )
        if golden.posture >= robot.postures:
            raise locate.error(
                ["golden", index, "posture"],
                f"posture {golden.posture} does not exist (the robot has {robot.postures})",
            )
