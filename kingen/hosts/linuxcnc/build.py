"""Building LinuxCNC kinematics modules: ``<name>kins.c`` compiled into ``<name>kins.so`` with
the flags of LinuxCNC's own module build (Makefile.modinc, uspace) against its headers, warnings
as errors; and the HAL stand-in kingen loads modules with, built once per content in the cache."""

import json
import os
import tempfile
from pathlib import Path

from ...defaults import VERSION
from ...runtime.compiler import CompileError, compile_c, compile_given_source, compiler_command
from ...defaults import DEFAULT_TIMEOUT
from ...errors import KingenError
from ...runtime.files import (cache_dir, cached, default_out_dir, digest, file_digest, read_stamp, write_atomic,
                              write_files)
from ..base import BuildResult
from .render import harness_source, module_name, render, source_name

HEADERS = "/usr/include/linuxcnc"
"""Where Debian's linuxcnc-uspace-dev puts kinematics.h, hal.h, rtapi.h ($KINGEN_LINUXCNC_INCLUDE)."""
MODULE_FLAGS = ("-std=gnu99", "-Wall", "-Wextra", "-Werror", "-O2", "-fPIC", "-shared", "-DRTAPI", "-D_GNU_SOURCE",
                "-Drealtime", "-D__MODULE__", "-DSIM", "-DUSPACE", "-fno-fast-math", "-fno-unsafe-math-optimizations")
"""LinuxCNC's uspace module flags (Makefile.modinc), with warnings as errors and -O2."""
HARNESS_FLAGS = ("-std=c99", "-Wall", "-Wextra", "-Werror", "-O2", "-fPIC", "-shared")


def header_folder():
    """Where LinuxCNC's headers are looked for: $KINGEN_LINUXCNC_INCLUDE, else Debian's folder."""
    return Path(os.environ.get("KINGEN_LINUXCNC_INCLUDE") or HEADERS)


def headers_found():
    """Whether :func:`header_folder` holds LinuxCNC's kinematics.h (a module can be built)."""
    return (header_folder() / "kinematics.h").is_file()


def linuxcnc_headers():
    """The folder holding LinuxCNC's kinematics.h; KingenError naming the package otherwise."""
    folder = header_folder()
    if not headers_found():
        raise KingenError(f"LinuxCNC's headers are not in {folder} (no kinematics.h): install Debian's "
                          "linuxcnc-uspace-dev or set KINGEN_LINUXCNC_INCLUDE")
    return folder


def default_dir(robot):
    return default_out_dir(robot) / "linuxcnc"


def harness(timeout=DEFAULT_TIMEOUT):
    """The HAL stand-in library (libkingen_hal.so), built once per content and compiler."""
    source, command = harness_source(), compiler_command()
    folder = cache_dir() / f"linuxcnc-hal-{digest(VERSION, source, *command)[:16]}"
    library = folder / "libkingen_hal.so"

    def make():
        write_atomic(folder / "kingen_hal.c", source)
        compile_c([folder / "kingen_hal.c"], library, list(HARNESS_FLAGS), timeout=timeout)

    cached(folder, library, make, {"kingen_hal.c": source})
    return library


def build_module(robot, out_dir=None, units="mm", timeout=DEFAULT_TIMEOUT):
    """Render and compile ``robot``'s module for a machine in ``units`` into ``out_dir``
    (default build/<name>/linuxcnc): ``<name>kins.c`` and ``<name>kins.so``. Skips compiling
    when the stamp matches."""
    out_dir = Path(out_dir or default_dir(robot))
    (name, text), = render(robot, units).items()
    command = compiler_command()
    flags = [*MODULE_FLAGS, f"-I{linuxcnc_headers()}"]
    source, library = out_dir / name, out_dir / f"{module_name(robot)}.so"
    key = digest(VERSION, text, *command, *flags)
    stamp = out_dir / ".kingen-build-linuxcnc.json"
    if read_stamp(stamp, "key") == key and read_stamp(stamp, "library_sha256") == file_digest(library) \
            and file_digest(source) == digest(text):
        return BuildResult(source, library, module_name(robot), compiled=False)
    with tempfile.TemporaryDirectory(prefix="kingen-build-") as scratch:
        scratch_source, scratch_library = Path(scratch) / name, Path(scratch) / library.name
        scratch_source.write_text(text)
        try:
            compile_c([scratch_source], scratch_library, flags, compiler=command, timeout=timeout, shown_source=source)
        except CompileError:
            write_atomic(source, text)
            raise
        data = scratch_library.read_bytes()
        write_atomic(source, text)
        write_atomic(library, data, executable=True)
    write_atomic(stamp, json.dumps({"key": key, "library_sha256": file_digest(library), "robot": robot.name,
                                    "kingen": VERSION}) + "\n")
    return BuildResult(source, library, module_name(robot), compiled=True)


def build_source(source, out_dir, timeout=DEFAULT_TIMEOUT):
    """Compile a hand-written module source (a stock module's, say) as LinuxCNC's build would;
    warnings allowed. Returns the module's path."""
    flags = [flag for flag in MODULE_FLAGS if flag not in ("-Werror", "-Wall", "-Wextra")]
    return compile_given_source(source, out_dir, [*flags, f"-I{linuxcnc_headers()}"], timeout=timeout)


def write_source(robot, out_dir, units="mm"):
    write_files({Path(out_dir) / name: text for name, text in render(robot, units).items()})
    return Path(out_dir) / source_name(robot)
