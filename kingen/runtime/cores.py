"""How many cores kingen may use: the cores this process may run on, within a container's
CPU quota."""

import math
import os
from pathlib import Path

from ..defaults import MAX_PROCESSES

CPU_QUOTA_FILES = (("/sys/fs/cgroup/cpu.max", None),
                   ("/sys/fs/cgroup/cpu/cpu.cfs_quota_us", "/sys/fs/cgroup/cpu/cpu.cfs_period_us"))
"""Where Linux control groups (v2, then v1) state a container's CPU time quota and period."""


def usable_cores():
    """How many processes kingen runs at once by default (verify's comparing processes,
    optimize's workers): one per core this process may run on, no more than its container's
    CPU quota allows, at most MAX_PROCESSES."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        cores = os.cpu_count() or 1
    quota = cpu_quota()
    if quota is not None:
        cores = min(cores, quota)
    return max(1, min(MAX_PROCESSES, cores))


def cpu_quota():
    """The cores a control group's CPU quota amounts to (rounded up), or None without one."""
    for quota_file, period_file in CPU_QUOTA_FILES:
        try:
            words = Path(quota_file).read_text().split()
            if period_file is not None:
                words.append(Path(period_file).read_text().strip())
            quota, period = float(words[0]), float(words[1])
        except (OSError, ValueError, IndexError):  # no such file, "max" (v2) or unreadable
            continue
        if quota > 0 and period > 0:
            return math.ceil(quota / period)
    return None
