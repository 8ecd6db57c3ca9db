"""Loading plugins as DELMIA does, through the host emulator and cffi.

The host emulator library is loaded first with global symbol visibility, so a
plugin's undefined ``DNBVMAP_*`` symbols resolve to it, as they resolve to the
host process inside DELMIA. Then the plugin is loaded, ``get_kin_config`` is
asked about the routine, and the routine is called per pose (``call``) or for a
whole array of T6 in C (``call_batch``). Outputs are pre-filled with sentinels
(NaN, -1) so an entry the routine never wrote stays visible.
"""

import shutil
import tempfile
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
    """Routine results for n poses: returned (n,), solutions (n, dof, postures), warnings (n, postures)."""

    returned: np.ndarray
    solutions: np.ndarray
    warnings: np.ndarray


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
        raise KingenError(f"{path}: cannot be loaded: {error}") from None
    _loaded[path] = (identity, library)
    return library


class Plugin:
    """A loaded user-kinematics library and one of its routines.

    ``open`` asks ``get_kin_config`` and tells the host emulator what the device
    definition is (dof and solution count), as DELMIA does from that answer.
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

    def _run(self, t6, link_lengths, link_offsets, kinstat, batch):
        count = t6.shape[0]
        t6 = np.ascontiguousarray(t6)
        lengths = np.ascontiguousarray(np.zeros(6) if link_lengths is None else link_lengths, dtype=float)
        offsets = np.ascontiguousarray(np.zeros(6) if link_offsets is None else link_offsets, dtype=float)
        solutions = np.full((count, self.dof, self.postures), np.nan)
        warnings = np.full((count, self.postures), UNWRITTEN_WARNING, dtype=np.intc)
        returned = np.full(count, -1, dtype=np.intc)
        data = ffi.NULL if kinstat is None else kinstat.pointer
        lengths_p, offsets_p = _pointer("double *", lengths), _pointer("double *", offsets)
        if batch:
            host().kingen_host_run_batch(
                ffi.cast("void *", self.function), count, _pointer("double *", t6), lengths_p, offsets_p,
                _pointer("double *", solutions), self.dof * self.postures,
                _pointer("int *", warnings), self.postures, _pointer("int *", returned), data,
            )
        else:
            for i in range(count):
                returned[i] = self.function(
                    lengths_p, offsets_p, ffi.cast("double (*)[4]", _pointer("double *", t6[i])),
                    ffi.cast(f"double (*)[{self.postures}]", _pointer("double *", solutions[i])),
                    _pointer("int *", warnings[i]), data,
                )
        return Calls(returned=returned, solutions=solutions, warnings=warnings)


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


def set_host_refusal(refuse):
    """Make the host's kin_check_definition refuse (True) or judge by counts (False)."""
    host().kingen_host_refuse(int(refuse))


