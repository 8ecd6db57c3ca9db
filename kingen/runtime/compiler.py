"""The system C compiler, run safely: its command from ``$CC``, no stdin, its own process
group killed whole past a timeout, bounded memory and file size, a private temporary folder
removed after it, and its first error turned into one KingenError naming file and line.
Every host compiles through :func:`compile_c`."""

import os
import re
import resource
import shlex
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from pathlib import Path

from ..defaults import DEFAULT_TIMEOUT
from ..errors import KingenError
from .file_gate import refuse_special_file
from .files import umask


class CompileError(KingenError):
    """The compiler ran and refused the source; the message names its first error."""


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


def _limit_compiler():
    """In the compiler's process, before exec: bounded memory and file size, no core dumps."""
    for limit, value in ((resource.RLIMIT_AS, COMPILER_MEMORY), (resource.RLIMIT_FSIZE, COMPILER_FILE_SIZE),
                         (resource.RLIMIT_CORE, 0)):
        _, hard = resource.getrlimit(limit)
        resource.setrlimit(limit, (value if hard == resource.RLIM_INFINITY else min(value, hard), hard))


def run_compiler(command, timeout):
    """Run a compiler command: no stdin, its own process group (killed whole past ``timeout``
    seconds), bounded memory and output, and a fresh temporary folder of its own ($TMPDIR,
    $TMP and $TEMP in its environment; gcc's ``cc*.s`` and the like go there). That folder
    is removed once the compiler's group is killed, however this ends: a compiler error,
    the timeout, or SIGTERM (which the CLI turns into SystemExit). Returns (exit status,
    stderr text)."""
    try:
        scratch = tempfile.mkdtemp(prefix="kingen-cc-")
    except OSError as error:
        raise KingenError(f"{tempfile.gettempdir()}: no temporary folder for the compiler "
                          f"({error.strerror or error}; $TMPDIR)") from None
    private = {"TMPDIR": scratch, "TMP": scratch, "TEMP": scratch}
    try:
        try:
            process = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                       stderr=subprocess.STDOUT, env={**os.environ, "LC_ALL": "C", **private},
                                       start_new_session=True, preexec_fn=_limit_compiler)
        except (FileNotFoundError, PermissionError, NotADirectoryError):
            raise KingenError(f"C compiler '{command[0]}' not found or not executable: "
                              "install one or set CC") from None
        output = []
        reader = threading.Thread(target=_keep_head, args=(process.stdout, output, 64 << 10), daemon=True)
        reader.start()
        try:
            status = process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise KingenError(f"compiler did not finish in {timeout:g} s (--timeout, $KINGEN_TIMEOUT)") from None
        finally:
            _kill_group(process)
            reader.join(timeout=5)
            process.stdout.close()
        return status, b"".join(output).decode(errors="replace")
    finally:
        _remove_folder(scratch)


def _keep_head(stream, kept, limit):
    """Read ``stream`` to its end through a pipe (no file, so a full disk cannot swallow the
    compiler's own "No space left on device"), keeping its first ``limit`` bytes."""
    size = 0
    for block in iter(lambda: stream.read(8192), b""):
        if size < limit:
            kept.append(block[:limit - size])
            size += len(kept[-1])


def _remove_folder(folder, attempts=20):
    """Remove ``folder`` and what is in it; a killed compiler's helpers (cc1, as) may still
    finish a file they were creating as they die, so a folder that is not gone yet is tried
    again a few times, 50 ms apart."""
    for _ in range(attempts):
        shutil.rmtree(folder, ignore_errors=True)
        if not os.path.lexists(folder):
            return
        time.sleep(0.05)


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


def compile_given_source(source, out_dir, flags, timeout=DEFAULT_TIMEOUT, *, suffix=".so", compiler=None, extra=()):
    """Compile a user's C source (a regular file, else KingenError), with kingen's ``extra``
    sources, into ``out_dir`` as ``<stem><suffix>`` with ``flags`` and ``compiler`` (default
    :func:`compiler_command`); the output's path."""
    source = Path(source)
    refuse_special_file(source)
    if not source.is_file():
        raise KingenError(f"{source}: no such C source")
    library = Path(out_dir) / f"{source.stem}{suffix}"
    compile_c([source, *extra], library, list(flags), compiler=compiler, timeout=timeout)
    return library
