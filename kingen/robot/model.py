"""Robot definitions: validate a robot file once, expand layouts, answer questions about it.

``load_robot(spec)`` is the only entry point the other modules need. It returns
a frozen :class:`Robot` or raises one :class:`~kingen.errors.KingenError` whose
message names the file, the line, the field and the problem. Geometry in the
YAML is in mm and degrees (docs/explanation/conventions.md); the Robot exposes travel limits
in internal units (mm, radians). Limb models come from :mod:`kingen.robot.limbs`.
"""

import functools
import hashlib
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Annotated, Literal, Optional, Union

import numpy as np
from pydantic import AfterValidator, Field, ValidationError

from ..conventions import SIX, branch_of_posture
from .design_schema import Optimize
from ..errors import KingenError
from ..runtime.file_gate import refuse_special_file
from .layouts import Layout
from .constraints import check_coordinates
from .located import Locator, diagnostic
from .passive_leg import PassiveLegFile, passive_leg_of
from .wrist import refuse_wrist
from .limbs import MODELS
from ..runtime.resources import robots_dir
from .reading import read_robot_file
from .schema import MAX_MM, Coordinate, Identifier, Length, Pose, Strict, calibration_value
from ..units import LENGTH_UNITS, document_in_mm

MAX_GOLDEN = 1000
MAX_LIMBS = 64
MAX_TWO_BRANCH_LIMBS = 8
"""At most 2**8 = 256 postures: the solutions array is NUM_DOFS x NUM_SOLUTIONS doubles."""

NAME_CHECKS = {}
"""How each host judges the names it makes from a robot's name: host name -> function (robot
name -> why it cannot be used, or None). kingen.hosts fills it as hosts register, so that
reading a robot file asks every host without knowing any."""


def _check_c_names(name):
    """The robot's own name may be anything identifier-shaped ('int' gives kin_int); the names
    every registered host makes from it must not collide with what that host or C reserves."""
    problems = [problem for check in NAME_CHECKS.values() if (problem := check(name))]
    if problems:
        raise ValueError("; ".join(problems))
    return name


def _check_non_negative(values):
    if any(value < 0 for value in values):
        raise ValueError("ranges must not be negative")
    return values


class Region(Strict):
    """Verification region: poses drawn uniformly in home +/- range (mm, degrees)."""

    home: Pose
    range: Annotated[Pose, AfterValidator(_check_non_negative)]


class Golden(Strict):
    """A published (or independently derived) pose -> joints pair, with its source."""

    source: Annotated[str, Field(min_length=1)]
    pose: Pose
    posture: Annotated[int, Field(ge=0)] = 0
    joints: Annotated[list[Coordinate], Field(max_length=MAX_LIMBS)]
    """mm for prismatic joints, degrees for revolute joints."""
    tolerance: Annotated[float, Field(gt=0, le=MAX_MM)]
    """In the units of ``joints``: half a unit of the last published digit is typical."""


class Singularity(Strict):
    """``singularity:`` in a robot file: when to call a pose a direct singularity."""

    direct_index_min: Length
    """mm: postures whose direct index is at most this answer WARN_SINGULAR_SOLUTION."""


class Forward(Strict):
    """``forward:`` in a robot file: which pose coordinates forward kinematics solves for."""

    free: Annotated[list[Literal["x", "y", "z", "roll", "pitch", "yaw"]], Field(min_length=1, max_length=6)]


class Collision(Strict):
    """``collision:`` in a robot file: radii (mm) of the cylinders passive links and cranks
    are modelled as; analyze reports clearances below them as collisions."""

    leg_radius: Optional[Length] = None
    rod_radius: Optional[Length] = None
    crank_radius: Optional[Length] = None


def robot_file_schema():
    """The YAML schema over the registered limb models (built anew when the registry changed);
    documented field by field in docs/how-to/robot-files.md."""
    return _schema_over(tuple(MODELS.values()))


