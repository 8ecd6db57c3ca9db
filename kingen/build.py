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
import pwd
import re
import resource
import shlex
import shutil
import signal
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

from . import __version__
from .defaults import DEFAULT_TIMEOUT
from .errors import KingenError
from .pe import dll_exports
from .render import render, render_header, host_source, source_name

STRICT_C89 = ("-std=c89", "-pedantic", "-Wall", "-Wextra", "-Werror")
"""The dialect and warnings every generated source must pass (old Visual C is C89)."""
SHARED_FLAGS = ("-O2", "-fPIC", "-shared")
WINDOWS_DEFINES = ("WINDOWS_SHELL", "_DNBUSERLIB", "WINDOWS_SOURCE", "NDEBUG", "WIN32", "WINNT", "WINDOWS_NT")
"""The vendor makefile's defines (plus WINDOWS_SOURCE, which turns DllExport into dllexport)."""
MINGW = "x86_64-w64-mingw32-gcc"


class CompileError(KingenError):
    """The compiler ran and refused the source; the message names its first error."""


@dataclass(frozen=True)
class BuildResult:
    """Paths of a built plugin; ``compiled`` is False when the cache was up to date."""

    source: Path
    library: Path
    routine: str
    compiled: bool


COMPILER_MEMORY = 4 << 30
COMPILER_FILE_SIZE = 256 << 20
"""Address space and largest file a compiler run may use: a source that includes /dev/zero
ends in a compiler error, not in a machine out of memory or disk."""
_DIAGNOSTIC = re.compile(r"^(?P<where>\S.*?:\d+(?::\d+)?): (?:fatal )?error: ", re.MULTILINE)


def compiler_command(variable="CC", default="cc"):
    """A compiler as an argument list: ``$CC`` (may hold flags), else ``cc``."""
    text = os.environ.get(variable) or default
    try:
        command = shlex.split(text)
    except ValueError as error:
        raise KingenError(f"${variable}: cannot be split into a command ({error}): {text!r}") from None
    if not command:
        raise KingenError(f"${variable} holds no command: set it to a C compiler or unset it")
    return command


def umask():
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_atomic(path, content, executable=False):
    """Write text or bytes to ``path`` through a temporary file and a rename. The file gets
    the permissions the user's umask gives a new file (0644 under umask 022; 0755 when
    ``executable``), never the temporary file's 0600."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    data = content.encode() if isinstance(content, str) else content
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
        os.chmod(temporary, (0o777 if executable else 0o666) & ~umask())
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def _limit_compiler():
    """In the compiler's process, before exec: bounded memory and file size, no core dumps."""
    for limit, value in ((resource.RLIMIT_AS, COMPILER_MEMORY), (resource.RLIMIT_FSIZE, COMPILER_FILE_SIZE),
                         (resource.RLIMIT_CORE, 0)):
        _, hard = resource.getrlimit(limit)
        resource.setrlimit(limit, (value if hard == resource.RLIM_INFINITY else min(value, hard), hard))


def run_compiler(command, timeout):
    """Run a compiler command: no stdin, its own process group (killed whole past ``timeout``
    seconds), bounded memory and output. Returns (exit status, stderr text)."""
    with tempfile.TemporaryFile() as errors:
        try:
            process = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=errors, stderr=errors,
                                       env={**os.environ, "LC_ALL": "C"}, start_new_session=True,
                                       preexec_fn=_limit_compiler)
        except (FileNotFoundError, PermissionError, NotADirectoryError):
            raise KingenError(f"C compiler '{command[0]}' not found or not executable: "
                              "install one or set CC") from None
        try:
            status = process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise KingenError(f"compiler did not finish in {timeout:g} s (--timeout, $KINGEN_TIMEOUT)") from None
        finally:
            _kill_group(process)
        errors.seek(0)
        return status, errors.read(64 << 10).decode(errors="replace")


def _kill_group(process):
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    process.wait()


def compile_c(sources, output, flags, compiler=None, timeout=DEFAULT_TIMEOUT, shown_source=None):
    """Compile ``sources`` into ``output`` (atomically, mode 0755 under umask 022); compiler
    errors become a KingenError naming the compiler's first error (file:line: error: ...).
    ``shown_source`` replaces the first source's path in that message (a scratch copy's
    path is useless to the user)."""
    command = list(compiler or compiler_command())
    output = Path(output)
    output.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=output.parent, prefix=f".{output.name}.")
    os.close(handle)
    try:
        status, stderr = run_compiler([*command, *flags, *map(str, sources), "-o", temporary, "-lm"], timeout)
        if status != 0:
            diagnostic = first_diagnostic(stderr, status)
            if shown_source is not None:
                diagnostic = diagnostic.replace(str(sources[0]), str(shown_source))
            first = str(shown_source or sources[0])
            if not diagnostic.startswith(first):
                diagnostic = f"{first}: {diagnostic}"
            raise CompileError(f"does not compile: {diagnostic}")
        os.chmod(temporary, 0o777 & ~umask())
        os.replace(temporary, output)
    finally:
        Path(temporary).unlink(missing_ok=True)


