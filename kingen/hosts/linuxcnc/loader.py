"""Loading a LinuxCNC kinematics module as LinuxCNC's motion controller does, without LinuxCNC:
the HAL stand-in (:func:`kingen.hosts.linuxcnc.build.harness`) is loaded first with global
symbol visibility, so the module's ``hal_*`` and ``rtapi_*`` imports resolve to it; the module
is loaded, its ``rtapi_app_main`` run, its parameters set (setp), and its
``kinematicsInverse`` and ``kinematicsForward`` called from C over whole batches.

Units: kingen's side is mm and radians (T6, Calls); the module's is the machine's units and
degrees (EmcPose, joints). Loading runs the module's code: callers do it in a child process.
"""

import shutil
import tempfile
from pathlib import Path

import cffi
import numpy as np

from ...conventions import pose_from_t6
from ...errors import KingenError, PluginDefect
from ...runtime.file_gate import refuse_special_file
from ...kinematics.routine import WARNINGS, Calls
from .build import harness
from .render import translating
from .checks import CHECKS, WRIST_CHECKS
from .five_axis import world_of_t6

ffi = cffi.FFI()
ffi.cdef("""
void kingen_hal_forget(const char *prefix);
int kingen_hal_set(const char *name, double value);
int kingen_hal_get(const char *name, double *value);
int kingen_hal_count(void);
const char *kingen_hal_name(int index);
void kingen_batch(void *routine, int forward, int count, double *poses, double *joints, int *returns,
                  const char *pin, double *pins);
int rtapi_app_main(void);
int kinematicsForward(const double *joint, void *world, const unsigned long *fflags, unsigned long *iflags);
int kinematicsInverse(const void *world, double *joint, const unsigned long *iflags, unsigned long *fflags);
int kinematicsType(void);
int kinematicsSwitchable(void);
""")
ENTRY_POINTS = ("kinematicsForward", "kinematicsInverse", "kinematicsType", "rtapi_app_main")
JOINT_SLOTS = 16
"""The joint array LinuxCNC passes (EMCMOT_MAX_JOINTS)."""
_harness = None


def _hal():
    global _harness
    if _harness is None:
        _harness = ffi.dlopen(str(harness()), ffi.RTLD_NOW | ffi.RTLD_GLOBAL)
    return _harness


def _pointer(ctype, array):
    return ffi.cast(ctype, ffi.from_buffer(array))


def _batch(routine, forward, poses, joints, pin):
    """The HAL stand-in's kingen_batch: ``routine`` (kinematicsInverse, or with ``forward``
    kinematicsForward) called once per row of ``poses`` (n, 9) and ``joints`` (n, 16),
    writing the other (forward: the pose, started from the one given) in place: (returns
    (n,), the pin named ``pin`` after each call (n,), NaN without one)."""
    count = len(poses)
    returns, pins = np.empty(count, dtype=np.intc), np.full(count, np.nan)
    _hal().kingen_batch(ffi.cast("void *", routine), forward, count, _pointer("double *", poses),
                        _pointer("double *", joints), _pointer("int *", returns), pin, _pointer("double *", pins))
    return returns, pins


