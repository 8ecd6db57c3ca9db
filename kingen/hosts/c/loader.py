"""Loading a C host library (generated or hand-written with the same header) through cffi,
and calling it over batches from C (the batch driver ``kingen_c_batch.c``, built once per
content in the cache). Loading runs the library's code: callers do it in a child process.

Units: the library's and kingen's are the same, mm and radians; kingen's T6 is the transposed
homogeneous matrix, the library's pose the row-major one.
"""

from pathlib import Path

import cffi
import numpy as np

from ...conventions import matrix_from_t6
from ...errors import KingenError, PluginDefect
from ...kinematics.routine import Calls
from ...runtime.compiler import compile_c, compiler_command
from ...runtime.file_gate import refuse_special_file
from ...runtime.files import cache_dir, cached, digest, write_atomic
from ...defaults import DEFAULT_TIMEOUT, VERSION
from .checks import CHECKS
from .render import has_machine_pose

BATCH = Path(__file__).resolve().parent / "templates" / "kingen_c_batch.c"
ENTRY_POINTS = ("inverse", "inverse_posture", "forward", "jacobian", "static_loads", "default_geometry")
"""What the header declares for every robot (``<routine>_<name>``); six-limb robots add
``direct_index``, machines with task coordinates and no wrist ``machine_pose``."""
OPTIONAL_ENTRY_POINTS = ("static_loads",)
"""What a library may leave out (a hand-written one): its checks then judge nothing ('c loads'
not exercised) instead of the library being refused."""


def entry_points(robot):
    """What ``robot``'s library exports (``<routine>_<name>``): :data:`ENTRY_POINTS` and its own."""
    return (*ENTRY_POINTS, *(("direct_index",) if robot.dof == 6 else ()),
            *(("machine_pose",) if has_machine_pose(robot) else ()))
_batch_ffi = cffi.FFI()
_batch_ffi.cdef("""
void kingen_c_inverse_batch(void *function, const void *geometry, int count, const double *poses, double *joints,
                            int joint_stride, int *warnings, int warning_stride, int *returns);
void kingen_c_forward_batch(void *function, const void *geometry, int count, const double *joints, int dof,
                            const int *postures, const double *seeds, double *poses, int *iterations, int *returns);
void kingen_c_machine_pose_batch(void *function, int count, const double *poses, double *machines, int *returns);
void kingen_c_timed_batch(void *function, const void *geometry, int calls, int pool_count, const double *poses,
                          double *joints, int *warnings, double *ns);
""")
_driver = None


def batch_library(timeout=DEFAULT_TIMEOUT):
    """The batch driver library's path, built once per content and compiler."""
    source, command = BATCH.read_text(), compiler_command()
    folder = cache_dir() / f"c-batch-{digest(VERSION, source, *command)[:16]}"
    library = folder / "libkingen_c_batch.so"

    def make():
        write_atomic(folder / BATCH.name, source)
        compile_c([folder / BATCH.name], library, ["-std=c99", "-Wall", "-Wextra", "-Werror", "-O2", "-fPIC", "-shared"], timeout=timeout)

    cached(folder, library, make, {BATCH.name: source})
    return library


def batch_driver(timeout=DEFAULT_TIMEOUT):
    """The batch driver library (batch_library), loaded once per process."""
    global _driver
    if _driver is None:
        _driver = _batch_ffi.dlopen(str(batch_library(timeout)))
    return _driver


def poses_of(t6):
    """Row-major homogeneous poses (n, 16) of kingen's T6 (n, 4, 4)."""
    return np.ascontiguousarray(matrix_from_t6(np.asarray(t6, dtype=float).reshape(-1, 4, 4)).reshape(-1, 16))


