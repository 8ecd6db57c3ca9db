"""DELMIA's own verify checks, one module each: the interface contract of docs/explanation/delmia-abi.md
(:mod:`.interface`), the routine's return value (:mod:`.return_value`) and its buffers
(:mod:`.buffers`); and ``CHECKS``: every check a DELMIA routine gets, in report order."""

from ....verify.checks import (Closure, Definition, Determinism, Golden, Jacobian, Machine, RoundTrip, Snapshot, Values,
                               Warnings)
from .buffers import Buffers, buffers_check
from .interface import GetKinConfig, KinCheckDefinition, NonFiniteT6, Refusal
from .return_value import ReturnValue

CHECKS = (Definition(), GetKinConfig(), KinCheckDefinition(), Refusal(), NonFiniteT6(), Values(), Warnings(),
          ReturnValue(), Buffers(), Closure(), Jacobian(), RoundTrip(), Determinism(), Machine(), Golden(),
          Snapshot())
"""Every check a DELMIA routine gets, in report order: definition, the interface, values,
warnings, return value, buffers, closure, Jacobian, round trip, determinism, machine, golden, snapshot."""

__all__ = ["CHECKS", "Buffers", "GetKinConfig", "KinCheckDefinition", "NonFiniteT6", "Refusal", "ReturnValue",
           "buffers_check"]
