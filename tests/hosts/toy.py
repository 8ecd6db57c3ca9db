"""A toy host, defined here and registered by the tests, touching no kingen file: a routine
``int toy_<name>(int count, const double *t6, double *joints, int *status)`` for robots of
legs only, rendered from kingen's shared view-model with its own template, compiled with
kingen's compiler, loaded with cffi, verified by kingen's shared checks and one of its own,
and packaged as a folder written whole."""

import shutil
from pathlib import Path

import cffi
import numpy as np

from kingen.runtime.compiler import compile_c, compiler_command
from kingen.errors import KingenError
from kingen.runtime.files import default_out_dir, write_atomic, write_folder
from kingen.hosts import BuildResult, Host
from kingen.hosts.render import robot_view, template
from kingen.kinematics.routine import Calls, WARNINGS
from kingen.verify.checks import SHARED, Check, VerifyCheck

TEMPLATES = Path(__file__).parent


class ReturnsZero(VerifyCheck):
    """The toy interface's own clause: the routine returns 0 for every batch."""

    name = "toy return"
    needs = "routine"
    item = "interface"

    def run(self, context):
        home = np.eye(4)[None].copy()
        home[0, 3, :3] = context.robot.verification.home[:3]
        returned = context.routine.returned_for(home)
        return [Check("toy return", returned == 0, f"the routine returns {returned} for the home position")]


CHECKS = (SHARED[0], ReturnsZero(), *SHARED[1:])


class ToyRoutine:
    """A loaded toy routine, called on a batch of T6 (n, 4, 4) through cffi."""

    checks = CHECKS

    def __init__(self, library, routine):
        self.ffi = cffi.FFI()
        self.ffi.cdef(f"int {routine}(int count, const double *t6, double *joints, int *status); "
                      f"int {routine}_dof(void);")
        self.library = self.ffi.dlopen(str(library))
        self.function = getattr(self.library, routine)
        self.routine, self.dof, self.postures = routine, getattr(self.library, f"{routine}_dof")(), 1

    def reset_host(self):
        pass

    def returned_for(self, t6):
        t6 = np.ascontiguousarray(t6, dtype=float)
        joints, status = np.empty((len(t6), self.dof)), np.empty(len(t6), dtype=np.intc)
        return self.function(len(t6), self.ffi.cast("double *", self.ffi.from_buffer(t6)),
                             self.ffi.cast("double *", self.ffi.from_buffer(joints)),
                             self.ffi.cast("int *", self.ffi.from_buffer(status)))

    def call(self, t6, link_lengths=None, link_offsets=None):
        t6 = np.ascontiguousarray(t6, dtype=float).reshape(-1, 4, 4)
        joints, status = np.empty((len(t6), self.dof)), np.empty(len(t6), dtype=np.intc)
        returned = self.function(len(t6), self.ffi.cast("double *", self.ffi.from_buffer(t6)),
                                 self.ffi.cast("double *", self.ffi.from_buffer(joints)),
                                 self.ffi.cast("int *", self.ffi.from_buffer(status)))
        warnings = np.where(status == 0, WARNINGS["WARN_GOOD_SOLUTION"], WARNINGS["WARN_UNREACHABLE"])
        return Calls(returned=np.full(len(t6), returned, dtype=np.intc), solutions=joints[:, :, None],
                     warnings=warnings.astype(np.intc)[:, None], faults=np.zeros(len(t6), dtype=np.intc))


class ToyHost(Host):
    name = "toy"
    description = "a toy host of the tests"
    checks = CHECKS

    def routine_name(self, robot):
        return f"toy_{robot.name}"

    def render(self, robot):
        if any(limb.model != "leg" for limb in robot.limbs):
            raise KingenError(f"{robot.path}: limbs: the toy host drives legs only")
        return {f"toy_{robot.name}.c": template("toy.c.j2", TEMPLATES).render(**robot_view(robot, self))}

    def write_source(self, robot, out_dir):
        for name, text in self.render(robot).items():
            write_atomic(Path(out_dir) / name, text)
        return Path(out_dir) / f"toy_{robot.name}.c"

    def build(self, robot, out_dir=None, *, target=None, defines=(), timeout=300.0):
        out_dir = Path(out_dir or default_out_dir(robot) / "toy")
        source = self.write_source(robot, out_dir)
        library = self.build_source(source, out_dir, timeout=timeout)
        return BuildResult(source, library, self.routine_name(robot), compiled=True)

    def build_source(self, source, out_dir, *, timeout=300.0):
        library = Path(out_dir) / f"lib{Path(source).stem}.so"
        compile_c([source], library, ["-std=c89", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O2", "-fPIC",
                                      "-shared"], compiler=compiler_command(), timeout=timeout)
        return library

    def load(self, library, routine, robot):
        return ToyRoutine(library, routine)

    def package(self, robot, out_dir, *, target=None, timeout=300.0):
        def fill(staging):
            built = self.build(robot, staging / ".build", timeout=timeout)
            write_atomic(staging / built.library.name, built.library.read_bytes(), executable=True)
            write_atomic(staging / built.source.name, built.source.read_text())
            shutil.rmtree(staging / ".build")
            write_atomic(staging / "README.txt", f"{robot.name}: call {built.routine}(count, t6, joints, status)\n")

        write_folder(out_dir, fill, f"written by the toy host for {robot.name}\n")
        return [Path(out_dir) / name for name in (f"libtoy_{robot.name}.so", f"toy_{robot.name}.c", "README.txt")]