@functools.lru_cache(maxsize=None)
def _schema_over(models):
    limb = Annotated[Union[models], Field(discriminator="model")]

    class RobotFile(Strict):
        name: Annotated[Identifier, AfterValidator(_check_c_names),
                        Field(description="The robot's name; each host makes its C names from it.")]
        description: Annotated[str, Field(min_length=1, description="What the robot is, in a sentence.")]
        source: Optional[str] = Field(None, description="Where the geometry comes from (a drawing, a paper).")
        limbs: Optional[Annotated[list[limb], Field(min_length=1, max_length=MAX_LIMBS)]] = Field(
            None, description="The limbs, one joint each, in joint order (or give a `layout`).")
        layout: Optional[Layout] = Field(None, description="A parametric layout that makes the limbs.")
        verification: Region = Field(description="The region verify draws its poses from, around a home pose.")
        golden: Annotated[list[Golden], Field(max_length=MAX_GOLDEN)] = Field(
            [], description="Published pose-to-joints pairs every routine must reproduce.")
        singularity: Optional[Singularity] = Field(None, description="When a pose counts as a direct singularity.")
        forward: Optional[Forward] = Field(None, description="The pose coordinates forward kinematics solves for.")
        task: Optional[list[Literal["x", "y", "z", "roll", "pitch", "yaw"]]] = Field(
            None, description="A lower-mobility machine's task coordinates: [z, roll, pitch] (x, y, yaw follow) or "
                  "[x, y, z] (roll, pitch, yaw follow).")
        passive_leg: Optional[PassiveLegFile] = Field(None, description="A passive constraining leg (universal "
                                                      "joint, prismatic joint, fixed to the platform): task [x, y, z].")
        working_posture: Annotated[int, Field(ge=0)] = Field(
            0, description="The posture a host with one answer per pose (LinuxCNC) uses.")
        collision: Optional[Collision] = Field(None, description="The radii `kingen analyze` checks clearances with.")
        units: Literal["mm", "inch"] = Field("mm", description="The file's length unit.")
        optimize: Optional[Optimize] = Field(None, description="The design problem `kingen optimize` searches.")

    return RobotFile


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
    direct_index_min: Optional[float] = None
    """mm, or None: no direct-singularity warning."""
    working_posture: int = 0
    """The assembly mode the machine is built in (analyze's default posture)."""
    working_posture_given: bool = False
    """Whether the robot file names it (a host with one answer needs it named)."""
    length_unit: str = "mm"
    """The unit the robot file's lengths are written in ('mm' or 'inch'); the Robot holds mm."""
    left_out: tuple = ()
    """What a view of the robot (kingen.robot.one_posture) leaves unchecked, in words: verify's notices."""
    collision: Optional[dict] = None
    """{leg_radius, rod_radius, crank_radius} (mm) given in the robot file, or None."""
    forward_free: tuple = ()
    """The pose coordinates forward kinematics solves for; empty: all six."""
    task: tuple = ()
    """A constrained machine's task coordinates (kingen.robot.constraints); empty: none."""
    parasitic_given: bool = True
    """Whether its routine reads a T6's x, y and yaw (then a T6 off the machine's manifold is
    unreachable); False: a host that reads the task coordinates only (LinuxCNC)."""
    passive_leg: Optional[object] = None
    """The passive constraining leg (kingen.robot.passive_leg.PassiveLeg, mm), or None."""
    lines: tuple = ()
    """((field path, 1-based line) ...) of the robot file, for reports that point at it."""

    def line_of(self, *path):
        """The robot file's line of the field at ``path`` (or of its nearest parent), else 1."""
        lines = dict(self.lines)
        for cut in range(len(path), 0, -1):
            if tuple(path[:cut]) in lines:
                return lines[tuple(path[:cut])]
        return 1

    @property
    def has_forward(self):
        """Whether forward kinematics is defined: six limbs, or free coordinates declared."""
        return self.dof == 6 or bool(self.forward_free)

    @property
    def has_direct_index(self):
        """Whether the direct index is defined: six force lines, one per platform DOF. Robots
        with fewer limbs have constraints kingen does not model (Exechon, Gantry-Tau)."""
        return self.dof == SIX

    @property
    def dof(self):
        return len(self.limbs)

    @functools.cached_property
    def branch_bits(self):
        """Per limb: its binary digit in the posture number (most significant first), or -1
        (computed once: a Robot is frozen)."""
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
                scale = limb.joint_type.yaml_scale
                lower[i], upper[i] = limb.travel[0] * scale, limb.travel[1] * scale
        return lower, upper

    def calibration(self):
        """Per calibrated parameter: (joint index, parameter, calibration field, built-in value in
        YAML units)."""
        return [
            (index, parameter, field, getattr(limb, parameter))
            for index, limb in enumerate(self.limbs)
            for parameter, field in limb.calibrate.items()
        ]

    def calibrated(self, link_lengths=None, link_offsets=None):
        """This robot with the calibration fields' values applied (``link_lengths`` and
        ``link_offsets``, 6 each or None): a zero or non-finite field keeps the
        built-in value, any other replaces it (mm, or degrees for a crank's zero_offset)."""
        limbs = list(self.limbs)
        for index, parameter, field, _ in self.calibration():
            value = calibration_value(field, link_lengths, link_offsets)
            if value != 0.0 and math.isfinite(value):
                limbs[index] = limbs[index].model_copy(update={parameter: value})
        return replace(self, limbs=tuple(limbs))

    @functools.cached_property
    def size_mm(self):
        """The largest magnitude of any length or coordinate of the robot and its verification
        region, mm: the scale floating-point rounding is relative to (computed once: a Robot is
        frozen)."""
        values = [abs(h) + abs(r) for h, r in zip(self.verification.home[:3], self.verification.range[:3])]
        for limb in self.limbs:
            for name in limb.length_fields:
                value = getattr(limb, name)
                values.extend(abs(v) for v in (value if isinstance(value, list) else [value]))
        return max(values)

    @property
    def revolute(self):
        """(dof,) bool: which joints are angles (compared modulo 2 pi)."""
        return np.array([t.wraps for t in self.joint_types])

    def joint_scale(self):
        """Per joint: factor from YAML units (mm, degrees) to internal units (mm, radians)."""
        return np.array([t.yaml_scale for t in self.joint_types])

    def posture_branches(self, posture):
        """Per limb: the branch (0 or 1) it takes in ``posture``; 0 for one-branch limbs."""
        return tuple(int(branch_of_posture(posture, bit)) if bit >= 0 else 0 for bit in self.branch_bits)


