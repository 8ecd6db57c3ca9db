"""The seeded poses of a robot's verification region, drawn the same way by verify, snapshots
and benchmarks: uniform in home +/- range (mm, degrees; docs/explanation/conventions.md), from one
PCG64 generator, so that a seed names the same poses bit for bit whatever the chunking. A
machine with task coordinates (kingen.kinematics.hybrid.parasitic) has its drawn poses moved onto its
manifold (x, y and yaw the machine's), but for one in OFF_MANIFOLD_EVERY, left as drawn, whose
answer is the off-manifold warning (where its routine reads x, y and yaw: ``parasitic_given``)."""

import numpy as np

from .hybrid.parasitic import OFF_MANIFOLD_EVERY, on_manifold


class PoseStream:
    """The seeded poses of a verification, in order: uniform in the robot's verification
    region (mm, degrees), from one generator, drawn or skipped a run at a time. Skipping
    moves the generator past the poses as if they had been drawn (each uniform double takes
    one 64-bit output of PCG64), so the poses after them are the same, bit for bit."""

    def __init__(self, robot, seed):
        region = robot.verification
        self._home, self._half_widths = np.asarray(region.home), np.asarray(region.range)
        self._generator = np.random.default_rng(seed)
        self._robot, self._drawn = robot, 0

    def draw(self, count):
        """The next ``count`` poses (count, 6)."""
        poses = self._home + self._generator.uniform(-1.0, 1.0, size=(count, 6)) * self._half_widths
        if self._robot.task:
            kept = ((np.arange(self._drawn, self._drawn + count) % OFF_MANIFOLD_EVERY) == OFF_MANIFOLD_EVERY - 1) \
                & self._robot.parasitic_given
            poses = np.where(kept[:, None], poses, on_manifold(self._robot, poses))
        self._drawn += count
        return poses

    def skip(self, count):
        """Move past the next ``count`` poses without drawing them."""
        self._generator.bit_generator.advance(6 * count)
        self._drawn += count


def chunk_bounds(count, chunk):
    """(first index, pose count) of each chunk of ``count`` poses, ``chunk`` at a time."""
    return [(begin, min(chunk, count - begin)) for begin in range(0, count, chunk)]


def pose_chunks(robot, count, seed, chunk):
    """(first index, poses (m, 6)) chunk by chunk: ``count`` poses of PoseStream, so the poses
    are the same, bit for bit, whatever the chunk size; memory stays that of one chunk."""
    stream = PoseStream(robot, seed)
    for begin, size in chunk_bounds(count, chunk):
        yield begin, stream.draw(size)


def sample_poses(robot, count, seed):
    """``count`` poses (mm, degrees) uniform in the robot's verification region, seeded."""
    return np.concatenate([poses for _, poses in pose_chunks(robot, count, seed, max(count, 1))])
