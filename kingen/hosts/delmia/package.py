"""Packaging for the simulator: a folder that drops into place and a setup sheet that
says exactly what to type into DELMIA's Inverse Kinematics dialog.

``render_package(robot, target)`` is pure ({file name: text}); ``write_package`` writes
the files atomically and, for Linux, adds the compiled library.
"""

import shutil
from pathlib import Path

from ...conventions import branch_of_posture
from ...defaults import DEFAULT_TIMEOUT, TARGETS
from ...runtime.files import write_atomic, write_folder
from ...robot.placement import branch_words, frames
from ...kinematics.routine import warnings_to_exercise
from ...robot.schema import CALIBRATION_FIELDS
from ..wrist import sheet_words
from . import abi, dialog
from .build import WINDOWS_DEFINES, build_plugin, library_name
from .render import delmia_template, render, view_model

HOST_IMPORT_LIB_PLACEHOLDER = "DELMIA_HOST_IMPORT_LIB.lib"
CRLF_FILES = ("makefile", "BUILD.txt")
"""nmake and Notepad want CRLF line ends; the C source keeps LF (cl reads both)."""
WARNING_MEANINGS = {
    "WARN_GOOD_SOLUTION": "reachable, regular, within travel",
    "WARN_JOINT_LIMITS_EXCEEDED": "a joint of this posture is outside its travel limits",
    "WARN_SINGULAR_SOLUTION": f"a limb within {abi.SINGULAR_TOLERANCE:g} (normalised radicand) of its limb singularity",
    "WARN_UNREACHABLE": "a limb has no real solution (joints are its closest approach)",
}
"""What each warning means from a kingen routine, for the setup sheet (order: precedence last);
the sheet lists WARN_GOOD_SOLUTION and the warnings the robot's routine can give
(:func:`kingen.kinematics.routine.warnings_to_exercise`)."""
WRIST_MEANINGS = {
    "WARN_SINGULAR_SOLUTION": "or the wrist's singularity: the tool axis along {first}, or its two branches meeting",
    "WARN_UNREACHABLE": "or no wrist angle turns the tool onto the asked tool axis",
}
"""What a machine with a wrist adds to a warning's meaning ({first}: the wrist's first joint)."""
SPHERICAL_SINGULAR = ("or the wrist's singularity: the axis of {third} along {first} (the gimbal lock), "
                      "or its two branches meeting")
"""What a three-axis wrist adds to WARN_SINGULAR_SOLUTION's meaning (it reaches every tool rotation)."""


def sheet_view(robot, target):
    """What the setup sheet shows, in the dialog's units (mm, degrees): the frames placed by the
    limbs' joints, each two-branch limb's branches in its model's words (true at the
    verification home), and only the warnings the robot's routine can give."""
    wrist = sheet_words(robot) if robot.wrist is not None else None
    # A wrist's branch is the posture's last digit, the legs' one up (kingen.hosts.wrist.whole_view).
    two_branch = [(index, bit + (wrist is not None)) for index, bit in enumerate(robot.branch_bits) if bit >= 0]
    used = {field for _, _, field, _ in robot.calibration()}
    calibration = [
        {"label": dialog.field_label(field), "joint": robot.joint_names[index], "parameter": parameter,
         "unit": robot.limbs[index].calibratable[parameter], "built_in": f"{built_in:.10g}"}
        for index, parameter, field, built_in in robot.calibration()
    ]
    joints = []
    for index, limb in enumerate(robot.limbs):
        kind, axis = dialog.ACTUATOR_SPACE[limb.joint_type.name]
        joints.append({
            "index": index,
            "name": robot.joint_names[index],
            "kind": kind,
            "axis": axis,
            "unit": limb.joint_type.yaml_unit,
            "lower": f"{limb.travel[0]:.10g}" if limb.travel else "-",
            "upper": f"{limb.travel[1]:.10g}" if limb.travel else "-",
        })
    words = branch_words(robot)
    working = robot.posture_branches(robot.working_posture)
    branch_rows = [{"name": robot.joint_names[index], "branch0": words[index][0], "branch1": words[index][1],
                    "working": words[index][working[index]]} for index, _ in two_branch]
    columns = [robot.joint_names[index] for index, _ in two_branch]
    bits = [bit for _, bit in two_branch]
    if wrist is not None:
        kind, axis = dialog.ACTUATOR_SPACE["revolute"]
        joints += [{"index": robot.dof + index, "name": joint["name"], "kind": kind, "axis": axis, "unit": "deg",
                    "lower": joint["travel"][0] if joint["travel"] else "-",
                    "upper": joint["travel"][1] if joint["travel"] else "-"} for index, joint in enumerate(wrist["joints"])]
        columns.append(f"wrist ({', '.join(joint['name'] for joint in wrist['joints'])})")
        bits.append(0)
        branch_rows.append({"name": columns[-1], "branch0": wrist["branches"][0], "branch1": wrist["branches"][1],
                            "working": wrist["branches"][branch_of_posture(robot.working_posture, 0)]})
    can_give = {"WARN_GOOD_SOLUTION", *warnings_to_exercise(robot)}
    return {
        **view_model(robot),
        "description": robot.description,
        "target": target,
        "dialog_fields": [{"label": dialog.field_label(field), "meaning": "read, see below" if field in used
                           else "leave empty"} for field in CALIBRATION_FIELDS],
        "calibration": calibration,
        "frames": frames(robot),
        "home": " ".join(f"{value:g}" for value in robot.verification.home),
        "branch_limbs": columns,
        "branch_words": branch_rows,
        "configurations": [
            {"index": k, "digits": "".join(str(branch_of_posture(k, bit)) for bit in bits),
             "branches": [f"branch {branch_of_posture(k, bit)}" for bit in bits]}
            for k in range(robot.postures)
        ],
        "joints": joints,
        "any_limits": any(joint["lower"] != "-" or joint["upper"] != "-" for joint in joints),
        "wrist": wrist,
        "wrist_task": list(robot.parallel.task),
        "warnings": [{"code": abi.WARNINGS[name], "name": name, "meaning": _meaning(robot, name, meaning)}
                     for name, meaning in WARNING_MEANINGS.items() if name in can_give],
        "limb_bands": any(limb.has_radicand for limb in robot.limbs),
        "direct_index_available": robot.has_direct_index,
        "task": list(robot.task),
        "working_posture": robot.working_posture,
        "direct_index_min": robot.direct_index_min,
        "compiler_defines": " ".join(f"-D{define}" for define in WINDOWS_DEFINES),
    }


