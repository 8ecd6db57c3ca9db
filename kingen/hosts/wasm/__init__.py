"""The C library compiled to WebAssembly (``--host wasm``): the same generated, verified C
(:mod:`kingen.hosts.c`) built by clang for wasm32-wasi into a self-contained module, for a
browser (kingen's 3D view) or any WebAssembly runtime, with a dependency-free JavaScript glue
(``templates/kingen_wasm.js``). Built by :mod:`.build`."""

from ...defaults import DEFAULT_TIMEOUT
from ...errors import KingenError
from ..c import CHost


class WasmHost(CHost):
    """The C host's library (its render, names, routine and checks) built and loaded as a module."""

    name = "wasm"
    description = "the C library compiled to WebAssembly, for a browser or any WebAssembly runtime"
    loading_stage = "loading the module"
    per_call = "wasmtime"

    def out_dir(self, robot):
        from .build import default_dir

        return default_dir(robot)

    def build(self, robot, out_dir=None, *, target=None, defines=(), timeout=DEFAULT_TIMEOUT):
        from .build import build_wasm

        if defines:
            raise KingenError("--debug: --host wasm has no debug build (the module cannot print)")
        return build_wasm(robot, out_dir, timeout=timeout)

    def build_source(self, source, out_dir, *, timeout=DEFAULT_TIMEOUT):
        from .build import build_source

        return build_source(source, out_dir, timeout=timeout)

    def prepare_load(self):
        """The module runs in wasmtime: KingenError when the package is not installed."""
        try:
            import wasmtime  # noqa: F401
        except ImportError:
            raise KingenError("--host wasm: loading a module needs the Python package wasmtime "
                              "(pip install 'kingen[wasm]')") from None

    def load(self, library, routine, robot=None):
        from .loader import WasmLibrary

        return WasmLibrary(library, routine, robot)

    def package(self, robot, out_dir, *, target=None, timeout=DEFAULT_TIMEOUT):
        from .package import write_package

        return write_package(robot, out_dir, timeout=timeout)

    def package_dir(self, robot, target):
        return self.out_dir(robot) / "package"
