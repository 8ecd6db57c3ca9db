"""Packaging the WebAssembly module for a web page or a JavaScript program: ``kingen_<name>.wasm``
(compiled from the C library, :mod:`.build`), the glue ``kingen_wasm.js``, the C header (the
interface the module exports), ``example.js`` (Node: the verification home through the inverse and
the forward) and ``SETUP.md``. Written whole or not at all, once the module compiled."""

import json
from pathlib import Path

from ...defaults import DEFAULT_TIMEOUT, VERSION
from ...kinematics.home import judged_posture
from ...runtime.files import write_atomic, write_folder
from ..c.render import file_names, view_model
from ..render import template
from ..wrist import sheet_words
from .build import GLUE, compile_wasm, module_meta

TEMPLATES = Path(__file__).resolve().parent / "templates"


def render_package(robot):
    """{relative path: text} of the package's text files (pure)."""
    view = view_model(robot)
    header = template("header.c.j2", TEMPLATES.parent.parent / "c" / "templates").render(**view)
    package_view = {**view, "meta": json.dumps(module_meta(robot)), "posture": judged_posture(robot).posture,
                    "home": ", ".join(repr(float(value)) for value in robot.verification.home),
                    "wrist_sheet": sheet_words(robot) if robot.wrist is not None else None}
    return {
        file_names(robot)[0]: header,
        GLUE.name: GLUE.read_text(),
        "example.js": template("example.js.j2", TEMPLATES).render(**package_view),
        "SETUP.md": template("SETUP.md.j2", TEMPLATES).render(**package_view),
    }


def write_package(robot, out_dir, timeout=DEFAULT_TIMEOUT):
    """Write the package folder ``out_dir`` whole or not at all, once the module compiles."""
    files = render_package(robot)
    module = compile_wasm(robot, timeout)

    def fill(staging):
        write_atomic(Path(staging) / module.name, module.read_bytes())
        for name, text in files.items():
            write_atomic(Path(staging) / name, text)

    write_folder(out_dir, fill, f"kingen {VERSION} WebAssembly package of robot {robot.name}\n")
    return [Path(out_dir) / name for name in (module.name, *files)]
