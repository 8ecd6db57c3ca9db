"""Packaging the C host's library for a controller engineer: ``include/`` and ``src/`` (the
header and source, as rendered), ``CMakeLists.txt`` (target ``kingen::<name>``, for
add_subdirectory and, installed, find_package), ``kingen_<name>.pc`` (pkg-config, relocatable),
``example/main.c`` (the verification home through the inverse and the forward, printed) and
``SETUP.md`` (units, frames, pose, postures, warnings, calibrated geometry). Written whole or
not at all; the source is compiled first, so a package never holds a library that does not build."""

import re
from pathlib import Path

import numpy as np

from ...conventions import matrix_from_pose
from ...defaults import DEFAULT_TIMEOUT, VERSION
from ...kinematics.forward import free_mask
from ...kinematics.home import judged_posture
from ...runtime.files import write_atomic, write_folder
from ..render import template
from ..wrist import sheet_words
from .build import build_library
from .render import TEMPLATES, view_model

SEED_OFFSET_MM = 0.5
"""The example's forward starts this far from the pose along each free translation."""


def _numbers(matrix):
    return ", ".join(repr(float(value)) for value in np.asarray(matrix).reshape(-1))


def _example_view(robot):
    """The example's pose (the verification home), its seed and the posture judged there."""
    home = np.array(robot.verification.home, dtype=float)
    seed = home.copy()
    free = free_mask(robot)
    seed[:3] += SEED_OFFSET_MM * free[:3]
    moved = [name for name, is_free in zip("xyz", free[:3]) if is_free]
    return {
        "pose": _numbers(matrix_from_pose(home)),
        "seed": _numbers(matrix_from_pose(seed)),
        "posture": judged_posture(robot).posture,
        "home_words": f"y z {home[0]:g} {home[1]:g} {home[2]:g} mm, roll pitch yaw {home[3]:g} {home[4]:g} "
                      f"{home[5]:g} degrees",
        "seed_words": f"{SEED_OFFSET_MM:g} mm off in {' '.join(moved)}" if moved else "at the pose",
    }


def _model_fields(view):
    """Per limb model: its geometry fields in the struct (the row's columns but its joint
    number and other hosts' calibration fields)."""
    return {model["name"]: ", ".join(key for key in model["rows"][0] if key not in ("joint", "name")
                                     and not key.endswith("_field")) for model in view["models"]}


def _calibration_example(view):
    """C lines of SETUP.md's example: the first row's first single-number field set to its value."""
    model = view["models"][0]
    row = model["rows"][0]
    field = next(key for key, value in row.items() if key not in ("joint", "name") and not key.endswith("_field")
                 and "," not in str(value))
    return [f"calibrated.{model['name']}s[0].{field} = {row[field]}; /* {row['name']}: the measured value */"]


def render_package(robot):
    """{relative path: text} of the package (pure)."""
    view = view_model(robot)
    prefix = view["prefix"]
    header, source = (template(name, TEMPLATES).render(**view) for name in ("header.c.j2", "source.c.j2"))
    version = ".".join(re.findall(r"\d+", VERSION)[:3]) or "0"
    package_view = {**view, **_example_view(robot), "cmake_version": version, "model_fields": _model_fields(view),
                    "calibration_example": _calibration_example(view),
                    "wrist_sheet": sheet_words(robot) if robot.wrist is not None else None}
    return {
        f"include/{prefix}.h": header,
        f"src/{prefix}.c": source,
        "CMakeLists.txt": template("CMakeLists.txt.j2", TEMPLATES).render(**package_view),
        f"{prefix}.pc": template("kingen.pc.j2", TEMPLATES).render(**package_view),
        "example/main.c": template("example.c.j2", TEMPLATES).render(**package_view),
        "SETUP.md": template("SETUP.md.j2", TEMPLATES).render(**package_view),
    }


def write_package(robot, out_dir, timeout=DEFAULT_TIMEOUT):
    """Write the package folder ``out_dir`` whole or not at all, once the library compiles."""
    files = render_package(robot)

    def fill(staging):
        build_library(robot, Path(staging) / ".build", timeout=timeout)
        for path in sorted((Path(staging) / ".build").iterdir()):
            path.unlink()
        (Path(staging) / ".build").rmdir()
        for name, text in files.items():
            write_atomic(Path(staging) / name, text)

    write_folder(out_dir, fill, f"kingen {VERSION} C library package of robot {robot.name}\n")
    return [Path(out_dir) / name for name in files]
