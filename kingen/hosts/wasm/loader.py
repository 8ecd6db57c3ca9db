"""Loading a WebAssembly module of the C library into this process through wasmtime, and calling
it as the C host's :class:`~kingen.hosts.c.loader.Library` calls its shared library: the same
methods, the same checks (:data:`kingen.hosts.c.checks.CHECKS`), the batch driver compiled into
the module (:mod:`.build`). What differs is only how arguments reach the code: a NumPy array
handed to a module's function is copied into a block of the module's memory obtained from the
module's own ``malloc`` (so a library that allocates cannot be handed the same bytes), the
function runs, and the outputs are copied back (:class:`Call`). Function pointers are indices
into the module's function table, where an exported function is added once.

Imports: a module may import WASI functions only (any other import is a defect), answered by
wasmtime's WASI with nothing granted: no files, no environment, no arguments, no standard streams.
The generated module imports only ``clock_time_get``, the timed batch's monotonic clock.
"""

from pathlib import Path

import numpy as np

from ...errors import KingenError, PluginDefect
from ...runtime.file_gate import refuse_special_file
from ..c.loader import OPTIONAL_ENTRY_POINTS, Library, entry_points, poses_of
from .build import BATCH_EXPORTS

WASI = "wasi_snapshot_preview1"
MAGIC = b"\0asm"
"""A WebAssembly binary's first bytes (wasmtime would read anything else as the text format)."""
ALIGNMENT = 16
REQUIRED = {"memory": "Memory", "malloc": "Func", "free": "Func", "__indirect_function_table": "Table",
            **{name: "Func" for name in BATCH_EXPORTS}}
"""What kingen calls in every module besides the library's own functions, and the kind of each export."""
KINDS = {"Func": "a function", "Global": "a global", "Memory": "a memory", "Table": "a table"}


