"""kingen inside pytest: robot files become test files, their checks test items.

Installing kingen registers this plugin (entry point ``pytest11``). ``pytest --kingen DIR``
(or the ini option ``kingen_robots = DIR``) collects every robot YAML in DIR; each gives the
items ``build``, ``interface``, ``values``, ``warnings``, ``closure``, ``jacobian``, one
``golden[i]`` per golden value and ``snapshot`` when ``<robot>.golden.json`` lies beside
it, so ``-k "tau and golden"`` selects them. Each file is built and verified once per
process (in a child process, as ``kingen verify`` does); a failing item shows its checks'
details and diagnoses, and points at the robot file's line. ``--kingen-samples N`` sets the
poses (default 2000; below 1 is a usage error), ``--kingen-host NAME`` the host (default
delmia). A robot file reached twice (through a symlink, a symlink loop) is collected once,
under the first path found; a robot file that cannot be read (a dangling symlink) or is not
a regular file (a FIFO, a symlink to a device) is a failing ``build`` item. A snapshot
verify refuses (one it cannot read included: a FIFO, a device, a dangling symlink) fails
the ``snapshot`` item alone: the other items are verified without it. Works with
pytest-xdist (under ``-n N`` a robot file's items go to one worker, so each robot is
verified once) and ``--junitxml``.
"""

import argparse
import gc
import os
from pathlib import Path

import pytest

from .defaults import DEFAULT_HOST

ROBOT_SUFFIXES = (".yaml", ".yml")
ITEMS = ("build", "interface", "values", "warnings", "closure", "jacobian")
"""The items every robot file gives (golden[i] and snapshot report their own checks)."""
ALWAYS_INTERFACE = ("load", "crash", "timeout")
"""What the ``interface`` item reports besides the host's checks whose ``item`` says so."""
DEFAULT_SAMPLES = 2000


def item_checks(host):
    """Which verify checks each item reports, from ``host``'s checks (their ``item``)."""
    items = {name: [] for name in ITEMS}
    items["interface"].append("load")
    for check in host.checks:
        if check.item in items:
            items[check.item].append(check.name)
    items["interface"].extend(ALWAYS_INTERFACE[1:])
    return {name: tuple(checks) for name, checks in items.items()}


def sample_count(text):
    """``--kingen-samples``'s value: a whole number of poses, at least 1; else
    argparse.ArgumentTypeError (pytest makes it a usage error)."""
    try:
        count = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of poses") from None
    if count < 1:
        raise argparse.ArgumentTypeError(f"{count} poses: give at least 1")
    return count


def pytest_addoption(parser):
    group = parser.getgroup("kingen", "kingen robot definitions as tests")
    group.addoption("--kingen", action="append", default=[], metavar="DIR",
                    help="collect every robot YAML in DIR as kingen tests (repeatable)")
    group.addoption("--kingen-samples", type=sample_count, default=None, metavar="N",
                    help=f"poses each robot is verified on (default {DEFAULT_SAMPLES})")
    group.addoption("--kingen-host", default=DEFAULT_HOST, metavar="NAME",
                    help=f"the host each robot is built for and verified against (default {DEFAULT_HOST})")
    parser.addini("kingen_robots", "folders whose robot YAML files are collected as kingen tests", type="paths")


def _folders(config):
    folders = [Path(folder) for folder in config.getoption("kingen")]
    folders += [Path(folder) for folder in config.getini("kingen_robots")]
    return [folder.resolve() for folder in folders]


def pytest_configure(config):
    for folder in _folders(config):
        if not folder.is_dir():
            raise pytest.UsageError(f"--kingen / kingen_robots: {folder} is not a folder")
        if str(folder) not in config.args and not any(_within(folder, Path(arg)) for arg in config.args):
            config.args.append(str(folder))


def pytest_collection_finish(session):
    """With robot folders collected: gc.freeze() what the session holds by now (the modules
    it imported, its collected items; kept to its end anyway), so that the garbage collector
    no longer scans it. pytest's five collections at the session's end (its unraisable-
    exception check) took 0.2 s of a warm run of the shipped robots before."""
    if _folders(session.config):
        gc.freeze()


