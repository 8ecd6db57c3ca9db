"""Compiling the C host's library to WebAssembly: the very source :mod:`kingen.hosts.c.render`
writes (the same verified code, unchanged) and the C host's batch driver, compiled by clang for
``wasm32-wasi`` against wasi-libc into one reactor module (no ``main``, ``_initialize`` runs
its constructors) that imports nothing but WASI's ``clock_time_get`` (the timed batch's clock),
kept in kingen's cache per content, flags and compiler. The toolchain is Debian's: clang, lld
(``wasm-ld``), wasi-libc and the wasm32 compiler-rt builtins (libclang-rt-14-dev-wasm32);
``$KINGEN_WASM_CC`` replaces ``clang`` (and may hold flags, ``--sysroot=`` a wasi-sdk's)."""

import functools
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

from ...defaults import DEFAULT_TIMEOUT, VERSION
from ...errors import KingenError
from ...runtime.compiler import compile_c, compile_given_source, compiler_command, first_diagnostic, run_compiler
from ...runtime.files import cache_dir, cached, default_out_dir, digest, write_atomic, write_files
from ..base import BuildResult
from ..c.build import STRICT_FLAGS, write_source
from ..c.render import file_names, prefix, render

BATCH = Path(__file__).resolve().parents[1] / "c" / "templates" / "kingen_c_batch.c"
"""The C host's batch driver, compiled into the module as it is into its shared library."""
EXPORTED = ("inverse", "inverse_posture", "forward", "jacobian", "direct_index", "machine_pose", "static_loads",
            "default_geometry", "default_payload", "build_info")
"""The library's names the module exports where the source defines them (``<prefix>_<name>``)."""
BATCH_EXPORTS = ("kingen_c_inverse_batch", "kingen_c_forward_batch", "kingen_c_machine_pose_batch",
                 "kingen_c_timed_batch")
TARGET_FLAGS = ("--target=wasm32-wasi", "-mexec-model=reactor")
LINK_FLAGS = ("-Wl,--export=malloc", "-Wl,--export=free", "-Wl,--export-table", "-Wl,--growable-table")
"""A reactor's own allocator exported (``malloc`` and ``free``: a caller's buffers come from it,
so they never overlap what the library itself allocates) and its function table, growable (a
caller adds an exported function to it to pass it to the batch driver)."""
SOURCE_FLAGS = (*TARGET_FLAGS, "-std=c99", "-O2", "-fvisibility=default", "-Wl,--export-dynamic", *LINK_FLAGS)
"""A hand-written source's flags: warnings allowed, and every symbol of default visibility
exported, so its names are exported whatever the file is called (``--routine`` names them)."""
WASM_FLAGS = (*TARGET_FLAGS, *STRICT_FLAGS, "-O2", "-fno-fast-math", *LINK_FLAGS)
"""The generated library's flags: the C library's strict C99, as its shared library compiles."""
GLUE = Path(__file__).resolve().parent / "templates" / "kingen_wasm.js"
"""The JavaScript glue: instantiates a module from its bytes, offers inverse and forward in
kingen's units (its opening comment documents the exports and memory layout)."""
PACKAGES = {"clang": "clang", "wasm-ld": "lld", "wasi-libc": "wasi-libc",
            "compiler-rt": "libclang-rt-14-dev-wasm32"}
"""What each part of the toolchain is installed with, on Debian."""
PROBE = "#include <math.h>\ndouble kingen_probe(double x) { return sqrt(x) + fmod(x, 3.0); }\n"
_MISSING = (("compiler-rt", re.compile(r"libclang_rt\.builtins-wasm32")),
            ("wasi-libc", re.compile(r"math\.h' file not found|cannot open crt1|unable to find library -l[cm]\b|libc\.a")),
            ("wasm-ld", re.compile(r"Executable \"wasm-ld[^\"]*\" doesn't exist|invalid linker name")))
"""Which part a failed probe lacks, by what clang or wasm-ld says: tried in this order (a
missing library is a linker error too, so the linker is named only when clang cannot run it)."""


@dataclass(frozen=True)
class WasmToolchain:
    """Whether kingen can compile WebAssembly here: ``ready``, else ``problem``, one line naming
    the missing part and the Debian package that installs it."""

    ready: bool
    problem: Optional[str] = None


def wasm_compiler():
    """The WebAssembly compiler command: ``$KINGEN_WASM_CC``, else ``clang``."""
    return compiler_command("KINGEN_WASM_CC", "clang")


