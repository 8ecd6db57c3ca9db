"""verify's checks: one module each, one common shape (:mod:`kingen.verify.checks.base`).

``SHARED`` are the checks every host's routine gets, in report order; a host composes its
routine's ``checks`` tuple from them and its own (:mod:`kingen.hosts.delmia.checks`).
"""

from .base import NEEDS, PHASES, Check, Context, VerifyCheck, by_need
from .closure import Closure
from .definition import Definition
from .determinism import Determinism
from .golden import Golden
from .jacobian import Jacobian
from .machine import Machine
from .round_trip import RoundTrip
from .snapshot import Snapshot
from .values import Values
from .warnings import Warnings

SHARED = (Definition(), Values(), Warnings(), Closure(), Jacobian(), RoundTrip(), Determinism(), Machine(), Golden(),
          Snapshot())
"""Every host's checks, in report order: a host inserts its own among them."""

__all__ = ["NEEDS", "PHASES", "SHARED", "Check", "Closure", "Context", "Definition", "Determinism", "Golden", "Jacobian",
           "Machine", "RoundTrip", "Snapshot", "Values", "VerifyCheck", "Warnings", "by_need"]