def _within(path, folder):
    try:
        path.resolve().relative_to(folder.resolve())
        return True
    except (ValueError, OSError):
        return False


_COLLECTED = pytest.StashKey[set]()


def _first_time(config, path):
    """True the first time this session meets the file at real path ``path`` (however reached)."""
    seen = config.stash.setdefault(_COLLECTED, set())
    real = os.path.realpath(path)
    if real in seen:
        return False
    seen.add(real)
    return True


def _is_robot_file(path, config):
    """Whether ``path`` names a robot YAML lying in a kingen folder (a symlink by where it
    lies, wherever it points)."""
    location = Path(os.path.realpath(path.parent)) / path.name
    return path.suffix in ROBOT_SUFFIXES and any(location.is_relative_to(folder) for folder in _folders(config))


def pytest_collect_file(file_path, parent):
    """A RobotFile for a robot YAML in a kingen folder, unless this session already
    collected the file it is (by real path)."""
    if _is_robot_file(file_path, parent.config) and _first_time(parent.config, file_path):
        return RobotFile.from_parent(parent, path=file_path)
    return None


@pytest.hookimpl(wrapper=True)
def pytest_make_collect_report(collector):
    """A folder's collection also gives its robot files that pytest passes over because they
    are neither a regular file nor a folder (dangling symlinks, FIFOs, sockets, devices and
    symlinks to them): each is a RobotFile whose ``build`` item fails, never a silent skip."""
    report = yield
    if (isinstance(collector, pytest.Directory) and report.passed
            and any(_within(collector.path, folder) for folder in _folders(collector.config))):
        for entry in sorted(os.scandir(collector.path), key=lambda entry: entry.name):
            path = Path(entry.path)
            if (_passed_over(entry) and _is_robot_file(path, collector.config)
                    and _first_time(collector.config, path)):
                report.result.append(RobotFile.from_parent(collector, path=path))
    return report


def _passed_over(entry):
    """Whether pytest's folder collection passes over the folder entry ``entry``: it collects
    only what is (through symlinks) a folder or a regular file."""
    try:
        return not entry.is_dir() and not entry.is_file()
    except OSError:
        return True


def robot_scope(nodeid):
    """The work unit of an item under pytest-xdist: a robot file's items share one, the file
    (``robots/tau.yaml``), so one worker verifies each robot once; any other item is its own."""
    path = nodeid.split("::", 1)[0]
    return path if path != nodeid and path.endswith(ROBOT_SUFFIXES) else nodeid


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """Under pytest-xdist's default distribution (``-n N`` alone, ``--dist load``) with kingen
    folders collected: xdist's scope scheduling with robot_scope's units, decided in the
    controlling process alone (workers need nothing). Otherwise None: xdist's own choice."""
    if config.getvalue("dist") != "load" or not _folders(config):
        return None
    from xdist.scheduler import LoadScopeScheduling

    class RobotScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid):
            return robot_scope(nodeid)

    return RobotScheduling(config, log)


