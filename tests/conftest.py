"""Shared fixtures: shipped robots, plugins built once per test session."""

import compileall
import contextlib
import dataclasses
import importlib.util
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import settings

settings.register_profile("ci", derandomize=True, database=None)
if os.environ.get("CI"):
    settings.load_profile("ci")  # the same examples on every CI run: a red CI is reproducible

# solve and verify fit $COLUMNS: tests that parse the full lines set none. GNU readline (which
# pytest's pdb support may load) exports the terminal's COLUMNS into the C environment, which
# child processes inherit though os.environ does not show it: load it first, then unset.
with contextlib.suppress(ImportError):
    import readline  # noqa: F401
os.environ.pop("COLUMNS", None)
os.unsetenv("COLUMNS")
os.environ.setdefault("KINGEN_CACHE", tempfile.mkdtemp(prefix="kingen-test-cache-"))

# Tests start kingen in new Python processes (`python -m kingen.cli` 49 times in one run, pytest
# sessions). Where Python is told not to write bytecode (PYTHONDONTWRITEBYTECODE,
# as in CI containers) and kingen is installed editable, each compiled every kingen module
# afresh (0.13 s of a 0.9 s `kingen verify`, median of paired runs); byte-compiled once here,
# they load it. Up-to-date files are skipped; a read-only tree is left as it is.
if not os.environ.get("PYTEST_XDIST_WORKER"):
    compileall.compile_dir(Path(importlib.util.find_spec("kingen").origin).parent, quiet=2)

from kingen.hosts.delmia.build import build_plugin  # noqa: E402
from kingen.conventions import t6_from_pose  # noqa: E402
from kingen.hosts.delmia.loader import Plugin  # noqa: E402
from kingen.robot.model import load_robot, shipped_robots  # noqa: E402

SHIPPED = shipped_robots()


@pytest.fixture(scope="session")
def build_root(tmp_path_factory):
    """Where ``built`` compiles: one folder for the whole run, which pytest-xdist's workers
    share (each build is stamped and written atomically, so a worker reuses another's
    library instead of compiling it again)."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = tmp_path_factory.getbasetemp().parent / "plugins"
        root.mkdir(exist_ok=True)
        return root
    return tmp_path_factory.mktemp("plugins")


@pytest.fixture(scope="session")
def built(build_root):
    """built(name) -> (robot, BuildResult), compiled once per session."""
    cache = {}

    def get(name):
        if name not in cache:
            robot = load_robot(name)
            cache[name] = (robot, build_plugin(robot, build_root / name))
        return cache[name]

    return get


@pytest.fixture(scope="session")
def plugin(built):
    """plugin(name) -> (robot, Plugin) loaded through the host emulator."""
    cache = {}

    def get(name):
        if name not in cache:
            robot, result = built(name)
            cache[name] = (robot, Plugin(result.library, result.routine))
        return cache[name]

    return get


PLUMB_LEG = """\
name: plumb_leg
description: One leg from the base origin to the platform origin, its joint the absolute length.
limbs:
  - {model: leg, base_point: [0, 0, 0], platform_point: [0, 0, 0], reference_length: 0, travel: [100, 200]}
verification: {home: [0, 0, 150, 0, 0, 0], range: [10, 10, 10, 0, 0, 0]}
"""
"""Its joint at pose (0, 0, z) is z: the travel limits 100 and 200 mm are met at z = 100, 200."""


ONE_RAIL = """\
name: one_rail
description: One rail along -z through the origin, link 100 mm to the platform origin.
limbs:
  - {model: rail, rail_point: [0, 0, 0], direction: [0, 0, -1], carriage_offset: [0, 0, 0],
     platform_point: [0, 0, 0], link_length: 100}
