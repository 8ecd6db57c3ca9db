"""Loading plugins as DELMIA does, through the host emulator and cffi.

The host emulator library is loaded first with global symbol visibility, so a
plugin's undefined ``DNBVMAP_*`` symbols resolve to it, as they resolve to the
host process inside DELMIA. Then the plugin is loaded, ``get_kin_config`` is
asked about the routine, and the routine is called for a whole array of T6 in C.
Every call gets output buffers pre-filled with sentinels (NaN, -1), so an entry the
routine never wrote stays visible, and placed against inaccessible pages, so a write
past (or far before) them faults and is reported per call instead of corrupting memory.

Loading runs the library's constructors and every call runs foreign code: the
command line does both only in a child process (:mod:`kingen.runtime.isolation`).
"""

import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import cffi
import numpy as np

from ...errors import KingenError, PluginDefect
from ...runtime.file_gate import refuse_special_file
from ...runtime.text import counted
from ...kinematics.routine import Calls, check_routine_name
from ...kinematics.singularity import branch_table, representative_postures
from . import abi
from .build import host_support
from .checks import CHECKS

ffi = cffi.FFI()
ffi.cdef(abi.cffi_declarations())

MAX_DOF = 64
MAX_SOLUTIONS = 1 << 16
"""The largest joint and solution counts a get_kin_config answer may give to be called at all."""

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


def _dlopen(path):
    """dlopen ``path``; a file replaced since it was first loaded here is loaded from a copy
    (the dynamic loader would otherwise hand back the old image)."""
    path = Path(path).resolve()
    refuse_special_file(path)
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
        with open(path, "rb") as stream:
            shared_object = stream.read(4) == b"\x7fELF"
        if shared_object:  # a library the host cannot load either (an undefined symbol, say)
            raise PluginDefect(f"the library cannot be loaded: {reason}", check="load") from None
        raise KingenError(f"{path}: cannot be loaded: {reason}") from None
    _loaded[path] = (identity, library)
    return library


class Plugin:
    """A loaded user-kinematics library and one of its routines.

    Loading asks ``get_kin_config`` about the routine and tells the host emulator the
    device definition (dof and solution count) from that answer, as DELMIA does.
    Raises KingenError for what is the user's to fix (no such file, not a loadable
    library, a routine the library does not know) and PluginDefect for a library that
    breaks the interface (no get_kin_config, impossible joint or solution counts).
    ``checks``: what verify runs on it (:mod:`kingen.hosts.delmia.checks`).
    """

    checks = CHECKS

    def __init__(self, library_path, routine):
        host()
        self.path = Path(library_path)
        self.routine = check_routine_name(routine)
        self.library = _dlopen(library_path)
        ffi.cdef(f"int {routine}(double *, double *, double (*)[4], double *, int *, void *);", override=True)
        try:
            self.function = getattr(self.library, routine)
        except AttributeError:
            self.function = None
        try:
            self.library.get_kin_config
        except AttributeError:
            raise PluginDefect("the library does not export get_kin_config", check="get_kin_config") from None
        self.config = self.kin_config(routine)
        if self.config.status != 0:
            raise KingenError(f"{self.path}: get_kin_config does not know routine '{routine}'")
        if self.function is None:
            raise KingenError(f"{self.path}: no exported routine '{routine}'")
        self.dof, self.postures = self.config.dof, self.config.solutions
        if not (1 <= self.dof <= MAX_DOF and 1 <= self.postures <= MAX_SOLUTIONS):
            raise PluginDefect(f"get_kin_config answers {counted(self.dof, 'joint')} and "
                               f"{counted(self.postures, 'solution')} for "
                               f"'{routine}': the routine cannot be called with such buffers", check="get_kin_config")
        self.reset_host()

    def host_state(self):
        """(kin_check_definition calls, last dof, last solution count) since the last reset."""
        return host_state()

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

    summarises_branches = True
    """call can summarise the solutions by limb branch (its ``branches_of``)."""

    def call(self, t6, link_lengths=None, link_offsets=None, kinstat=None, branches_of=None):
        """Call the routine for every T6 in ((4, 4) or (n, 4, 4)) from C, with guarded buffers.
        With ``branches_of`` (a robot of the routine's joint and posture counts), the C driver
        also summarises each call's solutions by the robot's limb branches while they are in
        the cache (Calls.branch_values and Calls.repeats)."""
        t6 = np.ascontiguousarray(t6, dtype=float).reshape(-1, 4, 4)
        count = t6.shape[0]
        solutions = np.empty((count, self.dof, self.postures))
        warnings = np.empty((count, self.postures), dtype=np.intc)
        returned = np.empty(count, dtype=np.intc)
        faults = np.empty(count, dtype=np.intc)
        lengths, offsets = _dialog(link_lengths), _dialog(link_offsets)
        summary = None
        if branches_of is not None:
            if (branches_of.dof, branches_of.postures) != (self.dof, self.postures):
                raise ValueError(f"branches_of: {branches_of.name} has {branches_of.dof} joints and "
                                 f"{branches_of.postures} postures, the routine {self.dof} and {self.postures}")
            summary = _BranchSummary(branches_of, count)
        status = host().kingen_host_run_guarded(
            ffi.cast("void *", self.function), count, _pointer("double *", t6), _pointer("double *", lengths),
            _pointer("double *", offsets), self.dof, self.postures, _pointer("double *", solutions),
            _pointer("int *", warnings), _pointer("int *", returned), _pointer("int *", faults),
            ffi.NULL if kinstat is None else kinstat.pointer,
            *(summary.arguments() if summary is not None else (ffi.NULL,) * 4),
        )
        if status < 0:
            raise KingenError("the host emulator could not map guarded buffers (out of memory?)")
        if summary is None:
            return Calls(returned=returned, solutions=solutions, warnings=warnings, faults=faults)
        solutions.flags.writeable = False
        return Calls(returned=returned, solutions=solutions, warnings=warnings, faults=faults,
                     branch_values=summary.branch_values, repeats=summary.repeats.astype(bool))

    def batch_runner(self, t6):
        """A function that runs the unguarded C batch driver over ``t6`` (n, 4, 4) into buffers
        allocated here once: what it costs is the routine's own time, for benchmarks. Every
        call writes the same solutions[][] and warnings[] (block 0), as a host's calls do, so
        the figure is the routine's, not that of streaming n outputs through memory (for
        CEART's 64 postures 3 KB a call, which took as long as the routine itself)."""
        t6 = np.ascontiguousarray(t6, dtype=float).reshape(-1, 4, 4)
        count = t6.shape[0]
        zeros = np.zeros(6)
        solutions = np.empty(self.dof * self.postures)
        warnings = np.empty(self.postures, dtype=np.intc)
        returned = np.empty(count, dtype=np.intc)
        arguments = (
            ffi.cast("void *", self.function), count, _pointer("double *", t6), _pointer("double *", zeros),
            _pointer("double *", zeros), _pointer("double *", solutions), 0,
            _pointer("int *", warnings), 0, _pointer("int *", returned), ffi.NULL,
        )
        keep_alive = (t6, zeros, solutions, warnings, returned)

        def run():
            host().kingen_host_run_batch(*arguments)
            return keep_alive

        return run

    def each_runner(self, t6):
        """A function that calls the routine once per T6 through cffi, as a Python host would:
        the per-call overhead figure of benchmarks."""
        t6 = np.ascontiguousarray(t6, dtype=float).reshape(-1, 4, 4)
        zeros = np.zeros(6)
        solutions = np.empty(self.dof * self.postures)
        warnings = np.empty(self.postures, dtype=np.intc)
        pointers = (_pointer("double *", zeros), _pointer("double *", zeros))
        solutions_p, warnings_p = _pointer("double *", solutions), _pointer("int *", warnings)
        matrices = [ffi.cast("double (*)[4]", _pointer("double *", t6) + 16 * i) for i in range(t6.shape[0])]
        function = self.function

        def run():
            for matrix in matrices:
                function(*pointers, matrix, solutions_p, warnings_p, ffi.NULL)
            return t6, zeros, solutions, warnings

        return run