class RobotFile(pytest.File):
    """A robot YAML: built and verified once, on first use, by any of its items."""

    def collect(self):
        from .errors import KingenError, located
        from .robot.model import load_robot
        from .verify.snapshot import snapshot_path

        if not self.path.exists():
            problem = located(self.path, None, None, f"the symlink's target {os.readlink(self.path)} does not exist"
                              if self.path.is_symlink() else "does not exist")
            yield KingenItem.from_parent(self, name="build", problem=str(problem))
            return
        try:
            robot = load_robot(self.path)
        except KingenError as error:
            yield KingenItem.from_parent(self, name="build", problem=str(error))
            return
        self.robot = robot
        for name in ITEMS:
            yield KingenItem.from_parent(self, name=name, line=robot.line_of("name"))
        for index in range(len(robot.golden)):
            yield KingenItem.from_parent(self, name=f"golden[{index}]", line=robot.line_of("golden", index))
        if os.path.lexists(snapshot_path(self.path)):
            yield KingenItem.from_parent(self, name="snapshot", line=1)

    def outcome(self):
        """(report, problem, snapshot problem): the verification of this file, run once per
        process whatever its end (an exception is raised again to every item asking)."""
        if not hasattr(self, "_outcome"):
            try:
                self._outcome = self._verify()
            except Exception as error:
                self._outcome = error
        if isinstance(self._outcome, Exception):
            raise self._outcome
        return self._outcome

    def _verify(self):
        from .errors import KingenError
        from .verify.snapshot import load, snapshot_path
        from .verify import VerifyOptions, verify_library

        samples = self.config.getoption("kingen_samples")
        samples = DEFAULT_SAMPLES if samples is None else samples
        snapshot, snapshot_problem = None, None
        if os.path.lexists(snapshot_path(self.path)):
            try:
                snapshot = load(snapshot_path(self.path), self.robot)
            except KingenError as error:
                snapshot_problem = str(error)
        try:
            host = _host(self.config)
            result = host.build(self.robot, _build_folder(host, self.robot))
            report = verify_library(self.robot, result.library, result.routine,
                                    VerifyOptions(samples=samples, snapshot=snapshot, processes=_processes()),
                                    host=host)
        except KingenError as error:
            return None, str(error), snapshot_problem
        return report, None, snapshot_problem


class KingenFailure(Exception):
    """A kingen check that failed: its text is the report."""


class KingenItem(pytest.Item):
    def __init__(self, *, problem=None, line=1, **kwargs):
        super().__init__(**kwargs)
        self.problem = problem
        self.line = line

    def runtest(self):
        if self.problem is not None:
            raise KingenFailure(self.problem)
        report, problem, snapshot_problem = self.parent.outcome()
        if self.name == "snapshot" and snapshot_problem is not None:
            raise KingenFailure(snapshot_problem)
        if problem is not None:
            raise KingenFailure(("the build failed: " if self.name == "build" else "not verified: ") + problem)
        names = item_checks(_host(self.config)).get(self.name, (self.name,))
        checks = [check for check in report.checks if check.name in names]
        if self.name not in ITEMS and not checks:
            raise KingenFailure(f"no check {self.name} in the report")
        failed = [check for check in checks if not check.passed]
        if failed:
            from .verify.report import statistics_lines

            lines = []
            for check in failed:
                lines.append(f"{check.name}: {check.detail}")
                lines.extend(f"  diagnosis: {text}" for text in check.diagnoses)
            if self.name in ("values", "warnings"):
                lines.extend(statistics_lines(report))
            raise KingenFailure("\n".join(lines))

    def repr_failure(self, excinfo):
        if isinstance(excinfo.value, KingenFailure):
            return f"{self.path}:{self.line}: {self.name}\n{excinfo.value}"
        return super().repr_failure(excinfo)

    def reportinfo(self):
        return self.path, self.line - 1, self.name


def _host(config):
    from .hosts import get_host

    return get_host(config.getoption("kingen_host"))


def _processes():
    """Comparing processes per verification: one in a pytest-xdist worker (the workers
    already share the cores), else verify's default (one per usable core)."""
    return 1 if os.environ.get("PYTEST_XDIST_WORKER") else None


def _build_folder(host, robot):
    """Where a robot is built: a folder of kingen's cache named by the host, kingen's version
    and the robot file's content, so that a later session (or another xdist worker) finds the
    build done; the build inside it is content-addressed too (a stamp of the source, compiler
    and flags), so nothing stale is ever used."""
    from .defaults import VERSION
    from .runtime.files import cache_dir, digest, private_folder

    root = cache_dir() / "pytest-builds"
    for folder in (cache_dir(), root):
        private_folder(folder)
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
    return root / f"{robot.name}-{digest(VERSION, host.name, robot.sha256)[:16]}"
