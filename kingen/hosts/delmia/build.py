"""Building DELMIA plugins: compiled exactly as for DELMIA, against the stand-in
``shlibdefs.h``, with the host symbols (``DNBVMAP_*``) left undefined for the host process
to resolve. The stand-in header and the host emulator library live in kingen's cache folder
(:func:`kingen.runtime.files.cache_dir`) keyed by their content and compiler. A plugin build is
skipped when its folder already holds the same source built with the same compiler and
flags (``.kingen-build-<target>.json``).
"""

import hashlib
import json
import shutil
import tempfile
from pathlib import Path

from ...defaults import VERSION
from ...runtime.compiler import CompileError, compile_c, compiler_command
from ...defaults import DEFAULT_TIMEOUT
from ...errors import KingenError
from ...runtime.file_gate import refuse_special_file
from ...runtime.files import (cache_dir, cached, default_out_dir, digest, file_digest, read_stamp, write_atomic,
                              write_files)
from ..base import BuildResult
from . import dialog
from .pe import dll_exports
from .render import host_source, render, render_header, source_name

STRICT_C89 = ("-std=c89", "-pedantic", "-Wall", "-Wextra", "-Werror")
"""The dialect and warnings every generated source must pass (old Visual C is C89)."""
SHARED_FLAGS = ("-O2", "-fPIC", "-shared")
WINDOWS_DEFINES = ("WINDOWS_SHELL", "_DNBUSERLIB", "WINDOWS_SOURCE", "NDEBUG", "WIN32", "WINNT", "WINDOWS_NT")
"""The vendor makefile's defines (plus WINDOWS_SOURCE, which turns DllExport into dllexport)."""
MINGW = "x86_64-w64-mingw32-gcc"


def host_support(timeout=DEFAULT_TIMEOUT):
    """(include folder with shlibdefs.h, host emulator library), built once per content."""
    header, source = render_header(), host_source()
    command = compiler_command()
    folder = cache_dir() / f"host-{digest(VERSION, header, source, *command)[:16]}"
    include, library = folder / "include", folder / "libkingen_host.so"

    def make():
        write_atomic(include / "shlibdefs.h", header)
        write_atomic(folder / "kingen_host.c", source)
        compile_c([folder / "kingen_host.c"], library, [*STRICT_C89, *SHARED_FLAGS, f"-I{include}"], timeout=timeout)

    cached(folder, library, make, {"include/shlibdefs.h": header, "kingen_host.c": source})
    return include, library


def mingw_command():
    """The mingw-w64 cross compiler (``$KINGEN_MINGW_CC``, else x86_64-w64-mingw32-gcc)."""
    command = compiler_command("KINGEN_MINGW_CC", MINGW)
    if shutil.which(command[0]) is None:
        raise KingenError(f"Windows cross compiler '{command[0]}' not found: install Debian's "
                          "gcc-mingw-w64-x86-64 or set KINGEN_MINGW_CC")
    return command


def windows_host_import_library(timeout=DEFAULT_TIMEOUT):
    """An import library standing in for DELMIA's: the host emulator cross-built as a DLL."""
    include, _ = host_support(timeout)
    command = mingw_command()
    folder = cache_dir() / f"host-windows-{digest(VERSION, render_header(), host_source(), *command)[:16]}"
    import_library = folder / "libkingen_host.dll.a"

    def make():
        write_atomic(folder / "kingen_host.c", host_source())
        compile_c([folder / "kingen_host.c"], folder / "kingen_host.dll",
                  [*STRICT_C89, "-O2", "-shared", f"-I{include}", f"-Wl,--out-implib,{import_library}"],
                  compiler=command, timeout=timeout)

    cached(folder, import_library, make, {"kingen_host.c": host_source()})
    return import_library


def library_name(robot, target="linux"):
    """lib<name>.so (or .dll), as DELMIA's Solver Attributes tab names the library (libtau)."""
    return f"{dialog.library_name(robot.name)}{'.dll' if target == 'windows' else '.so'}"


