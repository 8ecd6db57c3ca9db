"""Recorded snapshots: poses with every posture's joints and warnings, kept in a JSON file
next to a robot definition and checked on every run (:mod:`kingen.verify.checks.snapshot`).

A snapshot is recorded from the reference or from a trusted plugin (a hand-written routine
already validated in the simulator). Recording is the only way a snapshot changes, and it
rewrites the whole file. The file states its units and per-unit tolerances.
"""

import contextlib
import json
from pathlib import Path
from typing import Annotated, Optional

import numpy as np
from pydantic import Field, ValidationError

from ..defaults import VERSION
from ..conventions import t6_from_pose
from ..errors import InternalError, PluginDefect, located
from ..runtime.file_gate import read_limited, size_text
from ..runtime.files import atomic_file
from ..kinematics.poses import pose_chunks
from ..kinematics.routine import WARNINGS
from ..robot.schema import Strict

FORMAT = 1
TOLERANCE_MM = 1e-6
TOLERANCE_RAD = 1e-8
"""Defaults a snapshot is recorded with: far above rounding differences between compilers
and machines, far below any modelling change."""
MAX_SNAPSHOT_BYTES = 64 << 20


Name = Annotated[str, Field(max_length=255)]
"""A robot's, joint's or unit's name: short, so that a message quoting one stays short."""


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
    robot: Name
    definition_sha256: Annotated[str, Field(pattern="^[0-9a-f]{64}$")]
    kingen: Annotated[str, Field(max_length=100)]
    recorded_from: Annotated[str, Field(max_length=2000)]
    samples: int
    seed: Annotated[int, Field(ge=0)]
    joint_names: list[Name]
    joint_units: list[Name]
    tolerance: Tolerance
    entries: list[Entry]


def snapshot_path(robot_path):
    """Where the pytest plugin looks for a robot's snapshot: <robot>.golden.json beside it."""
    return Path(robot_path).with_name(Path(robot_path).stem + ".golden.json")


WORST_FLOAT = -2.2250738585072014e-308
"""A float whose JSON text is as long as any finite double's (24 characters)."""


def _entry_line(t6, joints, warnings):
    """One entry of the file, on one line: T6 (4, 4), joints (dof, postures) with None for
    a value that is not a finite number, warnings (postures,)."""
    entry = {"t6": t6.tolist(), "joints": [[float(v) if np.isfinite(v) else None for v in row] for row in joints],
             "warnings": [int(w) for w in warnings]}
    return "  " + json.dumps(entry, separators=(",", ":"), allow_nan=False)


def _frame(robot, recorded_from, samples, seed):
    """(head, tail): the file's text before and after its entries."""
    data = {
        "kingen_snapshot": FORMAT, "robot": robot.name, "definition_sha256": robot.sha256, "kingen": VERSION,
        "recorded_from": recorded_from, "samples": samples, "seed": seed, "joint_names": list(robot.joint_names),
        "joint_units": [joint_type.unit for joint_type in robot.joint_types],
        "tolerance": {"mm": TOLERANCE_MM, "rad": TOLERANCE_RAD}, "entries": ["ENTRIES"],
    }
    head, tail = json.dumps(data, indent=1, allow_nan=False).split('"ENTRIES"')
    return head.rstrip() + "\n", "\n" + tail.lstrip() + "\n"


def entry_bytes(robot):
    """An upper bound on the bytes one entry takes in the file for ``robot`` (its separator
    included): every number written as long as a finite double can be, every warning as the
    longest code."""
    worst_warning = max(WARNINGS.values(), key=lambda code: len(str(code)))
    return len(_entry_line(np.full((4, 4), WORST_FLOAT), np.full((robot.dof, robot.postures), WORST_FLOAT),
                           [worst_warning] * robot.postures)) + len(",\n")


def check_fits(robot, samples, recorded_from, seed):
    """Nothing when a snapshot of ``samples`` poses for ``robot`` is sure to stay within
    MAX_SNAPSHOT_BYTES, the most :func:`load` reads; else KingenError naming --samples and
    the largest count that fits. Called before anything is computed."""
    head, tail = _frame(robot, recorded_from, samples, seed)
    per_entry = entry_bytes(robot)
    fitting = (MAX_SNAPSHOT_BYTES - len(head) - len(tail)) // per_entry
    if samples > fitting:
        raise located(None, None, f"--samples {samples}", f"a snapshot of {robot.name} takes up to "
                      f"{per_entry / 1000:.1f} kB a pose and verify reads at most {size_text(MAX_SNAPSHOT_BYTES)}: "
                      f"at most {max(fitting, 0)} poses fit")