def aligned(size):
    """``size`` bytes rounded up to :data:`ALIGNMENT`."""
    return -(-size // ALIGNMENT) * ALIGNMENT


class Buffer:
    """A NumPy array handed to a module's function, copied into its memory before the call and,
    when ``output`` (and writable), back after it; ``[i]`` reads its element i (a ``double *``
    out-argument)."""

    def __init__(self, array, output=True):
        self.array, self.output = array, output and array.flags.writeable

    def __getitem__(self, index):
        return self.array.reshape(-1)[index]


class CffiStandIn:
    """Stands in for cffi where :class:`~kingen.hosts.c.loader.Library`'s methods ask it for
    arguments: ``from_buffer`` and ``new`` make :class:`Buffer` arguments for a module."""

    @staticmethod
    def from_buffer(ctype, array):
        return Buffer(array)

    @staticmethod
    def new(ctype):
        return Buffer(np.zeros(1))


class Module:
    """A module instantiated in its own wasmtime store: its exports (each of the kind kingen
    calls it as, else PluginDefect), its memory as NumPy bytes, blocks of it from its own malloc."""

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
        self.failures = (wasmtime.Trap, wasmtime.WasmtimeError)
        for name, kind in REQUIRED.items():
            self.export(name, kind, "kingen build --host wasm exports it")
        self.memory = self.exports["memory"]
        self._bytes, self._workspace = None, (0, 0)
        if "_initialize" in self.exports:
            self.export("_initialize", "Func")
            Call(self, "_initialize")()

    def export(self, name, kind, hint=None):
        """The export ``name``, of ``kind`` (a wasmtime class name); PluginDefect when it is missing or another kind."""
        if name not in self.exports:
            raise PluginDefect(f"the module does not export {name}" + (f" ({hint})" if hint else ""))
        found = self.exports[name]
        if type(found).__name__ != kind:
            raise PluginDefect(f"the module's export {name} is {KINDS.get(type(found).__name__, 'something else')}, "
                               f"not {KINDS[kind]}")
        return found

    def bytes(self):
        """The memory as uint8, as long as it was at the last :meth:`allocate`: it holds every
        block kingen allocated (the memory never moves or shrinks, so the view stays valid)."""
        return self._bytes

    def address(self, value, size, what):
        """An i32 ``value`` read unsigned as the address of ``size`` bytes inside the memory; PluginDefect if it is not."""
        address = int(value) & 0xFFFFFFFF
        if address == 0 or address + size > self.memory.data_len(self.store):
            raise PluginDefect(f"{what} is {address}, not the address of {size} bytes of the module's memory")
        return address

    def allocate(self, size):
        """The address of ``size`` bytes from the module's own malloc (kept for the module's life)."""
        try:
            value = self.exports["malloc"](self.store, size)
        except self.failures as error:
            raise PluginDefect(f"the module trapped in malloc: {trap_reason(error)}", check="crash") from None
        address = self.address(value, size, f"the module's malloc({size})")
        length = self.memory.data_len(self.store)
        if self._bytes is None or len(self._bytes) != length:
            self._bytes = np.ctypeslib.as_array(self.memory.data_ptr(self.store), shape=(length,))
        return address

    def workspace(self, size):
        """The address of a block of ``size`` bytes at least, from the module's malloc, reused by
        every call's arguments (freed and allocated again when a call needs more)."""
        address, held = self._workspace
        if size > held:
            if address:
                Call(self, "free")(address)
            self._workspace = (self.allocate(size), size)
        return self._workspace[0]

    def place(self, *arrays):
        """The addresses of ``arrays`` copied into one block from the module's malloc (kept for the module's life)."""
        sizes = [aligned(array.nbytes) for array in arrays]
        start = self.allocate(max(sum(sizes), ALIGNMENT))
        addresses = [start + sum(sizes[:index]) for index in range(len(arrays))]
        copy_in(self.bytes(), addresses, arrays)
        return addresses


    def table_index(self, name):
        """The function table's index of the exported function ``name`` (added to the table);
        PluginDefect when the table cannot grow."""
        try:
            return self.exports["__indirect_function_table"].grow(self.store, 1, self.exports[name])
        except self.failures as error:
            raise PluginDefect(f"the module's function table cannot take {name}: {trap_reason(error)}") from None


def copy_in(memory, addresses, arrays):
    """Each array's bytes written into ``memory`` (uint8) at its address."""
    for address, array in zip(addresses, arrays):
        memory[address:address + array.nbytes] = np.ascontiguousarray(array).view(np.uint8).reshape(-1)


def trap_reason(error):
    """What a trap says of its cause: wasmtime's last line ("wasm trap: ..."), without its backtrace."""
    lines = [line.strip() for line in str(error).splitlines() if line.strip()]
    return lines[-1] if lines else type(error).__name__


class Call:
    """An exported function called with :class:`Buffer` arguments laid out in the module's
    workspace (:meth:`Module.workspace`), integers passed as they are; a trap (or the module's
    exit through WASI, or a call its signature refuses) is a PluginDefect of the check ``crash``."""

    def __init__(self, module, name):
        self.module, self.name, self.function = module, name, module.exports[name]

    def __call__(self, *arguments):
        buffers, offsets, end = [], [], 0
        for argument in arguments:
            if isinstance(argument, Buffer):
                buffers.append(argument)
                offsets.append(end)
                end += aligned(argument.array.nbytes)
        start = self.module.workspace(end) if buffers else 0
        laid = [start + offset for offset in offsets]
        copy_in(self.module.bytes(), laid, [buffer.array for buffer in buffers])
        at = iter(laid)
        addresses = [next(at) if isinstance(argument, Buffer) else int(argument) for argument in arguments]
        try:
            returned = self.function(self.module.store, *addresses)
        except self.module.failures as error:
            raise PluginDefect(f"the module trapped in {self.name}: {trap_reason(error)}", check="crash") from None
        memory = self.module.bytes()
        for address, buffer in zip(laid, buffers):
            if buffer.output:
                buffer.array.reshape(-1)[...] = memory[address:address + buffer.array.nbytes].view(buffer.array.dtype)
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
    but WASI, or lacks a function of the header but the optional ones (or exports it as another kind)."""

    def __init__(self, library, routine, robot):
        path = Path(library).resolve()
        refuse_special_file(path)
        if not path.is_file():
            raise KingenError(f"{path}: no such module")
        self.module = Module(path)
        self.ffi = CffiStandIn()
        self.functions, self.indices = {}, {}
        for name in entry_points(robot):
            symbol = f"{routine}_{name}"
            if name in OPTIONAL_ENTRY_POINTS and symbol not in self.module.exports:
                continue
            if name == "default_geometry":
                value = self.module.export(symbol, "Global").value(self.module.store)
                self.geometry = self.module.address(value, 1, f"{symbol} (the geometry's address)")
            else:
                self.module.export(symbol, "Func")
                self.functions[name] = Call(self.module, symbol)
                self.indices[name] = self.module.table_index(symbol)
        self.routine, self.robot = routine, robot
        self.dof, self.postures = robot.joint_count, robot.postures
        self.driver = Driver(self.module)

    def _pointer(self, ctype, array):
        return Buffer(array, output=not ctype.startswith("const"))

    def _function(self, name):
        return self.indices[name]

    def _geometry(self):
        return self.geometry

    def batch_runner(self, t6):
        """The C host's batch runner (strides 0: every call writes the same joints and warnings)
        with its buffers laid out in the module's memory once: a run is the batch driver's call alone."""
        poses = poses_of(t6)
        count = len(poses)
        buffers = self.module.place(poses, np.empty(self.dof * self.postures), np.empty(self.postures, dtype=np.intc),
                                    np.empty(count, dtype=np.intc))
        inverse_batch, function, geometry = self.driver.kingen_c_inverse_batch, self._function("inverse"), self.geometry
        at_poses, at_joints, at_warnings, at_returns = buffers

        def run():
            inverse_batch(function, geometry, count, at_poses, at_joints, 0, at_warnings, 0, at_returns)
            return poses

        return run
