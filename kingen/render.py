"""Rendering: robot -> C source text. Pure: nothing here touches the file system
except reading the templates; the build layer writes files.

All decisions are made here in a Python view-model; the templates only loop and
substitute. Numbers are written with Python's shortest round-trip repr, so the
C tables hold exactly the doubles the reference uses.
"""

import functools
import math

import jinja2

from . import __version__, abi
from .model import REVOLUTE, calibration_unit, dialog_label, field_index
from .reference import SINGULAR_TOLERANCE
from .resources import templates_dir
from .text import finalizer, markdown


TEMPLATE_KINDS = {".c.j2": "c", ".md.j2": "markdown"}
"""Which escaping (:func:`kingen.text.finalizer`) a template's substitutions get, by suffix;
every other template is plain text. The stand-in header has no user text and none."""


@functools.lru_cache(maxsize=None)
def _environment(kind):
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(templates_dir())),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
        finalize=finalizer(kind) if kind else None,
    )


def template(name):
    """The jinja2 template ``name`` from templates/, in the environment that escapes its
    substitutions for its kind of file (C, Markdown, plain text): strict undefined."""
    kind = None if name == "shlibdefs.h.j2" else next(
        (kind for suffix, kind in TEMPLATE_KINDS.items() if name.endswith(suffix)), "plain")
    environment = _environment(kind)
    environment.filters["markdown"] = markdown
    return environment.get_template(name)


def c_double(value):
    """A C double literal that reads back as exactly ``value``."""
    text = repr(float(value))
    if not math.isfinite(float(value)):
        raise ValueError(f"cannot write {text} as a C constant")
    return text if ("." in text or "e" in text) else text + ".0"


def _c_vector(values):
    return ", ".join(c_double(value) for value in values)


def source_name(robot):
    """The generated source's file name, kin_<name>.c, as DELMIA's makefile expects."""
    return f"kin_{robot.name}.c"


def calibration_line(robot, joint, parameter, dialog_field, built_in):
    """'Length 3 -> leg3.reference_length (mm, built-in 803.887)' for sheets and banners."""
    return (f"{dialog_label(dialog_field)} -> {robot.joint_names[joint]}.{parameter} "
            f"({calibration_unit(parameter)}, built-in {built_in:.10g})")


def view_model(robot):
    """Everything the plugin template substitutes, already formatted as C."""
    lower, upper = robot.travel_limits()
    joints = []
    for index, (limb, bit) in enumerate(zip(robot.limbs, robot.branch_bits)):
        revolute = limb.joint_type == REVOLUTE
        limited = limb.travel is not None
        joints.append({
            "index": index,
            "name": robot.joint_names[index],
            "model": limb.model,
            "units": "radians" if revolute else "mm",
            "bit": bit,
            "limited": int(limited),
            "lower": c_double(lower[index] if limited else 0.0),
            "upper": c_double(upper[index] if limited else 0.0),
            "travel_text": f"[{limb.travel[0]:.10g}, {limb.travel[1]:.10g}] {'deg' if revolute else 'mm'}"
            if limited else "",
        })
    tables = {"leg": [], "rail": [], "crank": []}
    for index, limb in enumerate(robot.limbs):
        row = {"joint": index, "platform_point": _c_vector(limb.platform_point)}
        row.update({f"{parameter}_field": field_index(limb.calibrate[parameter]) if parameter in limb.calibrate else -1
                    for parameter in limb.calibratable})
        if limb.model == "leg":
            row.update(base_point=_c_vector(limb.base_point), reference_length=c_double(limb.reference_length))
        elif limb.model == "rail":
            row.update(
                rail_point=_c_vector(limb.rail_point),
                direction=_c_vector(limb.direction),
                carriage_offset=_c_vector(limb.carriage_offset),
                link_length=c_double(limb.link_length),
                origin=c_double(limb.origin),
            )
        else:
            beta = math.radians(limb.crank_direction)
            row.update(
                pivot=_c_vector(limb.pivot),
                cos_direction=c_double(math.cos(beta)),
                sin_direction=c_double(math.sin(beta)),
                crank_length=c_double(limb.crank_length),
                rod_length=c_double(limb.rod_length),
                zero_offset=c_double(math.radians(limb.zero_offset)),
            )
        tables[limb.model].append(row)
    models = [model for model in ("leg", "rail", "crank") if tables[model]]
    return {
        "version": __version__,
        "header_version": abi.HEADER_VERSION,
        "file_name": source_name(robot),
        "source_name": robot.path.name,
        "source_hash": robot.sha256,
        "name": robot.name,
        "description": " ".join(robot.description.split()),
        "library": robot.library,
        "routine": robot.routine,
        "dof": robot.dof,
        "postures": robot.postures,
        "two_branch_count": sum(1 for bit in robot.branch_bits if bit >= 0),
        "singular_tolerance": c_double(SINGULAR_TOLERANCE),
        "joints": joints,
        "legs": tables["leg"],
        "rails": tables["rail"],
        "cranks": tables["crank"],
        "models": models,
        "table_sizes": [(model, len(tables[model])) for model in models],
        "degree": c_double(math.pi / 180.0),
        "calibration": [calibration_line(robot, *entry) for entry in robot.calibration()],
        "get_kin_config": abi.GET_KIN_CONFIG,
        "routine_prototype": abi.routine_prototype(robot.routine, "NUM_SOLUTIONS"),
    }


def render(robot):
    """The plugin's files as {file name: text}; today one file, ``kin_<name>.c``."""
    text = template("kin_robot.c.j2").render(**view_model(robot))
    return {source_name(robot): text}


def render_header():
    """The stand-in ``shlibdefs.h`` text, from :mod:`kingen.abi`."""
    return template("shlibdefs.h.j2").render(
        version=__version__,
        header_version=abi.HEADER_VERSION,
        warnings=list(abi.WARNINGS.items()),
        warning_aliases=list(abi.WARNING_ALIASES.items()),
        constants=list(abi.CONSTANTS.items()),
        kinstat_struct=abi.kinstat_struct(),
        host_check=abi.HOST_CHECK,
        host_math=list(abi.HOST_MATH),
        emulator_functions=list(abi.EMULATOR_FUNCTIONS),
    )


def host_source():
    """The host emulator's C source (a fixed file, not a template)."""
    return (templates_dir() / "kingen_host.c").read_text()
