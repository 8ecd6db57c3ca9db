"""Loading plugins as DELMIA does, through the host emulator and cffi.

The host emulator library is loaded first with global symbol visibility, so a
plugin's undefined ``DNBVMAP_*`` symbols resolve to it, as they resolve to the
host process inside DELMIA. Then the plugin is loaded, ``get_kin_config`` is
asked about the routine, and the routine is called per pose (``call``) or for a
whole array of T6 in C (``call_batch``). Outputs are pre-filled with sentinels
(NaN, -1) so an entry the routine never wrote stays visible, and every pose's
buffers sit between guard zones so a write outside them is caught.
"""

import os
import shutil
import sys
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import cffi
import numpy as np

from . import abi
from .build import host_support
from .errors import KingenError
from .model import REVOLUTE

ffi = cffi.FFI()
ffi.cdef(abi.cffi_declarations())

UNWRITTEN_WARNING = -1
"""Sentinel left in a warning slot the routine did not write."""
GUARD = 8
"""Entries of guard zone before and after each pose's solutions and warnings."""
GUARD_DOUBLE = -7.0e300
GUARD_INT = -20260001

_host_library = None
_loaded = {}


def host():
    """The host emulator library, built if needed and loaded once per process (RTLD_GLOBAL)."""
    global _host_library
    if _host_library is None:
        _, library = host_support()
        _host_library = ffi.dlopen(str(library), ffi.RTLD_NOW | ffi.RTLD_GLOBAL)
    return _host_library


@dataclass(frozen=True)
class KinConfig:
    """What get_kin_config answered: status 0 on a match, then dof, solutions, data hint."""

    status: int
    dof: int
    solutions: int
    data_hint: int


@dataclass(frozen=True)
class Calls:
    """Routine results for n poses: returned (n,), solutions (n, dof, postures), warnings (n, postures).

    guard_violations: poses whose guard zones were written; inputs_modified: whether the
    routine wrote into T6, link_lengths or link_offsets.
    """

    returned: np.ndarray
    solutions: np.ndarray
    warnings: np.ndarray
    guard_violations: int = 0
    inputs_modified: bool = False


def _dlopen(path):
    """dlopen ``path``; a file replaced since it was first loaded here is loaded from a copy
    (the dynamic loader would otherwise hand back the old image)."""
    path = Path(path).resolve()
    if not path.is_file():
        raise KingenError(f"{path}: no such plugin library")
    stat = path.stat()
    identity = (stat.st_mtime_ns, stat.st_size, stat.st_ino)
    known = _loaded.get(path)
    if known is not None and known[0] == identity:
        return known[1]
    target = path
    if known is not None:
        folder = Path(tempfile.mkdtemp(prefix="kingen-reload-"))
        target = folder / path.name
        shutil.copy2(path, target)
    try:
        library = ffi.dlopen(str(target), ffi.RTLD_NOW)
    except OSError as error:
        reason = str(error).split(".  Additionally")[0]
        raise KingenError(f"{path}: cannot be loaded: {reason}") from None
    _loaded[path] = (identity, library)
    return library