def shipped_robots():
    """Names of the shipped robots, sorted."""
    return sorted(path.stem for path in robots_dir().glob("*.yaml"))


def resolve_robot_path(spec):
    """A YAML path as given, or the shipped robot of that name; else KingenError, which says
    so when the path is a FIFO, device or folder (never opened)."""
    path = Path(spec)
    if path.is_file():
        return path
    shipped = robots_dir() / f"{spec}.yaml"
    if path.suffix == "" and shipped.is_file():
        return shipped
    refuse_special_file(path)
    raise KingenError(
        f"{spec}: no such robot file, and no shipped robot of that name "
        f"(shipped: {', '.join(shipped_robots())})"
    )


def load_robot(spec):
    """Load, validate and expand a robot definition (path or shipped name)."""
    return load_robot_and_data(spec)[0]


def load_robot_and_data(spec):
    """(robot, data, lines): the robot of :func:`load_robot` with the plain data and the
    {field path tuple: 1-based line} of its file (kingen.robot.reading.read_robot_file), the
    file read once: what a design problem is built from beside the robot."""
    path = resolve_robot_path(spec)
    data, lines, raw = read_robot_file(path)
    return robot_from_data(data, path, lines, raw), data, lines


def robot_from_data(data, path, lines=None, raw=None):
    """Validate and expand a robot definition given as plain data (as read from ``path``,
    which errors name, with its ``lines`` and ``raw`` bytes; the data's JSON when not given)."""
    if raw is None:
        raw = json.dumps(data, sort_keys=True).encode()
    lines = lines or {}
    locate = Locator(str(path), lines)
    refuse_wrist(data, locate)
    try:
        document = robot_file_schema().model_validate(data)
    except ValidationError as error:
        raise diagnostic(error, locate) from None
    limbs = _expand_limbs(document, locate)
    if document.units != "mm":
        if document.golden and len({limb.joint_type.wraps for limb in limbs}) > 1:
            raise locate.error(["golden"], f"a golden tolerance is one number: with prismatic and revolute joints "
                                           f"in a file in {document.units}, write the file in mm")
        document, limbs = document_in_mm(document, limbs, LENGTH_UNITS[document.units])
    robot = Robot(
        name=document.name,
        description=document.description,
        path=path,
        sha256=hashlib.sha256(raw).hexdigest(),
        limbs=tuple(limbs),
        verification=document.verification,
        golden=tuple(document.golden),
        direct_index_min=document.singularity.direct_index_min if document.singularity else None,
        forward_free=tuple(document.forward.free) if document.forward else tuple(document.task or ()),
        task=tuple(document.task or ()),
        working_posture=document.working_posture,
        working_posture_given="working_posture" in document.model_fields_set,
        collision=document.collision.model_dump(exclude_none=True) if document.collision else None,
        length_unit=document.units,
        lines=tuple(lines.items()),
        passive_leg=passive_leg_of(document, locate),
    )
    if robot.size_mm > MAX_MM:
        raise locate.error(["units"], f"the robot measures {robot.size_mm:g} mm, beyond the {MAX_MM:g} mm kingen "
                                      "computes in")
    _check_golden(robot, locate)
    check_coordinates(robot, locate)
    _check_postures(robot, document, locate)
    if robot.direct_index_min is not None and not robot.has_direct_index:
        raise locate.error(["singularity", "direct_index_min"],
                           f"the direct index needs six force lines; this robot has {robot.dof} limbs")
    return robot


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
        for parameter, field in limb.calibrate.items():
            if field in used:
                raise locate.error(["limbs", index, "calibrate", parameter],
                                   f"dialog field {field} is already read for {used[field]}")
            used[field] = f"{names[index]}.{parameter}"
    two_branch = sum(1 for limb in limbs if limb.branches == 2)
    if two_branch > MAX_TWO_BRANCH_LIMBS:
        raise locate.error(["limbs"], f"{two_branch} two-branch limbs; at most {MAX_TWO_BRANCH_LIMBS} (256 postures)")
    return limbs


def _check_postures(robot, document, locate):
    """The working posture and an ``optimize:`` section's objective posture exist."""
    named = [(["working_posture"], robot.working_posture)]
    if document.optimize is not None and document.optimize.objective.posture is not None:
        named.append((["optimize", "objective", "posture"], document.optimize.objective.posture))
    for path, posture in named:
        if posture >= robot.postures:
            raise locate.error(path, f"posture {posture} does not exist (the robot has {robot.postures})")


def _check_golden(robot, locate):
    for index, golden in enumerate(robot.golden):
        if len(golden.joints) != robot.dof:
            raise locate.error(["golden", index, "joints"], f"expected {robot.dof} joint values, got {len(golden.joints)}")
        if golden.posture >= robot.postures:
            raise locate.error(["golden", index, "posture"],
                               f"posture {golden.posture} does not exist (the robot has {robot.postures})")
