"""Building the C host's library for verification and benchmarks: ``kingen_<name>.h`` and
``kingen_<name>.c`` written, the source compiled into ``libkingen_<name>.so`` at C99 with
every warning an error (the flags a controller's build would use, and -O2)."""

import tempfile
from pathlib import Path

from ...defaults import DEFAULT_TIMEOUT
from ...runtime.compiler import CompileError, compile_c, compile_given_source
from ...runtime.files import default_out_dir, write_atomic, write_files
from ..base import BuildResult
from .render import file_names, prefix, render

STRICT_FLAGS = ("-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror")
"""What the library compiles warning-free under, with gcc and clang (and as C++17 without -std)."""
LIBRARY_FLAGS = (*STRICT_FLAGS, "-O2", "-fPIC", "-shared", "-fno-fast-math")


def default_dir(robot):
    return default_out_dir(robot) / "c"


def write_source(robot, out_dir):
    """Write header and source into ``out_dir``; the source's path."""
    write_files({Path(out_dir) / name: text for name, text in render(robot).items()})
    return Path(out_dir) / file_names(robot)[1]


def build_library(robot, out_dir=None, timeout=DEFAULT_TIMEOUT):
    """Render ``robot`` into ``out_dir`` (default build/<name>/c) and compile the shared library
    ``kingen_<name>.so`` there, the library replaced only once it compiled."""
    out_dir = Path(out_dir or default_dir(robot))
    files = render(robot)
    source = out_dir / file_names(robot)[1]
    library = out_dir / f"{prefix(robot)}.so"
    with tempfile.TemporaryDirectory(prefix="kingen-build-") as scratch:
        for name, text in files.items():
            (Path(scratch) / name).write_text(text)
        built = Path(scratch) / library.name
        try:
            compile_c([Path(scratch) / source.name], built, [*LIBRARY_FLAGS, f"-I{scratch}"], timeout=timeout,
                      shown_source=source)
        finally:
            write_files({out_dir / name: text for name, text in files.items()})
        write_atomic(library, built.read_bytes(), executable=True)
    return BuildResult(source, library, prefix(robot), compiled=True)


def build_source(source, out_dir, timeout=DEFAULT_TIMEOUT):
    """Compile a hand-written library source (its header beside it) as a shared library;
    warnings allowed. Returns the library's path."""
    return compile_given_source(source, out_dir, ["-std=c99", "-O2", "-fPIC", "-shared", f"-I{Path(source).parent}"],
                                timeout=timeout)


__all__ = ["CompileError", "build_library", "build_source", "default_dir", "write_source"]
