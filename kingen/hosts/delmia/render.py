"""Rendering DELMIA's files: robot -> the plugin source, the stand-in ``shlibdefs.h`` and
the host emulator, from this host's templates and the shared view-model
(:func:`kingen.hosts.render.robot_view`). Pure: nothing is written here.
"""

from pathlib import Path

from ...defaults import VERSION
from ...robot.limbs import c_double
from ..render import robot_view, template
from . import DelmiaHost, abi, dialog

TEMPLATES = Path(__file__).resolve().parent / "templates"
"""DELMIA's templates: plugin source, stand-in header, host emulator, makefile, .def, sheets."""
HOST = DelmiaHost()
"""The host the shared view-model asks for DELMIA's names (kingen.hosts.render.robot_view)."""


def delmia_template(name):
    """The template ``name`` of this host (kingen.hosts.render.template in TEMPLATES)."""
    return template(name, TEMPLATES)


def source_name(robot):
    """The generated source's file name, kin_<name>.c, as DELMIA's makefile expects."""
    return f"{dialog.routine_name(robot.name)}.c"


def view_model(robot):
    """Everything the plugin template substitutes, already formatted as C."""
    return {
        **robot_view(robot, HOST),
        "header_version": abi.HEADER_VERSION,
        "file_name": source_name(robot),
        "singular_tolerance": c_double(abi.SINGULAR_TOLERANCE),
        "get_kin_config": abi.GET_KIN_CONFIG,
        "routine_prototype": abi.routine_prototype(dialog.routine_name(robot.name), "NUM_SOLUTIONS"),
        "entry_check": "kin_check_definition(NUM_DOFS, NUM_SOLUTIONS)",
        "limb_tables": "kingen_",
        "calibration_arguments": "link_lengths, link_offsets",
    }


def render(robot):
    """The plugin's files as {file name: text}; today one file, ``kin_<name>.c``."""
    text = delmia_template("kin_robot.c.j2").render(**view_model(robot))
    return {source_name(robot): text}


def render_header():
    """The stand-in ``shlibdefs.h`` text, from :mod:`kingen.hosts.delmia.abi`."""
    return delmia_template("shlibdefs.h.j2").render(
        version=VERSION,
        header_version=abi.HEADER_VERSION,
        warnings=list(abi.WARNINGS.items()),
        warning_aliases=list(abi.WARNING_ALIASES.items()),
        constants=list(abi.CONSTANTS.items()),
        kinstat_struct=abi.kinstat_struct(),
        host_check=abi.HOST_CHECK,
        host_math=list(abi.HOST_MATH.items()),
        emulator_functions=list(abi.EMULATOR_FUNCTIONS),
        host_defines=abi.host_defines(),
    )


def host_source():
    """The host emulator's C source (a fixed file, not a template)."""
    return (TEMPLATES / "kingen_host.c").read_text()
