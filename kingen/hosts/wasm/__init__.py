"""The C library compiled to WebAssembly (``--host wasm``): the same generated, verified C
(:mod:`kingen.hosts.c`) built by clang for wasm32-wasi into a self-contained module, for a
browser (kingen's 3D view) or any WebAssembly runtime, with a dependency-free JavaScript glue
(``templates/kingen_wasm.js``). Built by :mod:`.build`."""