def _meaning(robot, name, meaning):
    """``meaning`` as it holds for ``robot``: WARN_SINGULAR_SOLUTION names the limb band only if
    some limb has one, the direct index only if the robot sets its threshold."""
    if robot.wrist is not None and robot.wrist.whole_pose and name == "WARN_SINGULAR_SOLUTION":
        return f"{meaning}, {SPHERICAL_SINGULAR.format(first=robot.wrist.names[0], third=robot.wrist.names[2])}"
    if robot.wrist is not None and name in WRIST_MEANINGS:
        return f"{meaning}, {WRIST_MEANINGS[name].format(first=robot.wrist.names[0])}"
    if name != "WARN_SINGULAR_SOLUTION" or robot.direct_index_min is None:
        return meaning
    direct = f"the posture's direct index at most {robot.direct_index_min:g} mm (section 8)"
    return f"{meaning}, or {direct}" if any(limb.has_radicand for limb in robot.limbs) else direct


def render_package(robot, target):
    """The text files of the package for ``target`` as {file name: text}."""
    if target not in TARGETS:
        raise ValueError(f"unknown target {target!r}")
    files = dict(render(robot))
    view = sheet_view(robot, target)
    files["SETUP.md"] = delmia_template("setup_sheet.md.j2").render(**view)
    if target == "windows":
        extra = {"object": f"{dialog.routine_name(robot.name)}.obj", "host_import_lib": HOST_IMPORT_LIB_PLACEHOLDER}
        files["makefile"] = delmia_template("makefile.nmake.j2").render(**view, **extra)
        files[f"{view['library']}.def"] = delmia_template("exports.def.j2").render(**view)
        files["BUILD.txt"] = delmia_template("BUILD.txt.j2").render(**view, **extra, host_symbols=abi.HOST_SYMBOLS)
    return files


def write_package(robot, out_dir, target, timeout=DEFAULT_TIMEOUT):
    """Write the package folder ``out_dir``, whole or not at all (:func:`kingen.runtime.files.write_folder`:
    an existing folder is replaced only if it is empty or kingen wrote it); for linux also
    compile and add lib<name>.so. Returns the written paths."""
    files = {name: text.encode() for name, text in render_package(robot, target).items()}
    if target == "windows":
        files.update({name: files[name].replace(b"\n", b"\r\n") for name in files if name in CRLF_FILES
                      or name.endswith(".def")})

    def fill(staging):
        if target == "linux":
            built = build_plugin(robot, staging / ".build", timeout=timeout)
            write_atomic(staging / library_name(robot), built.library.read_bytes(), executable=True)
            shutil.rmtree(staging / ".build")
        for name, data in files.items():
            write_atomic(staging / name, data)

    write_folder(out_dir, fill, f"written by kingen for {robot.name} ({target})\n")
    names = [*files, *([library_name(robot)] if target == "linux" else [])]
    return [Path(out_dir) / name for name in names]
