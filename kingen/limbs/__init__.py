"""Deprecated import path: the limb models and their registry are :mod:`kingen.robot.limbs`
(``kingen.limbs.register``, ``kingen.limbs.base.LimbModel`` and the rest keep working here,
with a DeprecationWarning, for code written against the old layout)."""

import sys
import warnings

from ..robot.limbs import *  # noqa: F401,F403  (the same names)
from ..robot.limbs import __all__  # noqa: F401
from ..robot.limbs import base, crank, leg, rail

for _module in (base, crank, leg, rail):
    sys.modules[f"{__name__}.{_module.__name__.rpartition('.')[2]}"] = _module

warnings.warn("kingen.limbs is now kingen.robot.limbs; import it from there", DeprecationWarning, stacklevel=2)
