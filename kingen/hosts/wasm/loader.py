"""Loading a WebAssembly module of the C library into this process through wasmtime, and calling
it as the C host's :class:`~kingen.hosts.c.loader.Library` calls its shared library: the same
methods, the same checks (:data:`kingen.hosts.c.checks.CHECKS`), the batch driver compiled into
the module (:mod:`.build`). What differs is only how arguments reach the code: a NumPy array
handed to a module's function is copied into the module's memory from ``__heap_base`` on
(the library allocates nothing, so nothing of its own lives there), the function runs, and the
array is copied back (:class:`Call`). Function pointers are indices into the module's function
table, where an exported function is added once.

Imports: a module may import WASI functions only (any other import is a defect), answered by
wasmtime's WASI with nothing granted: no files, no environment, no arguments, no standard streams.
The generated module imports only ``clock_time_get``, the timed batch's monotonic clock.
"""

from pathlib import Path

import numpy as np

from ...errors import KingenError, PluginDefect
from ...runtime.file_gate import refuse_special_file
from ..c.loader import OPTIONAL_ENTRY_POINTS, Library, entry_points
from .build import BATCH_EXPORTS

WASI = "wasi_snapshot_preview1"
MAGIC = b"\0asm"
"""A WebAssembly binary's first bytes (wasmtime would read anything else as the text format)."""
ALIGNMENT = 16
PAGE = 65536
REQUIRED = ("memory", "__heap_base", "__indirect_function_table", *BATCH_EXPORTS)
"""What kingen calls in every module besides the library's own functions."""


class Buffer:
    """A NumPy array handed to a module's function, copied into its memory before the call and
    back after it (unless read-only); ``[i]`` reads its element i (a ``double *`` out-argument)."""

    def __init__(self, array):
        self.array = array

    def __getitem__(self, index):
        return self.array.reshape(-1)[index]


class Foreign:
    """What :class:`~kingen.hosts.c.loader.Library`'s methods ask of cffi, answered for a
    module: ``from_buffer`` and ``new`` make :class:`Buffer` arguments."""

    @staticmethod
    def from_buffer(ctype, array):
        return Buffer(array)

    @staticmethod
    def new(ctype):
        return Buffer(np.zeros(1))


