"""Defaults and bounds the command line needs before it loads anything heavy.

Imports nothing, so that ``kingen --help`` and ``kingen --version`` start without numpy,
pydantic or jinja2; the library modules take these values from here too.
"""

MAX_MM = 1e6
"""Coordinates and lengths are within +/- 1 km (mm): the stated geometry range, inside which
double precision keeps plugin and reference within verify's bound (see verify.value_tolerance_mm)."""
DEFAULT_TIMEOUT = 300.0
"""Seconds a compiler run may take (``--timeout``, ``$KINGEN_TIMEOUT``) before it is killed."""
TARGETS = ("linux", "windows")
"""What ``build --target`` and ``package --target`` can produce."""
MAX_PROCESSES = 16
"""verify's comparing processes at most (``--processes``; by default one per core up to this):
each holds about 100 MB of chunk arrays."""
