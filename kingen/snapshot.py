"""Recorded snapshots: poses with every posture's joints and warnings, kept in a JSON file
next to a robot definition and checked on every run (check ``snapshot``).

A snapshot is recorded from the reference or from a trusted plugin (a hand-written routine
already validated in the simulator). Recording is the only way a snapshot changes, and it
rewrites the whole file. The file states its units and per-unit tolerances.
"""

import json
from pathlib import Path
from typing import Annotated, Optional

import numpy as np
from pydantic import Field, ValidationError

from . import __version__, abi
from .conventions import t6_from_pose
from .errors import located, read_limited
from .report import Check
from .schema import Strict

FORMAT = 1
TOLERANCE_MM = 1e-6
TOLERANCE_RAD = 1e-8
"""Defaults a snapshot is recorded with: far above rounding differences between compilers
and machines, far below any modelling change."""
MAX_SNAPSHOT_BYTES = 64 << 20
WORST_SHOWN = 3


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
    from .verify import sample_poses

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
    if snapshot.robot != robot.name:
        raise located(path, None, "robot", f"recorded for '{snapshot.robot}', not '{robot.name}'")
    shapes = {(len(entry.joints), *{len(row) for row in entry.joints}, len(entry.warnings)) for entry in snapshot.entries}
    if shapes - {(robot.dof, robot.postures, robot.postures)}:
        raise located(path, None, "entries", f"entries must hold {robot.dof} joints x {robot.postures} postures")
    return snapshot


def check(robot, snapshot, call):
    """The ``snapshot`` check: ``call(t6)`` gives the routine's (solutions, warnings) for the
    snapshot's T6; joints are compared where the recording solved the posture, warnings
    everywhere. The detail names the worst entries."""
    t6 = np.array([entry.t6 for entry in snapshot.entries], dtype=float).reshape(-1, 4, 4)
    recorded = np.array([[[np.nan if v is None else v for v in row] for row in entry.joints]
                         for entry in snapshot.entries], dtype=float).reshape(len(t6), robot.dof, robot.postures)
    recorded_warnings = np.array([entry.warnings for entry in snapshot.entries], dtype=int).reshape(len(t6), -1)
    solutions, warnings = call(t6)
    units = np.array(snapshot.joint_units)
    tolerance = np.where(units == "rad", snapshot.tolerance.rad, snapshot.tolerance.mm)[None, :, None]
    difference = solutions - recorded
    difference[:, units == "rad"] = difference[:, units == "rad"] - 2 * np.pi * np.rint(
        difference[:, units == "rad"] / (2 * np.pi))
    error = np.where(np.isfinite(difference), np.abs(difference), np.inf)
    solved = (recorded_warnings != abi.WARNINGS["WARN_UNREACHABLE"])[:, None, :]
    excess = np.where(solved, error / tolerance, 0.0)
    wrong_values = int(np.count_nonzero(excess > 1.0))
    wrong_warnings = int(np.count_nonzero(warnings != recorded_warnings))
    detail = (f"{len(t6)} recorded poses x {robot.postures} postures ({snapshot.recorded_from}, kingen "
              f"{snapshot.kingen}): {wrong_values} joints beyond {snapshot.tolerance.mm:g} mm / "
              f"{snapshot.tolerance.rad:g} rad, {wrong_warnings} warnings differ")
    worst = []
    for flat in np.argsort(excess, axis=None)[::-1][:WORST_SHOWN]:
        pose, joint, posture = np.unravel_index(flat, excess.shape)
        if excess[pose, joint, posture] > 1.0:
            worst.append(f"pose {pose} posture {posture} {snapshot.joint_names[joint]}: recorded "
                         f"{recorded[pose, joint, posture]:.9g}, now {solutions[pose, joint, posture]:.9g} "
                         f"{units[joint]}")
    for pose, posture in list(zip(*np.nonzero(warnings != recorded_warnings)))[:WORST_SHOWN]:
        worst.append(f"pose {pose} posture {posture}: recorded warning {abi.WARNING_NAMES.get(recorded_warnings[pose, posture])}, "
                     f"now {abi.WARNING_NAMES.get(int(warnings[pose, posture]), warnings[pose, posture])}")
    result = Check("snapshot", not wrong_values and not wrong_warnings, detail, worst)
    if snapshot.definition_sha256 != robot.sha256:
        result.diagnoses.append(f"recorded from another definition (sha256 {snapshot.definition_sha256[:16]}; "
                                f"the robot file has {robot.sha256[:16]}): record it again if the change was meant")
    return result
