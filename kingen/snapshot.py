"""Recorded snapshots: poses with every posture's joints and warnings, kept in a JSON file
next to a robot definition and checked on every run (:mod:`kingen.verify.checks.snapshot`).

A snapshot is recorded from the reference or from a trusted plugin (a hand-written routine
already validated in the simulator). Recording is the only way a snapshot changes, and it
rewrites the whole file. The file states its units and per-unit tolerances.
"""

import json
from pathlib import Path
from typing import Annotated, Optional

import numpy as np
from pydantic import Field, ValidationError

from . import __version__
from .conventions import t6_from_pose
from .errors import located, read_limited
from .poses import sample_poses
from .schema import Strict

FORMAT = 1
TOLERANCE_MM = 1e-6
TOLERANCE_RAD = 1e-8
"""Defaults a snapshot is recorded with: far above rounding differences between compilers
and machines, far below any modelling change."""
MAX_SNAPSHOT_BYTES = 64 << 20


class Tolerance(Strict):
    mm: Annotated[float, Field(gt=0)]
    rad: Annotated[float, Field(gt=0)]


class Entry(Strict):
    t6: Annotated[list[Annotated[list[float], Field(min_length=4, max_length=4)]], Field(min_length=4, max_length=4)]
    joints: list[list[Optional[float]]]
    """joints[j][k]: joint j of posture k, in ``joint_units`` (None: not a finite number)."""
    warnings: list[int]


class Snapshot(Strict):
    """The file's schema."""

    kingen_snapshot: int
    robot: str
    definition_sha256: str
    kingen: str
    recorded_from: str
    samples: int
    seed: int
    joint_names: list[str]
    joint_units: list[str]
    tolerance: Tolerance
    entries: list[Entry]


def snapshot_path(robot_path):
    """Where the pytest plugin looks for a robot's snapshot: <robot>.golden.json beside it."""
    return Path(robot_path).with_name(Path(robot_path).stem + ".golden.json")


def record(robot, t6, joints, warnings, recorded_from, samples, seed):
    """The snapshot text for T6 (n, 4, 4), joints (n, dof, postures) and warnings (n, postures)."""
    data = {
        "kingen_snapshot": FORMAT,
        "robot": robot.name,
        "definition_sha256": robot.sha256,
        "kingen": __version__,
        "recorded_from": recorded_from,
        "samples": samples,
        "seed": seed,
        "joint_names": list(robot.joint_names),
        "joint_units": [joint_type.unit for joint_type in robot.joint_types],
        "tolerance": {"mm": TOLERANCE_MM, "rad": TOLERANCE_RAD},
        "entries": [{"t6": t6[i].tolist(),
                     "joints": [[float(v) if np.isfinite(v) else None for v in row] for row in joints[i]],
                     "warnings": [int(w) for w in warnings[i]]} for i in range(len(t6))],
    }
    return json.dumps(data, indent=1, allow_nan=False) + "\n"


def sample_t6(robot, samples, seed):
    """The poses a snapshot records: drawn like verify's, from their own seed."""
    return t6_from_pose(sample_poses(robot, samples, seed))


def load(path, robot):
    """The snapshot at ``path`` for ``robot``; KingenError naming the file and field otherwise."""
    path = Path(path)
    raw = read_limited(path, MAX_SNAPSHOT_BYTES, "not a kingen snapshot")
    try:
        snapshot = Snapshot.model_validate(json.loads(raw))
    except (ValueError, RecursionError) as error:
        if isinstance(error, ValidationError):
            first = error.errors(include_url=False)[0]
            field = ".".join(str(part) for part in first["loc"])
            raise located(path, None, field, first["msg"]) from None
        raise located(path, None, None, f"not a kingen snapshot (JSON: {str(error).splitlines()[0]})") from None
    if snapshot.kingen_snapshot != FORMAT:
        raise located(path, None, "kingen_snapshot", f"version {snapshot.kingen_snapshot} is not one this kingen "
                                                     f"reads (it reads {FORMAT})")
    if snapshot.robot != robot.name:
        raise located(path, None, "robot", f"recorded for '{snapshot.robot}', not '{robot.name}'")
    units = [joint_type.unit for joint_type in robot.joint_types]
    if len(snapshot.joint_units) != robot.dof:
        raise located(path, None, "joint_units", f"{len(snapshot.joint_units)} units for {robot.dof} joints")
    for name, given, unit in zip(robot.joint_names, snapshot.joint_units, units):
        if given != unit:
            raise located(path, None, "joint_units", f"'{given}' for joint {name}, which is in {unit}: a snapshot's "
                                                      "units are the robot's")
    shapes = {(len(entry.joints), *{len(row) for row in entry.joints}, len(entry.warnings)) for entry in snapshot.entries}
    if shapes - {(robot.dof, robot.postures, robot.postures)}:
        raise located(path, None, "entries", f"entries must hold {robot.dof} joints x {robot.postures} postures")
    return snapshot