verification: {home: [50, 0, -50, 0, 0, 0], range: [10, 10, 10, 0, 0, 0]}
"""
"""At (x, 0, z), |x| < 100, its two carriage positions are -z -/+ sqrt(100^2 - x^2) (u = -z):
two postures, both reachable; beyond x = 100 neither is."""


THREE_LEGS = ("name: legs\ndescription: Three legs, no forward coordinates.\nlimbs:\n"
              + "".join(f"  - {{model: leg, base_point: [{x}, {y}, 0], platform_point: [0, 0, 0], "
                        f"reference_length: 100}}\n" for x, y in ((100, 0), (-50, 87), (-50, -87)))
              + "verification: {home: [0, 0, 120, 0, 0, 0], range: [10, 10, 10, 0, 0, 0]}\n")
"""Three legs meeting at the platform origin and no free coordinates: no forward kinematics."""


class ChangedCalls:
    """A loaded plugin whose outputs ``change(t6 (n, 4, 4), calls)`` alters in place after
    each call (its solutions, warnings, faults): a routine that is wrong in a chosen way.
    The host's summary by limb branch (Calls.repeats) is left out: it describes the calls
    before the change (test_verify_columns.py holds it to the comparison without it)."""

    def __init__(self, plugin, change):
        self._plugin, self._change = plugin, change

    def __getattr__(self, name):
        return getattr(self._plugin, name)

    def call(self, t6, *arguments, **keywords):
        calls = self._plugin.call(t6, *arguments, **keywords)
        calls = dataclasses.replace(calls, solutions=calls.solutions.copy(), branch_values=None, repeats=None)
        self._change(np.asarray(t6).reshape(-1, 4, 4), calls)
        return calls


def refusal_of(source, folder, old, new):
    """(path, message): robot file ``source`` written to ``folder``/bad.yaml with its text ``old``
    (which must be there) replaced once by ``new``, and the KingenError loading it raises."""
    from kingen.errors import KingenError

    text = Path(source).read_text()
    assert old in text
    path = Path(folder) / "bad.yaml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(KingenError) as refused:
        load_robot(path)
    return path, str(refused.value)


class ReferenceRoutine:
    """The numpy reference as a routine (kingen.kinematics.routine.Calls), its joints changed by
    ``change(t6, joints)`` (in place) after each call when given: a routine right, or wrong in a
    chosen way, without a compiler."""

    def __init__(self, robot, change=None):
        self.robot, self.change = robot, change

    def reset_host(self):
        pass

    def call(self, t6, link_lengths=None, link_offsets=None):
        from kingen.kinematics.reference import solve
        from kingen.kinematics.routine import WARNINGS, Calls

        expected = solve(self.robot, t6, link_lengths, link_offsets)
        joints = expected.joints.copy()
        if self.change:
            self.change(np.asarray(t6), joints)
        unreachable = np.all(expected.warnings == WARNINGS["WARN_UNREACHABLE"], axis=1)
        return Calls(returned=np.where(unreachable, 1, 0).astype(np.intc), solutions=joints,
                     warnings=expected.warnings.astype(np.intc), faults=np.zeros(len(joints), dtype=np.intc))


class ChangedJoints(ChangedCalls):
    """A loaded plugin whose joints ``change(t6 (n, 4, 4), solutions (n, dof, postures))``
    alters in place after each call: a routine that rounds differently, or is wrong."""

    def __init__(self, plugin, change):
        super().__init__(plugin, lambda t6, calls: change(t6, calls.solutions))


def random_t6(robot, count, seed):
    """T6 arrays for ``count`` seeded poses in the robot's verification region."""
    rng = np.random.default_rng(seed)
    region = robot.verification
    poses = np.asarray(region.home) + rng.uniform(-1, 1, (count, 6)) * np.asarray(region.range)
    return poses, t6_from_pose(poses)


def skip_or_fail(message):
    """Skip a test whose requirement (a tool, a package's files, root) is missing, saying
    ``message``; under KINGEN_REQUIRE_TOOLCHAINS=1 (set by .ci/run) fail instead: a skipped
    matrix is not green."""
    if os.environ.get("KINGEN_REQUIRE_TOOLCHAINS") == "1":
        pytest.fail(message + "; KINGEN_REQUIRE_TOOLCHAINS=1 makes a missing requirement a failure")
    pytest.skip(message)


def require_tool(tool, package):
    """skip_or_fail when ``tool`` is missing, saying what installs it."""
    if shutil.which(tool) is None:
        skip_or_fail(f"{tool} is not installed (Debian package {package}; .ci/run installs it)")


def require_file(path, package):
    """As require_tool, for a file a package installs (LinuxCNC's stock modules)."""
    if not Path(path).is_file():
        skip_or_fail(f"{path} is not installed (Debian package {package}; .ci/run installs it)")


def require_linuxcnc_headers():
    """skip_or_fail unless kingen finds LinuxCNC's headers where it builds modules from
    (kingen.hosts.linuxcnc.build.linuxcnc_headers: $KINGEN_LINUXCNC_INCLUDE or Debian's folder)."""
    from kingen.errors import KingenError
    from kingen.hosts.linuxcnc.build import linuxcnc_headers

    try:
        linuxcnc_headers()
    except KingenError as error:
        skip_or_fail(f"{error} (.ci/run installs it)")


class _ExitZero:
    """Unpickling this ends the unpickling process with exit status 0."""

    def __reduce__(self):
        return (os._exit, (0,))


def forging_constructor(frame):
    """C: a library constructor that writes ``frame`` (bytes) into every file descriptor from
    3 up, as a plugin that looks for kingen's channel to its parent would."""
    data = ", ".join(str(byte) for byte in frame)
    return ("#include <unistd.h>\n"
            f"static const unsigned char forged[] = {{{data}}};\n"
            "__attribute__((constructor)) static void forge(void) {\n"
            "    for (int fd = 3; fd < 1024; fd++) (void)!write(fd, forged, sizeof forged);\n"
            "}\n")


def forged_frames():
    """What a plugin may write into kingen's channel, by name: a pickle frame as
    multiprocessing's pipes carry (unpickling it exits 0: a forged PASS), and a frame of
    kingen's own format with a passing report but a tag made without the channel's key."""
    import pickle
    import struct

    from kingen.runtime import wire

    data = pickle.dumps(("result", _ExitZero()))
    report = {"robot": "probe", "routine": "kin_probe", "samples": 200, "seed": 0, "postures": 1,
              "checks": [{"name": "values", "passed": True}]}
    return {"pickle": struct.pack("!i", len(data)) + data, "unkeyed": wire.encode(bytes(32), "result", report)}


FORGED = forged_frames()