class Recording:
    """A snapshot being written: ``add(t6, joints, warnings)`` appends a chunk of entries to
    the open stream as it is computed (memory stays that of one chunk). A warning that is not
    one of WARNINGS, which :func:`load` would refuse, is a PluginDefect (only a plugin gives one)."""

    def __init__(self, stream, recorded_from):
        self._stream, self._recorded_from = stream, recorded_from
        self.count = 0

    def add(self, t6, joints, warnings):
        """Append entries for T6 (n, 4, 4), joints (n, dof, postures) and warnings (n, postures)."""
        codes = np.isin(warnings, list(WARNINGS.values()))
        if not codes.all():
            pose, posture = np.argwhere(~codes)[0]
            raise PluginDefect(f"{self._recorded_from} answered warning {int(warnings[pose, posture])} (pose "
                               f"{self.count + pose}, posture {posture}), not one of kingen's warning codes; "
                               "a snapshot records only those")
        lines = [_entry_line(t6[i], joints[i], warnings[i]) for i in range(len(t6))]
        self._stream.write(((",\n" if self.count else "") + ",\n".join(lines)).encode())
        self.count += len(t6)


@contextlib.contextmanager
def recording(path, robot, recorded_from, samples, seed):
    """A :class:`Recording` whose file takes ``path``'s place, whole, when the block ends
    with all ``samples`` entries added; on any exception ``path`` is left as it was."""
    head, tail = _frame(robot, recorded_from, samples, seed)
    with atomic_file(path) as stream:
        stream.write(head.encode())
        snapshot = Recording(stream, recorded_from)
        yield snapshot
        if snapshot.count != samples:
            raise InternalError(f"{snapshot.count} snapshot entries recorded, {samples} announced")
        stream.write(tail.encode())


def t6_chunks(robot, samples, seed, chunk):
    """The poses a snapshot records, as T6 (m, 4, 4) ``chunk`` poses at a time: drawn like
    verify's, from their own seed (the same poses whatever ``chunk``)."""
    for _, poses in pose_chunks(robot, samples, seed, chunk):
        yield t6_from_pose(poses)


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
    _check_against(path, snapshot, robot)
    return snapshot


def _check_against(path, snapshot, robot):
    """KingenError naming the field unless ``snapshot`` fits ``robot``: its joints and units,
    entries (at least one, as many as ``samples``) of the robot's shape, known warning codes."""
    units = [joint_type.unit for joint_type in robot.joint_types]
    if len(snapshot.joint_names) != robot.dof:
        raise located(path, None, "joint_names", f"{len(snapshot.joint_names)} names for the robot's {robot.dof} "
                                                 f"joints ({', '.join(robot.joint_names)})")
    for index, (given, name) in enumerate(zip(snapshot.joint_names, robot.joint_names)):
        if given != name:
            raise located(path, None, f"joint_names.{index}", f"'{given}', but the robot's joint {index} is {name}")
    if len(snapshot.joint_units) != robot.dof:
        raise located(path, None, "joint_units", f"{len(snapshot.joint_units)} units for {robot.dof} joints")
    for name, given, unit in zip(robot.joint_names, snapshot.joint_units, units):
        if given != unit:
            raise located(path, None, "joint_units", f"'{given}' for joint {name}, which is in {unit}: a snapshot's "
                                                      "units are the robot's")
    if not snapshot.entries:
        raise located(path, None, "entries", "none recorded; record the snapshot again (kingen golden record)")
    if snapshot.samples != len(snapshot.entries):
        raise located(path, None, "samples", f"{snapshot.samples}, but the file holds {len(snapshot.entries)} entries")
    codes = set(WARNINGS.values())
    for index, entry in enumerate(snapshot.entries):
        shape = (len(entry.joints), *{len(row) for row in entry.joints}, len(entry.warnings))
        if shape != (robot.dof, robot.postures, robot.postures):
            raise located(path, None, f"entries.{index}", f"must hold {robot.dof} joints x {robot.postures} "
                                                           f"postures and {robot.postures} warnings")
        for posture, warning in enumerate(entry.warnings):
            if warning not in codes:
                raise located(path, None, f"entries.{index}.warnings.{posture}",
                              f"{warning} is not a warning code ({', '.join(map(str, sorted(codes)))})")
