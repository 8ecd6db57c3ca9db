"""DELMIA V5 / IGRIP, kingen's first host: a user-inverse-kinematics plugin (``kin_<name>.c``
built into ``lib<name>.so`` or ``.dll``), loaded through a host emulator exactly as DELMIA
loads it, verified with the interface checks of docs/explanation/delmia-abi.md, packaged with a setup
sheet for the Inverse Kinematics dialog.

Everything DELMIA's is in this package: the ABI (:mod:`.abi`), what its dialogs call things
(:mod:`.dialog`: the routine's and library's names, the calibration fields' labels, the joint
types), the templates (``templates/``), rendering (:mod:`.render`), building (:mod:`.build`),
loading (:mod:`.loader`), its checks (:mod:`.checks`) and its package (:mod:`.package`). The work is imported lazily, so that
registering the host costs nothing but :mod:`.abi` and :mod:`.dialog`.
"""

from ...defaults import DEFAULT_TIMEOUT, TARGETS
from ..base import Host
from . import abi, dialog


class DelmiaHost(Host):
    name = "delmia"
    description = "DELMIA V5 / IGRIP user-inverse-kinematics plugin"
    targets = TARGETS
    default_targets = {"build": "linux", "package": "windows"}
    loading_stage = "loading the plugin (its constructors and get_kin_config)"

    def name_problem(self, robot_name):
        """The robot's own name may be anything identifier-shaped ('int' gives kin_int); the C
        names made from it must not collide with a C keyword or a name the vendor header defines."""
        for made in (dialog.routine_name(robot_name), dialog.library_name(robot_name)):
            if made in abi.RESERVED_NAMES:
                return f"gives the C name '{made}', which the DELMIA header or the C language already uses"
        return None

    def describe_faults(self, bits):
        return "; ".join(text for bit, text in abi.GUARD_FAULTS.items() if bits & bit)

    @property
    def checks(self):
        from .checks import CHECKS

        return CHECKS

    def render(self, robot):
        from .render import render

        return render(robot)

    def write_source(self, robot, out_dir):
        from .build import write_source

        return write_source(robot, out_dir)

    def build(self, robot, out_dir=None, *, target=None, defines=(), timeout=DEFAULT_TIMEOUT):
        from .build import build_plugin

        return build_plugin(robot, out_dir, defines=defines, target=target or "linux", timeout=timeout)

    def build_source(self, source, out_dir, *, timeout=DEFAULT_TIMEOUT):
        from .build import build_legacy

        return build_legacy(source, out_dir, timeout=timeout)

    def prepare_load(self):
        from .build import host_support

        host_support()

    def load(self, library, routine, robot=None):
        from .loader import Plugin

        return Plugin(library, routine)

    def routine_name(self, robot):
        return dialog.routine_name(robot.name)

    def library_name(self, robot):
        return dialog.library_name(robot.name)

    def calibration_label(self, field):
        return dialog.field_label(field)

    def package(self, robot, out_dir, *, target=None, timeout=DEFAULT_TIMEOUT):
        from .package import write_package

        return write_package(robot, out_dir, target or "windows", timeout=timeout)
