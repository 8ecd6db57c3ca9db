"""Building: write rendered sources atomically and compile them with the system C compiler.

Plugins are built exactly as for DELMIA: against the stand-in ``shlibdefs.h``, with
the host symbols (``DNBVMAP_*``) left undefined for the host process to resolve.
The stand-in header and the host emulator library live in a cache folder
(``$KINGEN_CACHE``, else ``~/.cache/kingen``) keyed by their content and compiler.
A plugin build is skipped when its folder already holds the same source built
with the same compiler and flags (``.kingen-build.json``).
"""

import hashlib
import json
import os
import shlex
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

from . import __version__
from .errors import KingenError
from .pe import dll_exports
from .render import render, render_header, host_source, source_name

STRICT_C89 = ("-std=c89", "-pedantic", "-Wall", "-Wextra", "-Werror")
"""The dialect and warnings every generated source must pass (old Visual C is C89)."""
SHARED_FLAGS = ("-O2", "-fPIC", "-shared")
WINDOWS_DEFINES = ("WINDOWS_SHELL", "_DNBUSERLIB", "WINDOWS_SOURCE", "NDEBUG", "WIN32", "WINNT", "WINDOWS_NT")
"""The vendor makefile's defines (plus WINDOWS_SOURCE, which turns DllExport into dllexport)."""
MINGW = "x86_64-w64-mingw32-gcc"
TARGETS = ("linux", "windows")


@dataclass(frozen=True)
class BuildResult:
    """Paths of a built plugin; ``compiled`` is False when the cache was up to date."""

    source: Path
    library: Path
    routine: str
    compiled: bool


def compiler_command():
    """The C compiler as an argument list: ``$CC`` (may hold flags), else ``cc``."""
    return shlex.split(os.environ.get("CC") or "cc")


def write_atomic(path, content):
    """Write text or bytes to ``path`` through a temporary file and a rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    data = content.encode() if isinstance(content, str) else content
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def compile_c(sources, output, flags, compiler=None):
    """Compile ``sources`` into ``output`` (atomically); compiler errors become a KingenError.

    The error names the compiler's first diagnostic line (file:line: error: ...).
    """
    command = list(compiler or compiler_command())
    output = Path(output)
    output.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=output.parent, prefix=f".{output.name}.")
    os.close(handle)
    try:
        try:
            result = subprocess.run(
                [*command, *flags, *map(str, sources), "-o", temporary, "-lm"],
                capture_output=True, text=True, env={**os.environ, "LC_ALL": "C"},
            )
        except FileNotFoundError:
            raise KingenError(f"C compiler '{command[0]}' not found: install one or set CC") from None
        if result.returncode != 0:
            diagnostic = first_diagnostic(result.stderr)
            if not diagnostic.startswith(str(sources[0])):
                diagnostic = f"{' '.join(map(str, sources))}: {diagnostic}"
            raise KingenError(f"does not compile: {diagnostic}")
        os.replace(temporary, output)
    finally:
        Path(temporary).unlink(missing_ok=True)


def first_diagnostic(stderr):
    """The compiler's first error line (or first line) with file and line, stripped."""
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    for line in lines:
        if "error" in line.lower():
            return line
    return lines[0] if lines else "the compiler failed without a message"


def _digest(*parts):
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()


def cache_dir():
    """kingen's cache folder for the stand-in header and the host emulator."""
    return Path(os.environ.get("KINGEN_CACHE") or Path.home() / ".cache" / "kingen")


def host_support():
    """(include folder with shlibdefs.h, host emulator library), built once per content."""
    header, source = render_header(), host_source()
    command = compiler_command()
    folder = cache_dir() / f"host-{_digest(__version__, header, source, *command)[:16]}"
    include, library = folder / "include", folder / "libkingen_host.so"
    if not library.is_file():
        write_atomic(include / "shlibdefs.h", header)
        write_atomic(folder / "kingen_host.c", source)
        compile_c([folder / "kingen_host.c"], library, [*STRICT_C89, *SHARED_FLAGS, f"-I{include}"])
    return include, library


def mingw_command():
    """The mingw-w64 cross compiler (``$KINGEN_MINGW_CC``, else x86_64-w64-mingw32-gcc)."""
    command = shlex.split(os.environ.get("KINGEN_MINGW_CC") or MINGW)
    if shutil.which(command[0]) is None:
        raise KingenError(f"Windows cross compiler '{command[0]}' not found: install Debian's "
                          "gcc-mingw-w64-x86-64 or set KINGEN_MINGW_CC")
    return command