def build_plugin(robot, out_dir=None, defines=(), target="linux", timeout=DEFAULT_TIMEOUT):
    """Render and compile ``robot`` into ``out_dir`` (default build/<name>).

    Writes ``kin_<name>.c`` and ``lib<name>.so``, or for ``target="windows"`` a
    ``lib<name>.dll`` cross-compiled with mingw-w64 against a stand-in of DELMIA's import
    library and checked to export ``get_kin_config`` and the routine. ``defines`` are
    extra -D macros (for example KINGEN_DEBUG). Skips compiling when the stamp matches.
    """
    out_dir = Path(out_dir or default_out_dir(robot))
    (name, text), = render(robot).items()
    include, _ = host_support(timeout)
    if target == "windows":
        command = mingw_command()
        flags = [*STRICT_C89, "-O2", "-shared", f"-I{include}", *(f"-D{d}" for d in (*WINDOWS_DEFINES, *defines))]
        extra_sources = [windows_host_import_library(timeout)]
    else:
        command = compiler_command()
        flags = [*STRICT_C89, *SHARED_FLAGS, f"-I{include}", *(f"-D{d}" for d in defines)]
        extra_sources = []
    source, library = out_dir / name, out_dir / library_name(robot, target)
    key = digest(VERSION, text, *command, *flags)
    stamp = out_dir / f".kingen-build-{target}.json"
    if (read_stamp(stamp, "key") == key and read_stamp(stamp, "library_sha256") == file_digest(library)
            and file_digest(source) == hashlib.sha256(text.encode()).hexdigest()):
        return BuildResult(source, library, dialog.routine_name(robot.name), compiled=False)
    with tempfile.TemporaryDirectory(prefix="kingen-build-") as scratch:
        scratch_source, scratch_library = Path(scratch) / name, Path(scratch) / library.name
        scratch_source.write_text(text)
        try:
            compile_c([scratch_source, *extra_sources], scratch_library, flags, compiler=command, timeout=timeout,
                      shown_source=source)
        except CompileError:
            write_atomic(source, text)  # kept, so that the error's file:line can be opened
            raise
        if target == "windows":
            _check_exports(scratch_library, robot)
        data = scratch_library.read_bytes()
        write_atomic(source, text)
        write_atomic(library, data, executable=True)
    write_atomic(stamp, json.dumps({"key": key, "library_sha256": hashlib.sha256(data).hexdigest(),
                                    "robot": robot.name, "kingen": VERSION}) + "\n")
    return BuildResult(source, library, dialog.routine_name(robot.name), compiled=True)


def _check_exports(library, robot):
    missing = {"get_kin_config", dialog.routine_name(robot.name)} - set(dll_exports(library))
    if missing:
        raise KingenError(f"{library.name}: does not export {', '.join(sorted(missing))}")


LEGACY_FLAGS = ("-std=gnu99", "-O2", "-fPIC", "-shared")
"""For hand-written sources: K&R definitions, // comments and long double accepted, no -Werror."""


def legacy_library_name(source):
    """kin_hexapodFullTest.c -> libhexapodFullTest.so, the thesis's naming habit."""
    stem = Path(source).stem
    return f"lib{stem[4:] if stem.startswith('kin_') and len(stem) > 4 else stem}.so"


def build_legacy(source, out_dir, timeout=DEFAULT_TIMEOUT):
    """Compile a hand-written plugin source as DELMIA's makefile would, against the stand-in
    header with the host symbols left undefined; returns the library path.

    A source that does not compile raises KingenError with the compiler's first error."""
    source = Path(source)
    refuse_special_file(source)
    if not source.is_file():
        raise KingenError(f"{source}: no such C source")
    include, _ = host_support(timeout)
    library = Path(out_dir) / legacy_library_name(source)
    compile_c([source], library, [*LEGACY_FLAGS, f"-I{include}"], timeout=timeout)
    return library


def write_source(robot, out_dir):
    """Render ``robot`` and write ``kin_<name>.c`` into ``out_dir``; returns its path."""
    write_files({Path(out_dir) / name: text for name, text in render(robot).items()})
    return Path(out_dir) / source_name(robot)
