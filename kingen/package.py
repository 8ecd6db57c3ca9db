"""Packaging for the simulator: a folder that drops into place and a setup sheet that
says exactly what to type into DELMIA's Inverse Kinematics dialog.

``render_package(robot, target)`` is pure ({file name: text}); ``write_package`` writes
the files atomically and, for Linux, adds the compiled library.
"""

import os
import shutil
import tempfile
from pathlib import Path

from . import abi
from .build import WINDOWS_DEFINES, build_plugin, library_name, umask, write_atomic
from .conventions import branch_of_posture
from .defaults import DEFAULT_TIMEOUT, TARGETS
from .errors import KingenError
from .render import render, template, view_model
from .schema import dialog_label

HOST_IMPORT_LIB_PLACEHOLDER = "DELMIA_HOST_IMPORT_LIB.lib"
MARKER = ".kingen-package"
"""Marks a folder kingen wrote, so that it may be replaced by a newer package."""
CRLF_FILES = ("makefile", "BUILD.txt")
"""nmake and Notepad want CRLF line ends; the C source keeps LF (cl reads both)."""
WARNING_MEANINGS = {
    "WARN_GOOD_SOLUTION": "reachable, regular, within travel",
    "WARN_JOINT_LIMITS_EXCEEDED": "a joint of this posture is outside its travel limits",
    "WARN_SINGULAR_SOLUTION": f"a limb within {abi.SINGULAR_TOLERANCE:g} (normalised radicand) of its limb singularity",
    "WARN_UNREACHABLE": "a limb has no real solution (joints are its closest approach)",
}
"""What each warning means from a kingen routine, for the setup sheet (order: precedence last)."""


def sheet_view(robot, target):
    """What the setup sheet shows, in the dialog's units (mm, degrees)."""
    two_branch = [(index, bit) for index, bit in enumerate(robot.branch_bits) if bit >= 0]
    used = {dialog_field for _, _, dialog_field, _ in robot.calibration()}
    calibration = [
        {"label": dialog_label(dialog_field), "joint": robot.joint_names[index], "parameter": parameter,
         "unit": robot.limbs[index].calibratable[parameter], "built_in": f"{built_in:.10g}"}
        for index, parameter, dialog_field, built_in in robot.calibration()
    ]
    joints = []
    for index, limb in enumerate(robot.limbs):
        joints.append({
            "index": index,
            "name": robot.joint_names[index],
            "kind": limb.joint_type.delmia_type,
            "axis": limb.joint_type.delmia_axis,
            "unit": limb.joint_type.yaml_unit,
            "lower": f"{limb.travel[0]:.10g}" if limb.travel else "-",
            "upper": f"{limb.travel[1]:.10g}" if limb.travel else "-",
        })
    branch_models = {type(robot.limbs[index]): robot.limbs[index].model for index, _ in two_branch}
    return {
        **view_model(robot),
        "description": robot.description,
        "target": target,
        "library": robot.library,
        "dialog_fields": [
            {"label": dialog_label(f"{kind}{i}"), "meaning": "read, see below" if f"{kind}{i}" in used else "leave empty"}
            for kind in ("length", "offset") for i in range(1, 7)
        ],
        "calibration": calibration,
        "branch_limbs": [robot.joint_names[index] for index, _ in two_branch],
        "branch_models": [{"name": name, "branch0": cls.branch_labels[0], "branch1": cls.branch_labels[1]}
                          for cls, name in branch_models.items()],
        "configurations": [
            {"index": k, "digits": "".join(str(branch_of_posture(k, bit)) for _, bit in two_branch),
             "branches": [f"branch {branch_of_posture(k, bit)}" for _, bit in two_branch]}
            for k in range(robot.postures)
        ],
        "joints": joints,
        "any_limits": any(limb.travel for limb in robot.limbs),
        "warnings": [{"code": abi.WARNINGS[name], "name": name, "meaning": _meaning(robot, name, meaning)}
                     for name, meaning in WARNING_MEANINGS.items()],
        "direct_index_available": robot.has_direct_index,
        "working_posture": robot.working_posture,
        "direct_index_min": robot.direct_index_min,
        "compiler_defines": " ".join(f"-D{define}" for define in WINDOWS_DEFINES),
    }


def _meaning(robot, name, meaning):
    if name == "WARN_SINGULAR_SOLUTION" and robot.direct_index_min is not None:
        return f"{meaning}, or the posture's direct index at most {robot.direct_index_min:g} mm (section 7)"
    return meaning


def render_package(robot, target):
    """The text files of the package for ``target`` as {file name: text}."""
    if target not in TARGETS:
        raise ValueError(f"unknown target {target!r}")
    files = dict(render(robot))
    view = sheet_view(robot, target)
    files["SETUP.md"] = template("setup_sheet.md.j2").render(**view)
    if target == "windows":
        extra = {"object": f"kin_{robot.name}.obj", "host_import_lib": HOST_IMPORT_LIB_PLACEHOLDER}
        files["makefile"] = template("makefile.nmake.j2").render(**view, **extra)
        files[f"{robot.library}.def"] = template("exports.def.j2").render(**view)
        files["BUILD.txt"] = template("BUILD.txt.j2").render(**view)
    return files


def write_package(robot, out_dir, target, timeout=DEFAULT_TIMEOUT):
    """Write the package folder ``out_dir``, whole or not at all; for linux also compile and
    add lib<name>.so. Returns the written paths.

    The files are written into a hidden sibling folder which then takes ``out_dir``'s place.
    An existing ``out_dir`` is replaced only if it is empty or kingen wrote it (it holds
    the marker file ``.kingen-package``); anything else is refused, never overwritten."""
    out_dir = Path(out_dir)
    if out_dir.exists() and not (out_dir.is_dir() and (not any(out_dir.iterdir()) or (out_dir / MARKER).is_file())):
        raise KingenError(f"{out_dir}: exists and is not a kingen package folder; choose another -o")
    files = {name: text.encode() for name, text in render_package(robot, target).items()}
    if target == "windows":
        files.update({name: files[name].replace(b"\n", b"\r\n") for name in files if name in CRLF_FILES
                      or name.endswith(".def")})
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.", dir=out_dir.parent))
    try:
        if target == "linux":
            built = build_plugin(robot, staging / ".build", timeout=timeout)
            write_atomic(staging / library_name(robot), built.library.read_bytes(), executable=True)
            shutil.rmtree(staging / ".build")
        for name, data in files.items():
            write_atomic(staging / name, data)
        write_atomic(staging / MARKER, f"written by kingen for {robot.name} ({target})\n")
        os.chmod(staging, 0o777 & ~umask())
        _replace_folder(staging, out_dir)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    names = [*files, *([library_name(robot)] if target == "linux" else [])]
    return [out_dir / name for name in names]


def _replace_folder(new, old):
    """Put folder ``new`` where ``old`` is: the old one is moved aside first, removed last."""
    if not old.exists():
        os.replace(new, old)
        return
    aside = Path(tempfile.mkdtemp(prefix=f".{old.name}.old.", dir=old.parent))
    os.replace(old, aside / old.name)
    try:
        os.replace(new, old)
    except OSError:
        os.replace(aside / old.name, old)
        raise
    finally:
        shutil.rmtree(aside, ignore_errors=True)
