"""What a verification is asked to do, and the bounds every check shares: how close a
routine's joints must be (docs/explanation/verify.md)."""

from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..defaults import DEFAULT_TIMEOUT
from ..kinematics.routine import VALUE_TOLERANCE_MM

RELATIVE_TOLERANCE = 256 * np.finfo(float).eps
"""For robots larger than about 17 m the prismatic bound grows with size: 256 eps x size."""
CONDITIONING_FACTOR = 16.0 * np.finfo(float).eps
"""Inside a limb's singular band its joint is ill-conditioned (a square root of a radicand
near 0): there it is compared within CONDITIONING_FACTOR * scale / sqrt(max(|D|, eps)),
scale = link length (mm) for rails, 1 rad for cranks. Everywhere else the fixed limits hold."""


@dataclass(frozen=True)
class VerifyOptions:
    """What a verification is asked to do: poses, seed, the calibration fields, time limit (s)."""

    samples: int = 10000
    seed: int = 0
    link_lengths: tuple = None
    link_offsets: tuple = None
    timeout: float = DEFAULT_TIMEOUT
    snapshot: object = None
    """A loaded kingen.verify.snapshot.Snapshot to check the routine against (check ``snapshot``)."""
    processes: Optional[int] = 1
    """Processes comparing the sampled poses: 1 keeps everything in the calling process, more
    fork the others (compared_chunks); None: kingen.runtime.cores.usable_cores(), one per core."""
    scheduler: Optional[str] = None
    """A Dask scheduler's address (tcp://host:8786): the poses are compared by its cluster's
    workers instead (kingen.verify.cluster; ``processes`` does not apply)."""


def report_tolerance_mm(robot):
    """The prismatic bound verify reports for ``robot`` (see value_tolerance_mm)."""
    return value_tolerance_mm(robot)


def value_tolerance_mm(robot):
    """The bound on prismatic joints: 1e-9 mm, or 256 eps x the robot's size (mm) when larger."""
    return max(VALUE_TOLERANCE_MM, RELATIVE_TOLERANCE * robot.size_mm)