def first_diagnostic(stderr, status=1):
    """The compiler's first error as 'file:line[:column]: error: ...' (gcc, clang and tcc
    style); else its first line; else how it ended."""
    match = _DIAGNOSTIC.search(stderr)
    if match:
        return stderr[match.start():].splitlines()[0].strip()
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    if lines:
        return lines[0]
    if status < 0:
        return f"the compiler was killed by signal {signal.Signals(-status).name}"
    return f"the compiler failed without a message (exit status {status})"


def _digest(*parts):
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()


def cache_dir():
    """kingen's cache folder for the stand-in header and the host emulator: ``$KINGEN_CACHE``,
    else ``$XDG_CACHE_HOME/kingen``, else ``~/.cache/kingen`` (home from $HOME or the password
    database; an empty or relative value is ignored), else a per-user folder in the temp dir."""
    if os.environ.get("KINGEN_CACHE"):
        return Path(os.environ["KINGEN_CACHE"]).absolute()
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    if os.path.isabs(xdg):
        return Path(xdg) / "kingen"
    for home in (os.environ.get("HOME", ""), _password_home()):
        if os.path.isabs(home) and home != "/":
            return Path(home) / ".cache" / "kingen"
    return Path(tempfile.gettempdir()) / f"kingen-cache-{os.getuid()}"


def _password_home():
    try:
        return pwd.getpwuid(os.getuid()).pw_dir
    except KeyError:
        return ""


def _file_digest(path):
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return None


def _cached(folder, library, make):
    """``library`` in cache ``folder``, made by ``make()`` unless the folder's stamp records
    exactly its hash (a truncated or foreign file is rebuilt, never trusted)."""
    stamp = folder / "stamp.json"
    if _read_stamp(stamp, "library_sha256") == _file_digest(library) is not None:
        return
    try:
        make()
        write_atomic(stamp, json.dumps({"library_sha256": _file_digest(library)}) + "\n")
    except PermissionError as error:
        raise KingenError(f"kingen's cache folder {folder} is not writable ({error.strerror}): "
                          "set KINGEN_CACHE to a folder of your own") from None


def host_support(timeout=DEFAULT_TIMEOUT):
    """(include folder with shlibdefs.h, host emulator library), built once per content."""
    header, source = render_header(), host_source()
    command = compiler_command()
    folder = cache_dir() / f"host-{_digest(__version__, header, source, *command)[:16]}"
    include, library = folder / "include", folder / "libkingen_host.so"

    def make():
        write_atomic(include / "shlibdefs.h", header)
        write_atomic(folder / "kingen_host.c", source)
        compile_c([folder / "kingen_host.c"], library, [*STRICT_C89, *SHARED_FLAGS, f"-I{include}"], timeout=timeout)

    _cached(folder, library, make)
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
    folder = cache_dir() / f"host-windows-{_digest(__version__, render_header(), host_source(), *command)[:16]}"
    import_library = folder / "libkingen_host.dll.a"

    def make():
        write_atomic(folder / "kingen_host.c", host_source())
        compile_c([folder / "kingen_host.c"], folder / "kingen_host.dll",
                  [*STRICT_C89, "-O2", "-shared", f"-I{include}", f"-Wl,--out-implib,{import_library}"],
                  compiler=command, timeout=timeout)

    _cached(folder, import_library, make)
    return import_library


def default_out_dir(robot):
    return Path("build") / robot.name


def library_name(robot, target="linux"):
    """lib<name>.so (or .dll), as DELMIA's Solver Attributes tab names the library (libtau)."""
    return f"{robot.library}{'.dll' if target == 'windows' else '.so'}"


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
    key = _digest(__version__, text, *command, *flags)
    stamp = out_dir / f".kingen-build-{target}.json"
    if (_read_stamp(stamp, "key") == key and _read_stamp(stamp, "library_sha256") == _file_digest(library)
            and _file_digest(source) == hashlib.sha256(text.encode()).hexdigest()):
        return BuildResult(source, library, robot.routine, compiled=False)
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
                                    "robot": robot.name, "kingen": __version__}) + "\n")
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


def build_legacy(source, out_dir, timeout=DEFAULT_TIMEOUT):
    """Compile a hand-written plugin source as DELMIA's makefile would, against the stand-in
    header with the host symbols left undefined; returns the library path.

    A source that does not compile raises KingenError with the compiler's first error."""
    source = Path(source)
    if not source.is_file():
        raise KingenError(f"{source}: no such C source")
    include, _ = host_support(timeout)
    library = Path(out_dir) / legacy_library_name(source)
    compile_c([source], library, [*LEGACY_FLAGS, f"-I{include}"], timeout=timeout)
    return library


def write_source(robot, out_dir):
    """Render ``robot`` and write ``kin_<name>.c`` into ``out_dir``; returns its path."""
    for name, text in render(robot).items():
        write_atomic(Path(out_dir) / name, text)
    return Path(out_dir) / source_name(robot)


def _read_stamp(stamp, key):
    try:
        return json.loads(stamp.read_text()).get(key)
    except (OSError, ValueError, AttributeError):
        return None