class Plugin:
    """A loaded user-kinematics library and one of its routines.

    Loading asks ``get_kin_config`` about the routine and tells the host emulator the
    device definition (dof and solution count) from that answer, as DELMIA does.
    """

    def __init__(self, library_path, routine):
        host()
        self.path = Path(library_path)
        self.routine = routine
        self.library = _dlopen(library_path)
        self.config = self.kin_config(routine)
        if self.config.status != 0:
            raise KingenError(f"{self.path}: get_kin_config does not know routine '{routine}'")
        self.dof, self.postures = self.config.dof, self.config.solutions
        ffi.cdef(abi.routine_prototype(routine, self.postures) + ";", override=True)
        try:
            self.function = getattr(self.library, routine)
        except AttributeError:
            raise KingenError(f"{self.path}: no exported routine '{routine}'") from None
        self.reset_host()

    def kin_config(self, routine):
        """Ask get_kin_config about ``routine`` (any name, to test refusals too)."""
        values = ffi.new("int[3]", [-1, -1, -1])
        name = ffi.new("char[]", routine.encode())
        status = self.library.get_kin_config(name, values, values + 1, values + 2)
        return KinConfig(status, values[0], values[1], values[2])

    def reset_host(self, refuse=False):
        """Set the host's device definition to this routine's answer; optionally refuse it."""
        lib = host()
        lib.kingen_host_reset(self.dof, self.postures)
        lib.kingen_host_refuse(int(refuse))

    def call(self, t6, link_lengths=None, link_offsets=None, kinstat=None):
        """Call the routine once per T6 ((4, 4) or (n, 4, 4)) from Python, one cffi call each."""
        return self._run(np.asarray(t6, dtype=float).reshape(-1, 4, 4), link_lengths, link_offsets, kinstat, batch=False)

    def call_batch(self, t6, link_lengths=None, link_offsets=None, kinstat=None):
        """Call the routine for every T6 in (n, 4, 4) from C, in one host call."""
        return self._run(np.asarray(t6, dtype=float).reshape(-1, 4, 4), link_lengths, link_offsets, kinstat, batch=True)

    def batch_runner(self, t6):
        """A function that runs the C batch driver over ``t6`` (n, 4, 4) into buffers allocated
        here once: what it costs is the routine's own time, for benchmarks."""
        t6 = np.ascontiguousarray(t6, dtype=float).reshape(-1, 4, 4)
        count = t6.shape[0]
        zeros = np.zeros(6)
        solutions = np.empty(count * self.dof * self.postures)
        warnings = np.empty(count * self.postures, dtype=np.intc)
        returned = np.empty(count, dtype=np.intc)
        arguments = (
            ffi.cast("void *", self.function), count, _pointer("double *", t6), _pointer("double *", zeros),
            _pointer("double *", zeros), _pointer("double *", solutions), self.dof * self.postures,
            _pointer("int *", warnings), self.postures, _pointer("int *", returned), ffi.NULL,
        )
        keep_alive = (t6, zeros, solutions, warnings, returned)

        def run():
            host().kingen_host_run_batch(*arguments)
            return keep_alive

        return run

    def _run(self, t6, link_lengths, link_offsets, kinstat, batch):
        count, dof, postures = t6.shape[0], self.dof, self.postures
        t6 = np.ascontiguousarray(t6)
        lengths = np.array(np.zeros(6) if link_lengths is None else link_lengths, dtype=float)
        offsets = np.array(np.zeros(6) if link_offsets is None else link_offsets, dtype=float)
        inputs = (t6.copy(), lengths.copy(), offsets.copy())
        solution_block, warning_block = dof * postures + 2 * GUARD, postures + 2 * GUARD
        solution_buffer = np.full((count, solution_block), GUARD_DOUBLE)
        solution_buffer[:, GUARD:GUARD + dof * postures] = np.nan
        warning_buffer = np.full((count, warning_block), GUARD_INT, dtype=np.intc)
        warning_buffer[:, GUARD:GUARD + postures] = UNWRITTEN_WARNING
        returned = np.full(count, -1, dtype=np.intc)
        data = ffi.NULL if kinstat is None else kinstat.pointer
        lengths_p, offsets_p = _pointer("double *", lengths), _pointer("double *", offsets)
        solutions_p = _pointer("double *", solution_buffer) + GUARD
        warnings_p = _pointer("int *", warning_buffer) + GUARD
        if batch:
            host().kingen_host_run_batch(
                ffi.cast("void *", self.function), count, _pointer("double *", t6), lengths_p, offsets_p,
                solutions_p, solution_block, warnings_p, warning_block, _pointer("int *", returned), data,
            )
        else:
            t6_p = _pointer("double *", t6)
            for i in range(count):
                returned[i] = self.function(
                    lengths_p, offsets_p, ffi.cast("double (*)[4]", t6_p + 16 * i),
                    ffi.cast(f"double (*)[{postures}]", solutions_p + i * solution_block),
                    warnings_p + i * warning_block, data,
                )
        guards_intact = np.all(
            np.concatenate([solution_buffer[:, :GUARD], solution_buffer[:, -GUARD:]], axis=1) == GUARD_DOUBLE, axis=1
        ) & np.all(np.concatenate([warning_buffer[:, :GUARD], warning_buffer[:, -GUARD:]], axis=1) == GUARD_INT, axis=1)
        modified = not all(np.array_equal(a, b, equal_nan=True) for a, b in zip(inputs, (t6, lengths, offsets)))
        return Calls(
            returned=returned,
            solutions=solution_buffer[:, GUARD:GUARD + dof * postures].reshape(count, dof, postures),
            warnings=warning_buffer[:, GUARD:GUARD + postures],
            guard_violations=int(np.count_nonzero(~guards_intact)),
            inputs_modified=modified,
        )


def _pointer(ctype, array):
    return ffi.cast(ctype, ffi.from_buffer(array))


class KinStat:
    """A DLM_Data_KinStat for ``robot`` as DELMIA fills it (joint types, values, limits).

    Keeps its arrays alive as long as the object lives; pass it to Plugin.call.
    """

    def __init__(self, robot, joint_values=None, kin_mode=0):
        lower, upper = robot.travel_limits()
        self.types = ffi.new("int[]", [
            abi.CONSTANTS["ROTATIONAL"] if t == REVOLUTE else abi.CONSTANTS["TRANSLATIONAL"]
            for t in robot.joint_types
        ])
        self.values = ffi.new("double[]", list(joint_values if joint_values is not None else np.zeros(robot.dof)))
        self.lower = ffi.new("double[]", [float(v) if np.isfinite(v) else -1e30 for v in lower])
        self.upper = ffi.new("double[]", [float(v) if np.isfinite(v) else 1e30 for v in upper])
        self.pointer = ffi.new("DLM_Data_KinStat *")
        self.pointer.dof_count = robot.dof
        self.pointer.joint_types = self.types
        self.pointer.kin_mode = kin_mode
        self.pointer.joint_values = self.values
        self.pointer.jnt_trvl_lmts[0] = self.lower
        self.pointer.jnt_trvl_lmts[1] = self.upper


def host_state():
    """(kin_check_definition calls, last dof, last solution count) recorded by the host."""
    lib = host()
    return lib.kingen_host_check_calls(), lib.kingen_host_last_dof(), lib.kingen_host_last_solutions()


@contextmanager
def captured_output(limit=4096):
    """Capture what native code writes on file descriptors 1 and 2 (printf included).

    Yields a dict that holds, after the block, ``bytes`` (how many were written) and
    ``text`` (the first ``limit`` bytes, decoded).
    """
    result = {"bytes": 0, "text": ""}
    sys.stdout.flush()
    sys.stderr.flush()
    host().kingen_host_flush()
    saved = [os.dup(1), os.dup(2)]
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 1)
        os.dup2(sink.fileno(), 2)
        try:
            yield result
        finally:
            host().kingen_host_flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for descriptor in saved:
                os.close(descriptor)
            result["bytes"] = sink.seek(0, os.SEEK_END)
            sink.seek(0)
            result["text"] = sink.read(limit).decode(errors="replace")
