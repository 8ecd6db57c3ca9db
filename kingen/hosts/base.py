"""What a host is: the one small interface between the host-neutral core (model, limb models,
reference, verify) and a program that runs a generated routine (DELMIA, a controller, ...).

A host renders and builds a routine for a robot, builds a hand-written source, loads a
compiled routine (generated or hand-written) as a :class:`LoadedRoutine` whose ``call``
answers a batch of T6 with :class:`kingen.kinematics.routine.Calls` in kingen's units, names the verify
checks it runs, and writes a package. Hosts are registered in :mod:`kingen.hosts`; nothing
outside a host's own package names its files, symbols or checks (docs/developer/architecture.md).
"""

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar, Optional, Protocol

from ..defaults import DEFAULT_TIMEOUT
from ..errors import KingenError
from ..runtime.files import default_out_dir


@dataclass(frozen=True)
class BuildResult:
    """Paths of a built routine; ``compiled`` is False when the build was already up to date."""

    source: Path
    library: Path
    routine: str
    compiled: bool


class Written(list):
    """The paths a package wrote, and ``notices``: lines for the user about what it left
    undone (a module not built, say), each whole on its own."""

    def __init__(self, paths=(), notices=()):
        super().__init__(paths)
        self.notices = list(notices)


class LoadedRoutine(Protocol):
    """A compiled routine loaded into this process, as its host would load it.

    ``checks`` is the ordered tuple of :class:`kingen.verify.checks.VerifyCheck` that
    verify runs on it: the shared ones and the host's own, in report order."""

    routine: str
    dof: int
    postures: int
    checks: tuple
    warning_vocabulary: tuple
    """Optional: the warnings the routine can tell apart (all of kingen's when absent); the
    reference's others read as WARN_GOOD_SOLUTION when it is judged."""
    pose_coordinates: object
    """Optional: (6,) bool, the pose coordinates x y z roll pitch yaw the routine's answer
    depends on (all six when absent; a translating platform's controller ignores rotations)."""

    def reset_host(self):
        """Put the host's state back as before the first call (before every batch)."""

    def call(self, t6, link_lengths=None, link_offsets=None):
        """The routine on every T6 ((n, 4, 4), mm) with the calibration fields: a Calls."""


class Host:
    """A host: subclass, set the class attributes, implement the methods, and register an
    instance with :func:`kingen.hosts.register`. Work in methods imports lazily, so that
    registering a host (which the robot-file reader does to ask ``name_problem``) stays cheap."""

    name: ClassVar[str]
    """``--host NAME``."""
    description: ClassVar[str] = ""
    targets: ClassVar[tuple] = ()
    """What ``--target`` may name for this host (empty: the option does not apply)."""
    default_targets: ClassVar[dict] = {}
    """``--target`` when not given, per command ('build', 'package')."""
    per_call: ClassVar[str] = "cffi"
    """What calls the routine once per call from Python (``kingen bench``'s per-call line)."""
    loading_stage: ClassVar[str] = "loading the routine"
    """The stage a crash or hang while loading foreign code is reported in."""
    checks: tuple = ()
    """The verify checks of this host's routines, in report order (a loaded routine's
    ``checks``): those needing the library file run before it is loaded."""

    def configured(self, **settings):
        """This host with the command line's host settings (``units``, ``setp``); a host that
        takes none refuses any that is given."""
        given = [name for name, value in settings.items() if value]
        if given:
            raise KingenError(f"--{given[0]}: host {self.name} takes no such setting")
        return self

    def name_problem(self, robot_name) -> Optional[str]:
        """Why ``robot_name`` cannot name a routine for this host (a C name it would clash
        with), or None. Checked when a robot file is read, for every registered host."""
        return None

    def describe_faults(self, bits) -> str:
        """What a call's fault bits (Calls.faults) say it did, as a phrase after "the routine"."""
        return f"faulted (bits {bits})"

    def out_dir(self, robot) -> Path:
        """Where ``build`` writes by default."""
        return default_out_dir(robot)

    def render(self, robot) -> dict:
        """The routine's source files as {file name: text}: pure, nothing written."""
        raise NotImplementedError

    def write_source(self, robot, out_dir) -> Path:
        """Render ``robot`` into ``out_dir``; the main source's path."""
        raise NotImplementedError

    def build(self, robot, out_dir=None, *, target=None, defines=(), timeout=DEFAULT_TIMEOUT) -> BuildResult:
        """Render and compile ``robot`` (skipped when up to date)."""
        raise NotImplementedError

    def build_source(self, source, out_dir, *, timeout=DEFAULT_TIMEOUT) -> Path:
        """Compile a hand-written source for this host; the library's path."""
        raise NotImplementedError

    def load(self, library, routine, robot) -> LoadedRoutine:
        """Load ``routine`` of ``library`` for ``robot`` (as :meth:`as_seen` gives it) in this
        process (runs the library's constructors: callers do it in a child process,
        :mod:`kingen.runtime.isolation`)."""
        raise NotImplementedError

    def prepare_load(self):
        """Build in kingen's cache what :meth:`load` needs besides the library (a host
        emulator, a driver), in kingen's own process: load runs in a sandbox that can
        neither write the cache nor run a compiler (kingen.runtime.sandbox). Nothing by default."""

    def as_seen(self, robot):
        """``robot`` as this host's routines answer it (every posture by default; a host with
        one answer gives :func:`kingen.robot.one_posture.at_posture`). What verify compares with."""
        return robot

    def routine_name(self, robot) -> str:
        """The routine kingen generates for ``robot``."""
        raise NotImplementedError

    def library_name(self, robot) -> str:
        """The name the host is given for the compiled routine's library, without a file
        suffix; the routine's name by default."""
        return self.routine_name(robot)

    def calibration_label(self, field) -> str:
        """What this host calls a calibration field (``length1`` .. ``offset6``,
        :data:`kingen.robot.schema.CALIBRATION_FIELDS`) where its sheets and sources name
        it; the robot file's spelling by default."""
        return field

    def package(self, robot, out_dir, *, target=None, timeout=DEFAULT_TIMEOUT) -> list:
        """Write the package folder whole or not at all; the written paths (a :class:`Written`
        when there is something to tell the user, such as a part left unbuilt)."""
        raise NotImplementedError

    def package_dir(self, robot, target) -> Path:
        """Where ``package`` writes by default."""
        return default_out_dir(robot) / f"package-{target}" if target else default_out_dir(robot) / "package"