def windows_host_import_library():
    """An import library standing in for DELMIA's: the host emulator cross-built as a DLL."""
    include, _ = host_support()
    command = mingw_command()
    folder = cache_dir() / f"host-windows-{_digest(__version__, render_header(), host_source(), *command)[:16]}"
    import_library = folder / "libkingen_host.dll.a"
    if not import_library.is_file():
        write_atomic(folder / "kingen_host.c", host_source())
        compile_c([folder / "kingen_host.c"], folder / "kingen_host.dll",
                  [*STRICT_C89, "-O2", "-shared", f"-I{include}", f"-Wl,--out-implib,{import_library}"],
                  compiler=command)
    return import_library


def default_out_dir(robot):
    return Path("build") / robot.name


def library_name(robot, target="linux"):
    """lib<name>.so (or .dll), as DELMIA's Solver Attributes tab names the library (libtau)."""
    return f"{robot.library}{'.dll' if target == 'windows' else '.so'}"


def build_plugin(robot, out_dir=None, defines=(), target="linux"):
    """Render and compile ``robot`` into ``out_dir`` (default build/<name>).

    Writes ``kin_<name>.c`` and ``lib<name>.so``, or for ``target="windows"`` a
    ``lib<name>.dll`` cross-compiled with mingw-w64 against a stand-in of DELMIA's import
    library and checked to export ``get_kin_config`` and the routine. ``defines`` are
    extra -D macros (for example KINGEN_DEBUG). Skips compiling when the stamp matches.
    """
    out_dir = Path(out_dir or default_out_dir(robot))
    (name, text), = render(robot).items()
    include, _ = host_support()
    if target == "windows":
        command = mingw_command()
        flags = [*STRICT_C89, "-O2", "-shared", f"-I{include}", *(f"-D{d}" for d in (*WINDOWS_DEFINES, *defines))]
        extra_sources = [windows_host_import_library()]
    else:
        command = compiler_command()
        flags = [*STRICT_C89, *SHARED_FLAGS, f"-I{include}", *(f"-D{d}" for d in defines)]
        extra_sources = []
    source, library = out_dir / name, out_dir / library_name(robot, target)
    key = _digest(__version__, text, *command, *flags)
    stamp = out_dir / f".kingen-build-{target}.json"
    if library.is_file() and source.is_file() and _read_stamp(stamp) == key and source.read_text() == text:
        return BuildResult(source, library, robot.routine, compiled=False)
    with tempfile.TemporaryDirectory(prefix="kingen-build-") as scratch:
        scratch_source, scratch_library = Path(scratch) / name, Path(scratch) / library.name
        scratch_source.write_text(text)
        compile_c([scratch_source, *extra_sources], scratch_library, flags, compiler=command)
        if target == "windows":
            _check_exports(scratch_library, robot)
        write_atomic(source, text)
        write_atomic(library, scratch_library.read_bytes())
    write_atomic(stamp, json.dumps({"key": key, "robot": robot.name, "kingen": __version__}) + "\n")
    return BuildResult(source, library, robot.routine, compiled=True)


def _check_exports(library, robot):
    missing = {"get_kin_config", robot.routine} - set(dll_exports(library))
    if missing:
        raise KingenError(f"{library.name}: does not export {', '.join(sorted(missing))}")


LEGACY_FLAGS = ("-std=gnu99", "-O2", "-fPIC", "-shared")
"""For hand-written sources: K&R definitions, // comments and long double accepted, no -Werror."""


def legacy_library_name(source):
    """kin_hexapodFullTest.c -> libhexapodFullTest.so, the thesis's naming habit."""
    stem = Path(source).stem
    return f"lib{stem[4:] if stem.startswith('kin_') and len(stem) > 4 else stem}.so"


def build_legacy(source, out_dir):
    """Compile a hand-written plugin source as DELMIA's makefile would, against the stand-in
    header with the host symbols left undefined; returns the library path.

    A source that does not compile raises KingenError with the compiler's first error."""
    source = Path(source)
    if not source.is_file():
        raise KingenError(f"{source}: no such C source")
    include, _ = host_support()
    library = Path(out_dir) / legacy_library_name(source)
    compile_c([source], library, [*LEGACY_FLAGS, f"-I{include}"])
    return library


def write_source(robot, out_dir):
    """Render ``robot`` and write ``kin_<name>.c`` into ``out_dir``; returns its path."""
    for name, text in render(robot).items():
        write_atomic(Path(out_dir) / name, text)
    return Path(out_dir) / source_name(robot)


def _read_stamp(stamp):
    try:
        return json.loads(stamp.read_text()).get("key")
    except (OSError, ValueError):
        return None