class Library:
    """A loaded C host library for ``robot``: ``routine`` is its prefix, kingen_<name>.
    KingenError for what is the user's (no such file), PluginDefect for a library lacking a
    function of the header but those of :data:`OPTIONAL_ENTRY_POINTS` (``functions`` holds what
    it exports)."""

    summarises_branches = False

    checks = CHECKS

    def __init__(self, library, routine, robot):
        path = Path(library).resolve()
        refuse_special_file(path)
        if not path.is_file():
            raise KingenError(f"{path}: no such library")
        self.ffi = cffi.FFI()
        self.ffi.cdef(f"""
        int {routine}_inverse(const void *geometry, const double *pose, double *joints, int *warnings);
        int {routine}_inverse_posture(const void *geometry, const double *pose, int posture, double *joints);
        int {routine}_forward(const void *geometry, const double *joints, int posture, const double *seed,
                              double *pose, int *iterations);
        int {routine}_jacobian(const void *geometry, const double *pose, int posture, double *jacobian);
        int {routine}_direct_index(const void *geometry, const double *pose, int posture, double *index);
        int {routine}_machine_pose(const double *pose, double *machine);
        int {routine}_static_loads(const void *geometry, const double *pose, int posture, const double *payload,
                                   double *forces);
        extern double {routine}_default_geometry;
        """)
        try:
            self.library = self.ffi.dlopen(str(path))
        except OSError as error:
            raise PluginDefect(f"the library cannot be loaded: {str(error).split('.  Additionally')[0]}") from None
        self.functions = {}
        for name in entry_points(robot):
            try:
                self.functions[name] = (self.ffi.addressof(self.library, f"{routine}_{name}") if name == "default_geometry"
                                        else getattr(self.library, f"{routine}_{name}"))
            except (AttributeError, KeyError):
                if name in OPTIONAL_ENTRY_POINTS:
                    continue
                raise PluginDefect(f"the library does not export {routine}_{name}") from None
        self.geometry = self.ffi.cast("void *", self.functions["default_geometry"])
        self.routine, self.robot = routine, robot
        self.dof, self.postures = robot.joint_count, robot.postures
        self.driver = batch_driver()

    def reset_host(self):
        pass

    def _pointer(self, ctype, array):
        return _batch_ffi.cast(ctype, _batch_ffi.from_buffer(array))

    def inverse(self, poses):
        """The inverse on row-major poses (n, 16): (joints (n, dof, postures), warnings (n, postures), returns (n,))."""
        poses = np.ascontiguousarray(poses, dtype=float)
        count = len(poses)
        joints = np.full((count, self.dof, self.postures), np.nan)
        warnings = np.full((count, self.postures), -1, dtype=np.intc)
        returns = np.empty(count, dtype=np.intc)
        self.driver.kingen_c_inverse_batch(self._function("inverse"), self._geometry(), count,
                                           self._pointer("const double *", poses), self._pointer("double *", joints),
                                           self.dof * self.postures, self._pointer("int *", warnings), self.postures,
                                           self._pointer("int *", returns))
        return joints, warnings, returns

    def forward(self, joints, postures, seeds):
        """The forward from joints (n, dof) of ``postures`` (n,) and row-major seeds (n, 16):
        (poses (n, 16), iterations (n,), returns (n,))."""
        joints = np.ascontiguousarray(joints, dtype=float)
        postures = np.ascontiguousarray(postures, dtype=np.intc)
        seeds = np.ascontiguousarray(seeds, dtype=float)
        count = len(joints)
        poses, iterations = np.full((count, 16), np.nan), np.zeros(count, dtype=np.intc)
        returns = np.empty(count, dtype=np.intc)
        self.driver.kingen_c_forward_batch(self._function("forward"), self._geometry(), count,
                                           self._pointer("const double *", joints), self.dof,
                                           self._pointer("const int *", postures), self._pointer("const double *", seeds),
                                           self._pointer("double *", poses), self._pointer("int *", iterations),
                                           self._pointer("int *", returns))
        return poses, iterations, returns

    def jacobian(self, pose, posture):
        """(jacobian (dof, 6), warning) of one row-major pose (16,) and posture."""
        pose = np.ascontiguousarray(pose, dtype=float)
        rows = np.full((self.dof, 6), np.nan)
        warning = self.functions["jacobian"](self.geometry, self.ffi.from_buffer("double[]", pose), posture,
                                             self.ffi.from_buffer("double[]", rows))
        return rows, warning

    def machine_pose(self, poses):
        """A machine with task coordinates: the machine's pose for each row-major pose (n, 16):
        (machine poses (n, 16), statuses (n,))."""
        poses = np.ascontiguousarray(poses, dtype=float)
        machines, returns = np.full((len(poses), 16), np.nan), np.empty(len(poses), dtype=np.intc)
        self.driver.kingen_c_machine_pose_batch(self._function("machine_pose"), len(poses),
                                                self._pointer("const double *", poses), self._pointer("double *", machines),
                                                self._pointer("int *", returns))
        return machines, returns

    def direct_index(self, pose, posture):
        """(direct index mm, warning) of one row-major pose (16,) and posture (six-limb robots)."""
        pose = np.ascontiguousarray(pose, dtype=float)
        index = self.ffi.new("double *")
        warning = self.functions["direct_index"](self.geometry, self.ffi.from_buffer("double[]", pose), posture, index)
        return index[0], warning

    def static_loads(self, pose, posture, payload):
        """(forces (dof,) N or N m, return) of one row-major pose (16,) and posture holding
        ``payload`` (7,): mass kg, centre (3,) mm in the platform frame, gravity (3,) m/s^2."""
        pose, payload = np.ascontiguousarray(pose, dtype=float), np.ascontiguousarray(payload, dtype=float)
        forces = np.full(self.dof, np.nan)
        returned = self.functions["static_loads"](self.geometry, self.ffi.from_buffer("double[]", pose), posture,
                                                  self.ffi.from_buffer("double[]", payload),
                                                  self.ffi.from_buffer("double[]", forces))
        return forces, returned

    def _function(self, name):
        return _batch_ffi.cast("void *", int(self.ffi.cast("uintptr_t", self.functions[name])))

    def _geometry(self):
        return _batch_ffi.cast("void *", int(self.ffi.cast("uintptr_t", self.geometry)))

    def batch_runner(self, t6):
        """A function running the inverse over ``t6`` (n, 4, 4) from C into buffers made here once:
        the library's own time, for benchmarks. Every call writes the same joints[][] and
        warnings[] (strides 0), as a controller's calls do and as DELMIA's batch runner does, so
        the figure is the library's, not that of streaming n outputs through memory."""
        poses = poses_of(t6)
        count = len(poses)
        joints = np.empty((self.dof, self.postures))
        warnings, returns = np.empty(self.postures, dtype=np.intc), np.empty(count, dtype=np.intc)
        arguments = (self._function("inverse"), self._geometry(), count, self._pointer("double *", poses),
                     self._pointer("double *", joints), 0, self._pointer("int *", warnings), 0,
                     self._pointer("int *", returns))

        def run():
            self.driver.kingen_c_inverse_batch(*arguments)
            return poses, joints, warnings, returns  # the buffers live as long as the runner

        return run

    def each_runner(self, t6):
        """A function calling the inverse once per T6 through cffi, as a Python caller would."""
        poses = poses_of(t6)
        joints, warnings = np.empty(self.dof * self.postures), np.empty(self.postures, dtype=np.intc)
        pointers = [self.ffi.from_buffer("double[]", pose) for pose in poses]
        inverse, geometry = self.functions["inverse"], self.geometry
        joints_pointer, warnings_pointer = self.ffi.from_buffer("double[]", joints), self.ffi.from_buffer("int[]", warnings)

        def run():
            for pose in pointers:
                inverse(geometry, pose, joints_pointer, warnings_pointer)
            return poses, joints

        return run

    def call_times(self, t6, calls):
        """Nanoseconds (calls,) of each of ``calls`` inverse calls over the poses ``t6`` taken in
        turn, each call timed singly on the monotonic clock from C."""
        poses = poses_of(t6)
        joints, warnings = np.empty(self.dof * self.postures), np.empty(self.postures, dtype=np.intc)
        ns = np.empty(calls)
        self.driver.kingen_c_timed_batch(self._function("inverse"), self._geometry(), calls, len(poses),
                                         self._pointer("const double *", poses), self._pointer("double *", joints),
                                         self._pointer("int *", warnings), self._pointer("double *", ns))
        return ns

    def call(self, t6, link_lengths=None, link_offsets=None):
        """The inverse on every T6 (n, 4, 4), mm, as Calls. The library takes a calibrated
        geometry as a struct, not as calibration fields: fields holding a value are refused."""
        if any(np.any(np.asarray(fields, dtype=float) != 0.0) for fields in (link_lengths, link_offsets)
               if fields is not None):
            raise KingenError("--link-lengths/--link-offsets: the C library takes a calibrated geometry as its "
                              "struct, not as calibration fields (SETUP.md: loading calibrated geometry)")
        joints, warnings, returns = self.inverse(poses_of(t6))
        return Calls(returned=returns, solutions=joints, warnings=warnings, faults=np.zeros(len(returns), dtype=np.intc))
