"""The tilt judge: the largest tilt of a six-crank (6-RUS) platform towards each azimuth,
in compiled C (tilt_judge.c beside this module), for the design optimiser.

It decides every pose exactly as :func:`kingen.design.analysis.tilt_limits` (the numpy reference)
does, for robots of six cranks without travel limits, at a fraction of its cost: poses are
judged one by one in C and each azimuth stops at its first failing step. ``tests/
test_tilt_judge.py`` proves the two agree on random designs. Poses mm and degrees at this
module's boundary; the C works in radians.
"""

import functools
from pathlib import Path

import cffi
import numpy as np

from ..defaults import VERSION
from .analysis import CAUSES, CROSSING, Settings, singular_index_mm
from ..kinematics.loads import load_limited
from ..runtime.compiler import compile_c, compiler_command
from ..runtime.files import cache_dir, cached, digest, write_atomic

DECLARATIONS = """
typedef struct {
    double pivot[6][3]; double cos_direction[6]; double sin_direction[6]; double crank_length[6];
    double rod_length[6]; double platform[6][3]; int branch[6]; double home[6]; double index_threshold;
    double home_det_sign; int euler; int collision; double rod_radius, crank_radius; int cranks_collide_at_zero;
} kingen_design;
long kingen_tilt_table(const kingen_design *design, const double *azimuths, int count_azimuths,
                       const double *tilts, int count_tilts, int *first_stop, int *cause);
void kingen_home(const kingen_design *design, double *index, double *det_sign, int *cranks_collide_at_zero);
"""
COLLISION_MODELS = {"segments": 1, "thesis": 2}


def judges(robot):
    """Whether the compiled judge decides this robot: six limbs whose model gives the judge its
    geometry (LimbModel.tilt_judge_row: cranks), no travel limits, no load limits
    (kingen.design.load_analysis judges those)."""
    return (robot.dof == 6 and all(limb.tilt_judge_row() is not None and limb.travel is None for limb in robot.limbs)
            and not load_limited(robot))


@functools.lru_cache(maxsize=1)
def _library():
    """(ffi, library): the judge compiled once per content and compiler into kingen's cache."""
    source = (Path(__file__).resolve().parent / "tilt_judge.c").read_text()
    command = compiler_command()
    folder = cache_dir() / f"tilt-judge-{digest(VERSION, source, *command)[:16]}"
    library = folder / "libkingen_tilt_judge.so"

    def make():
        write_atomic(folder / "tilt_judge.c", source)
        compile_c([folder / "tilt_judge.c"], library, ["-O3", "-funroll-loops", "-shared", "-fPIC", "-lm"])

    cached(folder, library, make, {"tilt_judge.c": source})
    ffi = cffi.FFI()
    ffi.cdef(DECLARATIONS)
    return ffi, ffi.dlopen(str(library))


def home(robot, posture, settings=Settings()):
    """(direct index mm, sign of det W (0: unreachable or singular), whether the thesis's
    cranks at angle 0 collide) at the verification home, as the judge computes them
    (analysis.home_values in numpy)."""
    _, values = _design(robot, posture, settings)
    return values


def _design(robot, posture, settings):
    """(the C design struct, its home values) for ``robot`` in ``posture``."""
    ffi, library = _library()
    design = ffi.new("kingen_design *")
    branches = robot.posture_branches(posture)
    position = np.array(robot.verification.home, dtype=float)
    for number, limb in enumerate(robot.limbs):
        for member, value in limb.tilt_judge_row().items():
            getattr(design, member)[number] = value
        design.branch[number] = int(branches[number])
    design.home = [*map(float, position[:3]), *map(float, np.radians(position[3:]))]
    design.euler = int(settings.tilt_convention == "euler")
    if robot.collision is not None:
        design.collision = COLLISION_MODELS[settings.collision]
        design.rod_radius = robot.collision.get("rod_radius", 0.0)
        design.crank_radius = robot.collision.get("crank_radius", 0.0)
    index, sign, cranks_collide = ffi.new("double *"), ffi.new("double *"), ffi.new("int *")
    library.kingen_home(design, index, sign, cranks_collide)
    floor = singular_index_mm(robot)
    thresholds = [value for value in (robot.direct_index_min, CROSSING * index[0], floor)
                  if np.isfinite(value or np.nan)]
    design.index_threshold = max(thresholds)
    design.home_det_sign = 0.0 if index[0] <= floor else sign[0]
    design.cranks_collide_at_zero = int(cranks_collide[0]) if design.collision == COLLISION_MODELS["thesis"] else 0
    return design, (float(index[0]), float(design.home_det_sign), bool(cranks_collide[0]))


def tilt_table(robot, posture, settings=Settings()):
    """[(max_tilt_deg, cause)] per azimuth of ``settings``, as analysis.tilt_limits gives them
    (the largest multiple of the tilt step up to which every step passes; 'none' up to the
    cap), and the number of poses judged."""
    ffi, library = _library()
    design, _ = _design(robot, posture, settings)
    azimuths, tilts = settings.azimuths, settings.tilts
    first = np.zeros(len(azimuths), dtype=np.intc)
    cause = np.zeros(len(azimuths), dtype=np.intc)
    judged = library.kingen_tilt_table(
        design, ffi.from_buffer("double[]", np.ascontiguousarray(np.radians(azimuths))), len(azimuths),
        ffi.from_buffer("double[]", np.ascontiguousarray(np.radians(tilts))), len(tilts),
        ffi.from_buffer("int[]", first), ffi.from_buffer("int[]", cause))
    table = [(round(float(tilts[max(stop - 1, 0)] if stop < len(tilts) else tilts[-1]), 6), CAUSES[code])
             for stop, code in zip(first, cause)]
    return table, int(judged)