class Module:
    """A module instantiated in its own wasmtime store: its exports and its memory as NumPy bytes."""

    def __init__(self, path):
        import wasmtime

        config = wasmtime.Config()
        config.parallel_compilation = False  # no compiler threads in the sandbox's process budget
        config.memory_may_move = False  # a view of the memory stays valid however the memory grows
        self.engine = wasmtime.Engine(config)
        self.store = wasmtime.Store(self.engine)
        binary = Path(path).read_bytes()
        if not binary.startswith(MAGIC):
            raise PluginDefect("the module cannot be loaded: not a WebAssembly binary (it does not start with \\0asm)")
        try:
            module = wasmtime.Module(self.engine, binary)
        except wasmtime.WasmtimeError as error:
            raise PluginDefect(f"the module cannot be loaded: {str(error).splitlines()[0]}") from None
        for wanted in module.imports:
            if wanted.module != WASI:
                raise PluginDefect(f"the module imports {wanted.module}.{wanted.name}: a routine may import "
                                   "only WASI functions")
        linker = wasmtime.Linker(self.engine)
        linker.define_wasi()
        self.store.set_wasi(wasmtime.WasiConfig())
        try:
            instance = linker.instantiate(self.store, module)
        except (wasmtime.WasmtimeError, wasmtime.Trap) as error:
            raise PluginDefect(f"the module cannot be instantiated: {str(error).splitlines()[0]}") from None
        self.exports = instance.exports(self.store)
        missing = [name for name in REQUIRED if name not in self.exports]
        if missing:
            raise PluginDefect(f"the module does not export {missing[0]} (kingen build --host wasm exports it)")
        self.memory = self.exports["memory"]
        self.base = self.exports["__heap_base"].value(self.store)
        self._bytes = None
        self.failures = (wasmtime.Trap, wasmtime.WasmtimeError)
        if "_initialize" in self.exports:
            Call(self, "_initialize")()

    def bytes(self, end):
        """The memory as uint8, grown to hold ``end`` bytes at least (the library itself never
        grows it: it allocates nothing, so a view stays valid until this grows it)."""
        if self._bytes is None or len(self._bytes) < end:
            size = self.memory.data_len(self.store)
            if size < end:
                self.memory.grow(self.store, -(-(end - size) // PAGE))
            self._bytes = np.ctypeslib.as_array(self.memory.data_ptr(self.store),
                                                shape=(self.memory.data_len(self.store),))
        return self._bytes

    def table_index(self, name):
        """The function table's index of the exported function ``name`` (added to the table)."""
        return self.exports["__indirect_function_table"].grow(self.store, 1, self.exports[name])


def trap_reason(error):
    """What a trap says of its cause: wasmtime's last line ("wasm trap: ..."), without its backtrace."""
    lines = [line.strip() for line in str(error).splitlines() if line.strip()]
    return lines[-1] if lines else type(error).__name__


class Call:
    """An exported function called with :class:`Buffer` arguments laid out from ``__heap_base``;
    a trap (or the module's exit through WASI) is a PluginDefect of the check ``crash``."""

    def __init__(self, module, name):
        self.module, self.name, self.function = module, name, module.exports[name]

    def __call__(self, *arguments):
        buffers, addresses, end = [], [], self.module.base
        for argument in arguments:
            if isinstance(argument, Buffer):
                buffers.append((end, argument.array))
                addresses.append(end)
                end += -(-argument.array.nbytes // ALIGNMENT) * ALIGNMENT
            else:
                addresses.append(int(argument))
        memory = self.module.bytes(end)
        for address, array in buffers:
            memory[address:address + array.nbytes] = np.ascontiguousarray(array).view(np.uint8).reshape(-1)
        try:
            returned = self.function(self.module.store, *addresses)
        except self.module.failures as error:
            raise PluginDefect(f"the module trapped in {self.name}: {trap_reason(error)}", check="crash") from None
        for address, array in buffers:
            if array.flags.writeable:
                array.reshape(-1)[...] = memory[address:address + array.nbytes].view(array.dtype)
        return returned


class Driver:
    """The batch driver's functions in the module, as the C host's cffi driver offers them."""

    def __init__(self, module):
        self.module = module

    def __getattr__(self, name):
        return Call(self.module, name)


class WasmLibrary(Library):
    """A WebAssembly module of the C library for ``robot``, loaded through wasmtime: the C host's
    :class:`~kingen.hosts.c.loader.Library` with the module in place of the shared library.
    KingenError for no such file; PluginDefect for a module that does not load, imports anything
    but WASI, or lacks a function of the header (but the optional ones)."""

    def __init__(self, library, routine, robot):
        path = Path(library).resolve()
        refuse_special_file(path)
        if not path.is_file():
            raise KingenError(f"{path}: no such module")
        self.module = Module(path)
        self.ffi = Foreign()
        self.functions, self.indices = {}, {}
        for name in entry_points(robot):
            symbol = f"{routine}_{name}"
            if symbol not in self.module.exports:
                if name in OPTIONAL_ENTRY_POINTS:
                    continue
                raise PluginDefect(f"the module does not export {symbol}")
            if name == "default_geometry":
                self.geometry = self.module.exports[symbol].value(self.module.store)
            else:
                self.functions[name] = Call(self.module, symbol)
                self.indices[name] = self.module.table_index(symbol)
        self.routine, self.robot = routine, robot
        self.dof, self.postures = robot.joint_count, robot.postures
        self.driver = Driver(self.module)

    def _pointer(self, ctype, array):
        return Buffer(array)

    def _function(self, name):
        return self.indices[name]

    def _geometry(self):
        return self.geometry
