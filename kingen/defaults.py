"""Defaults and bounds the command line needs before it loads anything heavy.

Imports nothing, so that ``kingen --help`` and ``kingen --version`` start without numpy,
pydantic or jinja2; the library modules take these values from here too.
"""

MAX_MM = 1e6
"""Coordinates and lengths are within +/- 1 km (mm): the stated geometry range, inside which
double precision keeps plugin and reference within verify's bound (see verify.value_tolerance_mm)."""
DEFAULT_TIMEOUT = 300.0
"""Seconds a compiler run may take (``--timeout``, ``$KINGEN_TIMEOUT``) before it is killed."""
DEFAULT_HOST = "delmia"
"""The host a command builds for without ``--host``, and :func:`kingen.hosts.get_host`'s."""
TARGETS = ("linux", "windows")
"""What ``build --target`` and ``package --target`` can produce."""
MAX_PROCESSES = 16
"""verify's comparing processes at most (``--processes``; by default one per core up to this):
each holds about 100 MB of chunk arrays."""
TILT_STEP_DEG = (0.001, 90.0)
"""(least, most) tilt step in degrees: analyze's ``--tilt-step`` and an ``optimize:``
section's ``objective.tilt_step``."""
AZIMUTH_STEP_DEG = (0.5, 180.0)
"""(least, most) step between tilt azimuths in degrees: ``--azimuth-step`` and ``objective.azimuth_step``."""
TILT_MAX_DEG = (0.1, 180.0)
"""(least, most) largest tilt tried in degrees: ``--tilt-max`` and ``objective.tilt_max``."""
CALIBRATION_NOISE = {"device_mm": 0.01, "device_deg": 0.001, "joint_mm": 0.001, "joint_deg": 0.0001}
"""calibrate's stated noise without options, one standard deviation per coordinate: the device's
positions (mm) and angles (degrees), the joints read (mm, degrees): ``--noise-mm``, ``--noise-deg``,
``--noise-joint-mm``, ``--noise-joint-deg`` (kingen.calibrate.noise.Noise)."""
VERSION = "0.1.0"
"""kingen's version (``kingen.__version__``), written into generated files and snapshots."""
LOAD_RATE_MAX = 1e9
"""kingen loads: |velocity| and |acceleration| components at most (mm, degrees per s or s^2)."""
LOAD_WRENCH_MAX = 1e12
"""kingen loads: |wrench| components at most (N, N m)."""
INTERPRETER_SECONDS = 60.0
"""check-path: CPU seconds each of LinuxCNC's interpreters (the gcode module's child, rs274) may take."""
MAX_SAMPLES = 100_000_000
"""check-path: regular samples a program may ask for at its chord (five to fifteen minutes of checking on one core)."""