@functools.lru_cache(maxsize=None)
def _probe(command, timeout):
    """The toolchain's state for ``command``, kept for the process: a compiler not found, or the
    probe's compile and link judged (:data:`_MISSING`). KingenError, kept for no one, when the
    compiler did not finish within ``timeout`` s (a slow machine is not a missing part)."""
    if shutil.which(command[0]) is None:
        return WasmToolchain(False, f"WebAssembly toolchain: {command[0]} is not installed "
                                    f"(Debian package {PACKAGES['clang']}; or set $KINGEN_WASM_CC)")
    with tempfile.TemporaryDirectory(prefix="kingen-wasm-probe-") as folder:
        source = Path(folder) / "probe.c"
        source.write_text(PROBE)
        status, output = run_compiler([*command, *TARGET_FLAGS, "-Wl,--export=kingen_probe", str(source), "-o",
                                       str(Path(folder) / "probe.wasm"), "-lm"], timeout)
    if status == 0:
        return WasmToolchain(True)
    part = next((part for part, pattern in _MISSING if pattern.search(output)), None)
    said = first_diagnostic(output.replace(str(source), source.name), status)
    if part is None:
        return WasmToolchain(False, f"WebAssembly toolchain: {command[0]} --target=wasm32-wasi does not link: {said}")
    return WasmToolchain(False, f"WebAssembly toolchain: {part} is not installed (Debian package {PACKAGES[part]}): "
                                f"{command[0]} --target=wasm32-wasi says: {said}")


def wasm_toolchain(timeout=DEFAULT_TIMEOUT):
    """Whether the WebAssembly toolchain works (a small C file with ``<math.h>`` compiled and
    linked for wasm32-wasi, once per process and compiler command) and, if not, why. A probe
    that timed out is said as such and tried again on the next call."""
    command = tuple(wasm_compiler())
    try:
        return _probe(command, timeout)
    except KingenError as error:
        return WasmToolchain(False, f"WebAssembly toolchain: {command[0]} --target=wasm32-wasi: {error}")


def require_toolchain(timeout=DEFAULT_TIMEOUT):
    """The compiler command; KingenError (its ``problem``) when the toolchain is not ready."""
    toolchain = wasm_toolchain(timeout)
    if not toolchain.ready:
        raise KingenError(toolchain.problem)
    return wasm_compiler()


def export_flags(routine):
    """Linker flags exporting ``routine``'s names (where defined) and the batch driver's."""
    return [*(f"-Wl,--export-if-defined={routine}_{name}" for name in EXPORTED),
            *(f"-Wl,--export={name}" for name in BATCH_EXPORTS)]


def compile_module(sources, module, routine, flags=WASM_FLAGS, timeout=DEFAULT_TIMEOUT, shown_source=None):
    """Compile C ``sources`` (with the batch driver) into the WebAssembly ``module``, atomically."""
    command = require_toolchain(timeout)
    compile_c([*sources, BATCH], module, [*flags, *export_flags(routine)], compiler=command, timeout=timeout,
              shown_source=shown_source)


def compile_wasm(robot, timeout=DEFAULT_TIMEOUT):
    """The path of ``robot``'s C library compiled to WebAssembly (``kingen_<name>.wasm``), in
    kingen's cache: compiled when its sources, flags, compiler command or kingen's version
    changed, else the cached module (checked against its recorded hash). KingenError naming
    what is missing when the toolchain is not ready (:func:`wasm_toolchain`)."""
    command = require_toolchain(timeout)
    files = render(robot)
    folder = cache_dir() / f"wasm-{robot.name}-{digest(VERSION, *command, *WASM_FLAGS, *files.values(), BATCH.read_text())[:16]}"
    module = folder / f"{prefix(robot)}.wasm"

    def make():
        write_files({folder / name: text for name, text in files.items()})
        compile_module([folder / file_names(robot)[1]], module, prefix(robot), timeout=timeout,
                       shown_source=Path(file_names(robot)[1]))

    cached(folder, module, make, files)
    return module


def module_meta(robot):
    """What the JavaScript glue is given with ``robot``'s module (``KingenWasm.create(bytes,
    meta)``): its names' ``prefix``, ``dof`` (joints per posture, a wrist's included) and ``postures``."""
    return {"prefix": prefix(robot), "dof": robot.joint_count, "postures": robot.postures}


def default_dir(robot):
    """Where ``kingen build ROBOT --host wasm`` writes: build/<name>/wasm."""
    return default_out_dir(robot) / "wasm"


def build_wasm(robot, out_dir=None, timeout=DEFAULT_TIMEOUT):
    """``robot``'s header, source and module written into ``out_dir`` (default :func:`default_dir`)."""
    out_dir = Path(out_dir or default_dir(robot))
    module = compile_wasm(robot, timeout)
    source = write_source(robot, out_dir)
    target = out_dir / module.name
    write_atomic(target, module.read_bytes())
    return BuildResult(source, target, prefix(robot), compiled=True)


def build_source(source, out_dir, timeout=DEFAULT_TIMEOUT):
    """A hand-written library source (its header beside it, the generated one's names under
    any prefix) compiled with the batch driver to ``<stem>.wasm`` in ``out_dir``; warnings
    allowed. The module's path."""
    return compile_given_source(source, out_dir, [*SOURCE_FLAGS, f"-I{Path(source).parent}",
                                                  *(f"-Wl,--export={name}" for name in BATCH_EXPORTS)],
                                timeout=timeout, suffix=".wasm", compiler=require_toolchain(timeout), extra=(BATCH,))


__all__ = ["GLUE", "WasmToolchain", "module_meta", "build_source", "build_wasm", "compile_wasm", "default_dir",
           "wasm_toolchain"]
