"""kingen inside pytest: robot files become test files, their checks test items.

Installing kingen registers this plugin (entry point ``pytest11``). ``pytest --kingen DIR``
(or the ini option ``kingen_robots = DIR``) collects every robot YAML in DIR; each gives the
items ``build``, ``interface``, ``values``, ``warnings``, ``closure``, ``jacobian``, one
``golden[i]`` per golden value and ``snapshot`` when ``<robot>.golden.json`` lies beside
it, so ``-k "tau and golden"`` selects them. Each file is built and verified once per
process (in a child process, as ``kingen verify`` does); a failing item shows its checks'
details and diagnoses, and points at the robot file's line. ``--kingen-samples N`` sets the
poses (default 2000), ``--kingen-host NAME`` the host (default delmia). Works with
pytest-xdist and ``--junitxml``.
"""

import atexit
import shutil
import tempfile
from pathlib import Path

import pytest

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


def pytest_addoption(parser):
    group = parser.getgroup("kingen", "kingen robot definitions as tests")
    group.addoption("--kingen", action="append", default=[], metavar="DIR",
                    help="collect every robot YAML in DIR as kingen tests (repeatable)")
    group.addoption("--kingen-samples", type=int, default=None, metavar="N",
                    help=f"poses each robot is verified on (default {DEFAULT_SAMPLES})")
    group.addoption("--kingen-host", default="delmia", metavar="NAME",
                    help="the host each robot is built for and verified against (default delmia)")
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


def _within(path, folder):
    try:
        path.resolve().relative_to(folder.resolve())
        return True
    except (ValueError, OSError):
        return False


def pytest_collect_file(file_path, parent):
    if file_path.suffix in ROBOT_SUFFIXES and any(_within(file_path, folder) for folder in _folders(parent.config)):
        return RobotFile.from_parent(parent, path=file_path)
    return None


class RobotFile(pytest.File):
    """A robot YAML: built and verified once, on first use, by any of its items."""

    def collect(self):
        from .errors import KingenError
        from .model import load_robot
        from .snapshot import snapshot_path

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
        if snapshot_path(self.path).is_file():
            yield KingenItem.from_parent(self, name="snapshot", line=1)

    def outcome(self):
        """(report, problem): the verification of this file, run once per process."""
        if not hasattr(self, "_outcome"):
            self._outcome = self._verify()
        return self._outcome

    def _verify(self):
        from .errors import KingenError
        from .snapshot import load, snapshot_path
        from .verify import VerifyOptions, verify_library

        samples = self.config.getoption("kingen_samples") or DEFAULT_SAMPLES
        try:
            host = _host(self.config)
            snapshot = load(snapshot_path(self.path), self.robot) if snapshot_path(self.path).is_file() else None
            result = host.build(self.robot, _build_folder() / self.robot.name)
            report = verify_library(self.robot, result.library, result.routine,
                                    VerifyOptions(samples=samples, snapshot=snapshot, processes=None), host=host)
        except KingenError as error:
            return None, str(error)
        return report, None


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
        report, problem = self.parent.outcome()
        if problem is not None:
            raise KingenFailure(("the build failed: " if self.name == "build" else "not verified: ") + problem)
        names = item_checks(_host(self.config)).get(self.name, (self.name,))
        checks = [check for check in report.checks if check.name in names]
        if self.name not in ITEMS and not checks:
            raise KingenFailure(f"no check {self.name} in the report")
        failed = [check for check in checks if not check.passed]
        if failed:
            from .report import statistics_lines

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


_folder = None


def _build_folder():
    """A build folder for this process (pytest-xdist workers build side by side)."""
    global _folder
    if _folder is None:
        _folder = Path(tempfile.mkdtemp(prefix="kingen-pytest-"))
        atexit.register(shutil.rmtree, _folder, True)
    return _folder
