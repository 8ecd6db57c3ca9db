"""A portable C99 library (``--host c``): ``kingen_<name>.h`` and ``kingen_<name>.c`` with the
inverse kinematics of every posture and of one, the forward kinematics (Newton's method from a
given pose, a bounded number of steps), the analytic Jacobian; the geometry a ``const`` struct
passed by pointer, so a controller can pass a calibrated copy. No allocation, no global mutable
state, no I/O, only ``<math.h>``: for a controller's own real-time loop. Verified through cffi
(:mod:`.loader`), packaged with CMake and pkg-config files (:mod:`.package`).
"""

import functools
import re

from ...defaults import DEFAULT_TIMEOUT
from ..base import Host


@functools.lru_cache(maxsize=1)
def shared_names():
    """The names the library's C uses besides its own (``kingen_...`` functions and tables,
    ``KINGEN_...`` macros: the shared routine helpers, the limb partials, the batch driver), read
    once from the templates that write them; a name ending in ``_`` is the start of names a
    template completes (``kingen_solve_<model>``)."""
    from pathlib import Path

    from ...runtime.resources import templates_dir

    files = [*templates_dir().rglob("*.c.j2"), *Path(__file__).with_name("templates").glob("*.c*")]
    return frozenset(name for path in files for name in re.findall(r"\b(?:kingen|KINGEN)_\w+", path.read_text()))


class CHost(Host):
    name = "c"
    description = "portable C99 library (header and source) for your own controller"
    loading_stage = "loading the library"

    @property
    def checks(self):
        from .checks import CHECKS

        return CHECKS

    def name_problem(self, robot_name):
        """The library's names are kingen_<name>_... and KINGEN_<NAME>_...: none may be the start
        of a name its C uses besides (``solve`` would make kingen_solve_leg, a helper's name)."""
        own = (f"kingen_{robot_name}_", f"KINGEN_{robot_name.upper()}_")
        taken = sorted(name for name in shared_names() if name.startswith(own))
        if taken:
            return (f"gives the C library's names the prefix '{own[0]}' or '{own[1]}', which the C library's own "
                    f"names start with ('{taken[0]}')")
        return None

    def out_dir(self, robot):
        from .build import default_dir

        return default_dir(robot)

    def render(self, robot):
        from .render import render

        return render(robot)

    def write_source(self, robot, out_dir):
        from .build import write_source

        return write_source(robot, out_dir)

    def build(self, robot, out_dir=None, *, target=None, defines=(), timeout=DEFAULT_TIMEOUT):
        from .build import build_library

        return build_library(robot, out_dir, timeout=timeout)

    def build_source(self, source, out_dir, *, timeout=DEFAULT_TIMEOUT):
        from .build import build_source

        return build_source(source, out_dir, timeout=timeout)

    def prepare_load(self):
        from .loader import batch_library

        batch_library()

    def load(self, library, routine, robot=None):
        from .loader import Library

        return Library(library, routine, robot)

    def routine_name(self, robot):
        from .render import prefix

        return prefix(robot)

    def package(self, robot, out_dir, *, target=None, timeout=DEFAULT_TIMEOUT):
        from .package import write_package

        return write_package(robot, out_dir, timeout=timeout)

    def package_dir(self, robot, target):
        from .build import default_dir

        return default_dir(robot) / "package"
