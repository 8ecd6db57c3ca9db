"""The shape every verify check has, and what checks read.

A check is a :class:`VerifyCheck`: its ``name`` in the reports, what it ``needs`` (one of
``NEEDS``: the library file, the loaded routine, the calls on the sampled poses, the
compared poses, the robot's golden values, a snapshot), and ``run(context)`` returning
:class:`~kingen.verify.report.Check` results (a verdict, the detail behind it, diagnoses). verify
runs a routine's checks (its ``checks`` tuple, which its host composes from ``SHARED`` and
its own) in that order, each once what it needs is there; adding or removing a check is one
module and one entry in a host's tuple (:mod:`kingen.verify.checks`).
"""

from dataclasses import dataclass
from typing import Any, ClassVar, Optional

from ..report import Check  # noqa: F401  (the result every check returns)

NEEDS = ("library", "routine", "sampled calls", "compared poses", "golden values", "snapshot")
"""What a check can need, in the order verify has it: ``library`` the file (read in kingen's
own process, before anything is loaded); ``routine`` the loaded routine, before any pose;
``sampled calls`` the totals of the calls on the sampled poses; ``compared poses`` also at
least one call whose outputs were compared (else the check reports ``uncompared`` or is
left out); ``golden values`` the robot's golden entries; ``snapshot`` a recorded snapshot."""
PHASES = {"routine": "the interface checks", "sampled calls": "the determinism check",
          "compared poses": "the determinism check", "golden values": "the golden values",
          "snapshot": "the snapshot"}
"""The stage a crash or hang inside a check is reported in, by what the check needs."""

STOPPED_CALLS = "not compared: every call was stopped at a write outside its buffers"
"""The ``uncompared`` failure of the checks that judge the routine's outputs."""


@dataclass
class Context:
    """What checks read: the robot, the loaded routine, the options, the report so far; the
    library's path (``library`` checks); the comparison's totals (:class:`kingen.verify.tally.Tally`)."""

    robot: Any
    options: Any
    routine: Any = None
    report: Any = None
    library: Any = None
    tally: Any = None

    def call(self, t6, calibrated=True):
        """The routine's Calls on ``t6`` from a reset host, with the options' calibration
        fields (or with empty fields: the published geometry)."""
        self.routine.reset_host()
        if not calibrated:
            return self.routine.call(t6)
        return self.routine.call(t6, self.options.link_lengths, self.options.link_offsets)


class VerifyCheck:
    """One check: subclass with its ``name`` and ``needs`` (and ``item``, ``uncompared``) as
    class keywords, ``class Closure(VerifyCheck, name="closure", needs="compared poses")``,
    or as class attributes; implement ``run``."""

    name: ClassVar[str]
    needs: ClassVar[str]
    item: ClassVar[Optional[str]] = None
    """The pytest plugin's item that reports this check (None: only verify's report)."""
    uncompared: ClassVar[Optional[str]] = None
    """For ``compared poses`` checks: the failure reported when no call's outputs could be
    compared (None: the check is left out then)."""

    def __init_subclass__(cls, **attributes):
        unknown = sorted(set(attributes) - {"name", "needs", "item", "uncompared"})
        if unknown:
            raise TypeError(f"{cls.__name__}: a check has no class keyword {', '.join(unknown)}")
        super().__init_subclass__()
        for key, value in attributes.items():
            setattr(cls, key, value)

    def run(self, context) -> list:
        """The check's results (usually one Check named ``name``)."""
        raise NotImplementedError


def by_need(checks, need):
    """The checks of ``checks`` that need ``need``, in order."""
    return [check for check in checks if check.needs == need]

