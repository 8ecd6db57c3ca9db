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
from typing import Optional

import numpy as np
from pydantic import ValidationError

from ..conventions import REVOLUTE, SIX, branch_of_posture
from ..errors import KingenError
from ..runtime.file_gate import refuse_special_file
from .constraints import check_coordinates
from .located import Locator, diagnostic
from .passive_leg import passive_leg_of
from ..runtime.resources import robots_dir
from .reading import read_robot_file
from .file_schema import MAX_TWO_BRANCH_LIMBS, Region, robot_file_schema
from .loads_schema import payload_of
from .schema import MAX_MM, calibration_value
from .wrist import with_wrist
from ..units import LENGTH_UNITS, document_in_mm


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
    """The unit the robot file's lengths are written in ('mm', 'm' or 'inch'); the Robot holds mm."""
    length_unit_given: bool = False
    """Whether the robot file states its unit (``units:``); a file without it is read in mm."""
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
    wrist: Optional[object] = None
    """A serial wrist on the platform (kingen.robot.wrist.Wrist), or None: then the pose is the
    tool's, the joints are the legs' then the wrist's (kingen.robot.wrist.with_wrist)."""
    parallel_part: Optional["Robot"] = None
    """With a wrist: the parallel part alone (its region the platform's), else None."""
    lines: tuple = ()
    """((field path, 1-based line) ...) of the robot file, for reports that point at it."""
    payload: Optional[object] = None
    """What the platform carries (kingen.robot.loads_schema.Payload: kg, mm, kg m^2), or None."""
    gravity: tuple = (0.0, 0.0, -9.81)
    """m/s^2, base frame."""

    def line_of(self, *path):
        """The robot file's line of the field at ``path`` (or of its nearest parent), else 1."""
        lines = dict(self.lines)
        for cut in range(len(path), 0, -1):
            if tuple(path[:cut]) in lines:
                return lines[tuple(path[:cut])]
        return 1

    @property
    def has_forward(self):
        """Whether forward kinematics is defined: six limbs, free coordinates declared, or a wrist."""
        return self.dof == 6 or bool(self.forward_free) or self.wrist is not None

    @property
    def has_direct_index(self):
        """Whether the direct index is defined: six force lines, one per platform DOF. Robots
        with fewer limbs have constraints kingen does not model (Exechon, Gantry-Tau)."""
        return self.dof == SIX

    @property
    def dof(self):
        """The number of limbs (the parallel part's actuators)."""
        return len(self.limbs)

    @property
    def joint_count(self):
        """The number of joints a routine answers: the limbs', then the wrist's."""
        return self.dof + (len(self.wrist.names) if self.wrist is not None else 0)

    @property
    def parallel(self):
        """The parallel part alone: this robot, or without its wrist."""
        return self.parallel_part if self.wrist is not None else self

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
        """The limbs' branch combinations, times the wrist's two branches (the last bit; one
        where a one-posture view holds the wrist on one branch)."""
        return 2 ** sum(1 for bit in self.branch_bits if bit >= 0) * (2 if self._wrist_branches else 1)

    @property
    def _wrist_branches(self):
        """Whether the wrist's two branches are postures (a wrist not held on one branch)."""
        return self.wrist is not None and self.wrist.branch is None

    @property
    def joint_names(self):
        wrist = self.wrist.names if self.wrist is not None else ()
        return tuple(limb.name or f"joint{i + 1}" for i, limb in enumerate(self.limbs)) + wrist

    @property
    def joint_types(self):
        return tuple(limb.joint_type for limb in self.limbs) + (REVOLUTE,) * (self.joint_count - self.dof)

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
        if self.wrist is not None:
            return np.concatenate([lower, self.wrist.lower]), np.concatenate([upper, self.wrist.upper])
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
        parallel = replace(self.parallel_part, limbs=tuple(limbs)) if self.wrist is not None else None
        return replace(self, limbs=tuple(limbs), parallel_part=parallel)

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
        """(joint_count,) bool: which joints are angles (compared modulo 2 pi)."""
        return np.array([t.wraps for t in self.joint_types])

    def joint_scale(self):
        """Per joint: factor from YAML units (mm, degrees) to internal units (mm, radians)."""
        return np.array([t.yaml_scale for t in self.joint_types])

    def posture_branches(self, posture):
        """Per limb: the branch (0 or 1) it takes in ``posture``; 0 for one-branch limbs (with a
        wrist: in the parallel part's posture, ``posture`` // 2)."""
        posture = posture // 2 if self._wrist_branches else posture
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
        length_unit_given="units" in document.model_fields_set,
        lines=tuple(lines.items()),
        passive_leg=passive_leg_of(document, locate),
        payload=payload_of(document, LENGTH_UNITS[document.units]),
        gravity=tuple(document.gravity),
    )
    if robot.size_mm > MAX_MM:
        raise locate.error(["units"], f"the robot measures {robot.size_mm:g} mm, beyond the {MAX_MM:g} mm kingen "
                                      "computes in")
    check_coordinates(robot, locate)
    if document.wrist is not None or document.tool is not None:
        robot = with_wrist(replace(robot, golden=()), document, locate)
    _check_golden(robot, locate)
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
        if len(golden.joints) != robot.joint_count:
            raise locate.error(["golden", index, "joints"],
                               f"expected {robot.joint_count} joint values, got {len(golden.joints)}")
        if golden.posture >= robot.postures:
            raise locate.error(["golden", index, "posture"],
                               f"posture {golden.posture} does not exist (the robot has {robot.postures})")