class Module:
    """A loaded kinematics module for ``robot`` (a one-posture view: the joints LinuxCNC sees).

    ``routine`` is the HAL module name (``<name>kins``, ``genhexkins``; kingen's own cut where its
    pin names would be too long: kingen.hosts.linuxcnc.render.module_name), its HAL component's
    too, which starts its pins' and parameters' names. ``setp`` is {name: value} set after ``rtapi_app_main``.
    Raises KingenError for what is the user's (no such file, not a library) and PluginDefect
    for a module that lacks an entry point or whose rtapi_app_main fails."""

    checks = CHECKS

    def __init__(self, library, routine, robot, setp=None, inch=False):
        hal = _hal()
        path = Path(library).resolve()
        refuse_special_file(path)
        if not path.is_file():
            raise KingenError(f"{path}: no such module")
        # in a child (kingen.runtime.isolation.run_in_child) the temporary folder is the parent's to remove,
        # so the copy goes even when the module's constructor never lets the child get to rmtree below
        folder = Path(tempfile.mkdtemp(prefix="kingen-module-"))
        copy = folder / path.name  # a fresh copy: each load gets the module's own static state
        shutil.copy2(path, copy)
        hal.kingen_hal_forget(f"{routine}.".encode())
        try:
            self.library = ffi.dlopen(str(copy), ffi.RTLD_NOW)
        except OSError as error:
            raise PluginDefect(f"the module cannot be loaded: {str(error).split('.  Additionally')[0]}") from None
        finally:
            shutil.rmtree(folder, ignore_errors=True)
        for name in ENTRY_POINTS:
            try:
                getattr(self.library, name)
            except AttributeError:
                raise PluginDefect(f"the module does not export {name}") from None
        status = self.library.rtapi_app_main()
        if status != 0:
            raise PluginDefect(f"rtapi_app_main returned {status}")
        for name, value in (setp or {}).items():
            if hal.kingen_hal_set(name.encode(), float(value)) != 0:
                raise KingenError(f"--setp {name}: the module has no such pin or parameter")
        self.routine, self.robot = routine, robot
        self.dof, self.postures = robot.joint_count, 1
        self.pose_coordinates = np.array([True] * 3 + [not translating(robot)] * 3)
        if robot.wrist is not None:
            self.checks = WRIST_CHECKS
        self.scale = 25.4 if inch else 1.0
        self.status_pin = self._pin("status")
        self.iterations_pin = self._pin("iterations")
        if self.status_pin == ffi.NULL:
            self.warning_vocabulary = ("WARN_GOOD_SOLUTION", "WARN_UNREACHABLE")
            """Without a status pin the module tells only success from failure (its return)."""
        self._warm_up()

    def _warm_up(self):
        """A switchable module (genhexkins, built on LinuxCNC's switchkins.c) starts its first
        forward after loading from a static all-zero pose instead of the pose passed in, as in
        LinuxCNC's first servo cycle: that call is made here, with the joints of the verification
        home, and its return kept (``first_forward``), so that every later call starts where it
        is told."""
        self.first_forward = None
        try:
            switchable = self.library.kinematicsSwitchable()
        except AttributeError:
            return
        if switchable:
            home = np.zeros((1, 9))
            home[0, :3] = np.asarray(self.robot.verification.home[:3]) / self.scale
            home[0, 3:6] = self.robot.verification.home[3:]
            joints, _, _ = self.inverse(home)
            _, returns, _ = self.forward(np.nan_to_num(joints), home)
            self.first_forward = int(returns[0])

    def parameter(self, name):
        """The value of the module's pin or parameter ``name``, or None when it has none."""
        value = ffi.new("double *")
        return value[0] if _hal().kingen_hal_get(name.encode(), value) == 0 else None

    def _pin(self, suffix):
        """The C name of the pin <module>.<suffix>, or NULL when the module has none."""
        name = f"{self.routine}.{suffix}"
        return ffi.new("char[]", name.encode()) if self.parameter(name) is not None else ffi.NULL

    def reset_host(self):
        pass

    def hal_names(self):
        """Every pin and parameter the module made (named after it)."""
        hal = _hal()
        names = [ffi.string(hal.kingen_hal_name(index)).decode() for index in range(hal.kingen_hal_count())]
        return [name for name in names if name.startswith(f"{self.routine}.")]

    def emc_poses(self, t6):
        """EmcPose numbers (n, 9): x y z in machine units, a b c degrees, u v w 0, from T6 (mm);
        with a wrist, the five-axis world (:func:`.five_axis.world_of_t6`)."""
        if self.robot.wrist is not None:
            return world_of_t6(self.robot, t6, self.scale)
        pose = pose_from_t6(np.asarray(t6, dtype=float).reshape(-1, 4, 4))
        world = np.zeros((len(pose), 9))
        world[:, :3] = pose[:, :3] / self.scale
        world[:, 3:6] = pose[:, 3:]
        return world

    def inverse(self, world):
        """kinematicsInverse on EmcPose numbers (n, 9): (joints (n, 16) machine units and degrees,
        returns (n,), status pin (n,) or NaN without one)."""
        world = np.ascontiguousarray(world, dtype=float)
        joints = np.full((len(world), JOINT_SLOTS), np.nan)
        return (joints, *_batch(self.library.kinematicsInverse, 0, world, joints, self.status_pin))

    def static_loads(self, world, payload):
        """The pins load.0 .. load.<joints - 1> (N or N m) after kinematicsInverse at each of the
        EmcPose numbers ``world`` (n, 9), holding ``payload`` (mass kg, centre (3,) machine units
        in the platform frame, a wrist's tool frame, gravity (3,) m/s^2) set into the parameters payload.mass,
        payload.centre.x|y|z and gravity.x|y|z first: (loads (n, dof), returns (n,)), NaN where
        the module has no such pin."""
        mass, centre, gravity = payload
        hal = _hal()
        for suffix, value in (("payload.mass", mass), *zip(("payload.centre.x", "payload.centre.y", "payload.centre.z",
                                                            "gravity.x", "gravity.y", "gravity.z"), (*centre, *gravity))):
            hal.kingen_hal_set(f"{self.routine}.{suffix}".encode(), float(value))
        world = np.ascontiguousarray(world, dtype=float)
        loads, returns = np.full((len(world), self.dof), np.nan), np.zeros(len(world), dtype=np.intc)
        for index in range(self.dof):  # each pin read after every call: one pass per pin
            pin = self._pin(f"load.{index}")
            if pin != ffi.NULL:
                returns, loads[:, index] = _batch(self.library.kinematicsInverse, 0, world.copy(),
                                                  np.full((len(world), JOINT_SLOTS), np.nan), pin)
        return loads, returns

    def forward(self, joints, seeds):
        """kinematicsForward on joints (n, 16) from seeds (n, 9): (poses (n, 9), returns, iterations)."""
        joints = np.ascontiguousarray(joints, dtype=float)
        poses = np.ascontiguousarray(seeds, dtype=float).copy()
        return (poses, *_batch(self.library.kinematicsForward, 1, poses, joints, self.iterations_pin))

    def batch_runner(self, t6):
        """A function running kinematicsInverse over ``t6`` (n, 4, 4) from C into buffers made
        here once: the module's own time, for benchmarks."""
        world = np.ascontiguousarray(self.emc_poses(t6))
        count = len(world)
        joints, returns = np.empty((count, JOINT_SLOTS)), np.empty(count, dtype=np.intc)
        arguments = (ffi.cast("void *", self.library.kinematicsInverse), 0, count, _pointer("double *", world),
                     _pointer("double *", joints), _pointer("int *", returns), ffi.NULL, ffi.NULL)

        def run():
            _hal().kingen_batch(*arguments)
            return world, joints, returns

        return run

    def each_runner(self, t6):
        """A function calling kinematicsInverse once per T6 through cffi, as a Python caller would."""
        world = np.ascontiguousarray(self.emc_poses(t6))
        joints = np.empty(JOINT_SLOTS)
        flags = ffi.new("unsigned long[2]")
        poses = [ffi.cast("void *", _pointer("double *", world) + 9 * index) for index in range(len(world))]
        inverse, joints_pointer = self.library.kinematicsInverse, _pointer("double *", joints)

        def run():
            for pose in poses:
                inverse(pose, joints_pointer, flags, flags + 1)
            return world, joints

        return run

    def joint_scale(self):
        """Per joint: factor from the module's joint units to kingen's (mm, radians)."""
        return np.where(self.robot.revolute, np.pi / 180.0, self.scale)

    def call(self, t6, link_lengths=None, link_offsets=None):
        """The inverse on every T6 (n, 4, 4), mm, as Calls in kingen's units: one posture; the
        status pin's warning where the module has one, else good (0) or unreachable."""
        joints, returns, statuses = self.inverse(self.emc_poses(t6))
        solutions = (joints[:, :self.dof] * self.joint_scale())[:, :, None]
        # A failed call's joints mean nothing to LinuxCNC (it stops): kingen's contract wants them finite.
        solutions[(returns != 0)[:, None, None] & ~np.isfinite(solutions)] = 0.0
        fallback = np.where(returns == 0, WARNINGS["WARN_GOOD_SOLUTION"], WARNINGS["WARN_UNREACHABLE"])
        warnings = np.where(np.isfinite(statuses), statuses, fallback).astype(np.intc)[:, None]
        return Calls(returned=returns, solutions=solutions, warnings=warnings, faults=np.zeros(len(t6), dtype=np.intc))
