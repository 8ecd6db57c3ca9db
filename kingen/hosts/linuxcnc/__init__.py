"""LinuxCNC, the open real-time CNC controller: a kinematics module (``<name>kins.c``, built
into ``<name>kins.so``, loaded by ``loadrt <name>kins``; the name cut where its pins' names
would pass HAL's 47 characters, :func:`.render.module_name`) whose inverse is kingen's closed form
at the robot's working posture and whose forward is Newton's method with the analytic
Jacobian; verified through a HAL stand-in (:mod:`.loader`) and packaged with ``.hal`` and
``.ini`` snippets and a setup sheet. linuxcnc.md in the project's shared notes has the facts.
"""

from dataclasses import replace

from ...defaults import DEFAULT_TIMEOUT
from ..base import Host


class LinuxcncHost(Host):
    name = "linuxcnc"
    description = "LinuxCNC kinematics module"
    loading_stage = "loading the module (rtapi_app_main)"

    def __init__(self, units=None, setp=()):
        self.units, self.setp = units, dict(setp)

    def configured(self, units=None, setp=()):
        """This host for a machine in ``units`` (LINEAR_UNITS 'mm' or 'inch'; default: the robot
        file's), its modules' pins and parameters set to ``setp`` ((name, value) pairs) when loaded."""
        return LinuxcncHost(units, setp)

    def machine_units(self, robot):
        """LINEAR_UNITS: the configured ones, else the robot file's ('mm' for a file in metres)."""
        return self.units or ("inch" if robot.length_unit == "inch" else "mm")

    @property
    def checks(self):
        from .checks import CHECKS

        return CHECKS

    def as_seen(self, robot):
        """The robot at its working posture; a translating platform without rotations (LinuxCNC's
        A B C pass through to other joints), so verify draws its poses without them; a machine
        with task coordinates whose x, y and yaw are not read (the module solves them)."""
        from ...robot.one_posture import at_posture
        from .render import check_robot, translating

        check_robot(robot)
        seen = at_posture(robot, robot.working_posture)
        if translating(robot):
            region = robot.verification
            still = region.model_copy(update={"home": [*region.home[:3], 0.0, 0.0, 0.0],
                                              "range": [*region.range[:3], 0.0, 0.0, 0.0]})
            seen = replace(seen, verification=still)
        if robot.task:  # the module reads the task coordinates only: x, y, C are the machine's
            seen = replace(seen, parasitic_given=False)
        return seen

    def out_dir(self, robot):
        from .build import default_dir

        return default_dir(robot)

    def render(self, robot):
        from .render import render

        return render(robot, self.machine_units(robot))

    def write_source(self, robot, out_dir):
        from .build import write_source

        return write_source(robot, out_dir, self.machine_units(robot))

    def build(self, robot, out_dir=None, *, target=None, defines=(), timeout=DEFAULT_TIMEOUT):
        from .build import build_module

        return build_module(robot, out_dir, self.machine_units(robot), timeout=timeout)

    def build_source(self, source, out_dir, *, timeout=DEFAULT_TIMEOUT):
        from .build import build_source

        return build_source(source, out_dir, timeout=timeout)

    def prepare_load(self):
        from .build import harness

        harness()

    def load(self, library, routine, robot=None):
        from .loader import Module

        return Module(library, routine, robot, self.setp, self.machine_units(robot) == "inch")

    def routine_name(self, robot):
        from .render import module_name

        return module_name(robot)

    def package(self, robot, out_dir, *, target=None, timeout=DEFAULT_TIMEOUT):
        from .package import write_package

        return write_package(robot, out_dir, self.machine_units(robot), timeout=timeout)

    def package_dir(self, robot, target):
        from .build import default_dir

        return default_dir(robot) / "package"