def _dialog(values):
    """The six Length or Offset fields as a contiguous array (zeros: all empty)."""
    array = np.zeros(6) if values is None else np.array(values, dtype=float).reshape(6)
    return np.ascontiguousarray(array)


class _BranchSummary:
    """The tables and outputs of kingen_host_run_guarded's summary by limb branch of ``robot``
    over ``count`` calls."""

    def __init__(self, robot, count):
        self._first_postures = np.array(representative_postures(robot), dtype=np.intc)
        self._branch_of = np.array(branch_table(robot), dtype=np.intc)
        self.branch_values = np.empty((count, robot.joint_count, 2))
        self.repeats = np.empty(count, dtype=np.intc)

    def arguments(self):
        return (_pointer("int *", self._first_postures), _pointer("int *", self._branch_of),
                _pointer("double *", self.branch_values), _pointer("int *", self.repeats))


def _pointer(ctype, array):
    return ffi.cast(ctype, ffi.from_buffer(array))


class KinStat:
    """A DLM_Data_KinStat for ``robot`` as DELMIA fills it (joint types, values, limits).

    Keeps its arrays alive as long as the object lives; pass it to Plugin.call.
    """

    def __init__(self, robot, joint_values=None, kin_mode=0):
        lower, upper = robot.travel_limits()
        self.types = ffi.new("int[]", [
            abi.CONSTANTS[abi.KINSTAT_JOINT_TYPES[t.name]] for t in robot.joint_types
        ])
        self.values = ffi.new("double[]", list(joint_values if joint_values is not None else np.zeros(robot.joint_count)))
        self.lower = ffi.new("double[]", [float(v) if np.isfinite(v) else -1e30 for v in lower])
        self.upper = ffi.new("double[]", [float(v) if np.isfinite(v) else 1e30 for v in upper])
        self.pointer = ffi.new("DLM_Data_KinStat *")
        self.pointer.dof_count = robot.joint_count
        self.pointer.joint_types = self.types
        self.pointer.kin_mode = kin_mode
        self.pointer.joint_values = self.values
        self.pointer.jnt_trvl_lmts[0] = self.lower
        self.pointer.jnt_trvl_lmts[1] = self.upper


def host_state():
    """(kin_check_definition calls, last dof, last solution count) recorded by the host."""
    lib = host()
    return lib.kingen_host_check_calls(), lib.kingen_host_last_dof(), lib.kingen_host_last_solutions()
