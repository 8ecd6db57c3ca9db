"""Packaging for the simulator: a folder that drops into place and a setup sheet that
says exactly what to type into DELMIA's Inverse Kinematics dialog.

``render_package(robot, target)`` is pure ({file name: text}); ``write_package`` writes
the files atomically and, for Linux, adds the compiled library.
"""

import tempfile
from pathlib import Path

from .build import build_plugin, library_name, write_atomic
from .model import REVOLUTE, calibration_unit, dialog_label
from .render import render, template, view_model

TARGETS = ("windows", "linux")
HOST_IMPORT_LIB_PLACEHOLDER = "DELMIA_HOST_IMPORT_LIB.lib"
CRLF_FILES = ("makefile", "BUILD.txt")
"""nmake and Notepad want CRLF line ends; the C source keeps LF (cl reads both)."""
BRANCHES = {
    "rail": ("u.w - sqrt(...) (carriage nearer the rail point)", "u.w + sqrt(...)"),
    "crank": ("phi + acos(K/rho)", "phi - acos(K/rho)"),
}


def sheet_view(robot, target):
    """What the setup sheet shows, in the dialog's units (mm, degrees)."""
    two_branch = [(index, bit) for index, bit in enumerate(robot.branch_bits) if bit >= 0]
    used = {dialog_field for _, _, dialog_field, _ in robot.calibration()}
    calibration = [
        {"label": dialog_label(dialog_field), "joint": robot.joint_names[index], "parameter": parameter,
         "unit": calibration_unit(parameter), "built_in": f"{built_in:.10g}"}
        for index, parameter, dialog_field, built_in in robot.calibration()
    ]
    joints = []
    for index, limb in enumerate(robot.limbs):
        revolute = limb.joint_type == REVOLUTE
        joints.append({
            "index": index,
            "name": robot.joint_names[index],
            "kind": "Rotational" if revolute else "Translational",
            "axis": "Rot Z" if revolute else "Trans Z",
            "unit": "deg" if revolute else "mm",
            "lower": f"{limb.travel[0]:.10g}" if limb.travel else "-",
            "upper": f"{limb.travel[1]:.10g}" if limb.travel else "-",
        })
    return {
        **view_model(robot),
        "target": target,
        "library": robot.library,
        "dialog_fields": [
            {"label": dialog_label(f"{kind}{i}"), "meaning": "read, see below" if f"{kind}{i}" in used else "leave empty"}
            for kind in ("length", "offset") for i in range(1, 7)
        ],
        "calibration": calibration,
        "branch_limbs": [robot.joint_names[index] for index, _ in two_branch],
        "branch_models": [{"name": model, "branch0": BRANCHES[model][0], "branch1": BRANCHES[model][1]}
                          for model in robot.models if model in BRANCHES],
        "configurations": [
            {"index": k, "digits": "".join(str((k >> bit) & 1) for _, bit in two_branch),
             "branches": [f"branch {(k >> bit) & 1}" for _, bit in two_branch]}
            for k in range(robot.postures)
        ],
        "joints": joints,
        "any_limits": any(limb.travel for limb in robot.limbs),
    }


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


def write_package(robot, out_dir, target):
    """Write the package into ``out_dir``; for linux also compile and add lib<name>.so.

    Everything is produced first (a compile error leaves ``out_dir`` untouched), then
    each file is written atomically. Returns the written paths."""
    files = {name: text.encode() for name, text in render_package(robot, target).items()}
    if target == "windows":
        files.update({name: files[name].replace(b"\n", b"\r\n") for name in files if name in CRLF_FILES
                      or name.endswith(".def")})
    else:
        with tempfile.TemporaryDirectory(prefix="kingen-package-") as scratch:
            files[library_name(robot)] = build_plugin(robot, scratch).library.read_bytes()
    for name, data in files.items():
        write_atomic(Path(out_dir) / name, data)
    return [Path(out_dir) / name for name in files]
