"""verify's chunks on a Dask cluster (``--scheduler ADDRESS``), through the executor the
design search uses (:mod:`kingen.runtime.executors`).

Each chunk is one job: a worker loads the library (its bytes travel with the job, so the
workers need kingen, not the build folder; loaded once per worker process), draws the
chunk's poses from the seeded stream (skipping to its first pose, so they are the same, bit
for bit) and sends back the chunk's _Part, as a local comparing process does. The parts are
merged in chunk order, so the report is the one a local run gives. A chunk whose job fails
(the routine crashed a worker, a worker was lost) is compared again in this process, where
a crash is named as always; if it runs to the end here, it is reported as a death for the
``crash`` check."""

import hashlib
import itertools
import shutil
import tempfile
from collections import deque
from dataclasses import dataclass
from pathlib import Path

from ..runtime.executors import executor
from ..kinematics.poses import PoseStream
from . import processes

AHEAD = 4
"""Jobs submitted per worker thread ahead of the chunk being merged: enough to keep every
thread busy, few enough that memory holds a bounded number of parts."""


@dataclass(frozen=True)
class ChunkJob:
    """What a worker needs to compare any chunk: the robot, its calibrated copy, the host
    (a kingen.hosts.Host), the library's bytes, their sha256 and the routine, the options."""

    robot: object
    calibrated: object
    host: object
    library: bytes
    digest: str
    routine: str
    options: object


def chunk_job(robot, calibrated, loaded_from, options):
    """The ChunkJob of a verification of the routine ``loaded_from`` (host, library path,
    routine name)."""
    host, library, routine = loaded_from
    data = Path(library).read_bytes()
    return ChunkJob(robot, calibrated, host, data, hashlib.sha256(data).hexdigest(), routine, options)


_loaded = {}
"""Per worker process: the loaded routine of each library digest."""


def compare_on_worker(job, begin, size):
    """On a worker: the _Part of poses ``begin`` .. ``begin + size - 1`` of the job's seed
    (the first chunk keeps its poses for the diagnoses, as locally)."""
    if job.digest not in _loaded:
        folder = Path(tempfile.mkdtemp(prefix="kingen-worker-"))
        try:
            path = folder / f"{job.digest[:16]}.so"
            path.write_bytes(job.library)
            _loaded[job.digest] = job.host.load(path, job.routine, job.robot)
        finally:  # the loaded library stays mapped; its file is not needed again
            shutil.rmtree(folder, ignore_errors=True)
    processes.set_chunk_job(job.robot, job.calibrated, _loaded[job.digest], job.options)
    stream = PoseStream(job.robot, job.options.seed)
    stream.skip(begin)
    return processes.compare_poses(stream.draw(size), first=begin == 0)


class ClusterChunks:
    """The chunks ``bounds`` compared on the cluster at ``options.scheduler``: open it with
    ``with``; ``count`` is the worker threads comparing (at most one per chunk), ``parts()``
    yields (first index, pose count, _Part) in chunk order. ``deaths`` collects (first
    index, pose count, what failed) of each chunk whose job failed and which then ran to the
    end here."""

    def __init__(self, robot, calibrated, plugin, options, bounds, loaded_from, phase):
        self._job = chunk_job(robot, calibrated, loaded_from, options)
        self._local = (robot, calibrated, plugin, options)
        self._bounds, self._phase = bounds, phase
        self._opened = executor(scheduler=options.scheduler)
        self.count = 0
        self.deaths = []

    def __enter__(self):
        processes.set_chunk_job(*self._local)  # for the chunks compared here, and the boundary poses after
        self._workers = self._opened.__enter__()
        self.count = max(1, min(len(self._bounds), self._workers.count))
        return self

    def __exit__(self, *exception):
        return self._opened.__exit__(*exception)

    def parts(self):
        chunks = iter(self._bounds)
        pending = deque(self._submit(*chunk) for chunk in itertools.islice(chunks, AHEAD * self.count))
        while pending:
            begin, size, future = pending.popleft()
            pending.extend(self._submit(*chunk) for chunk in itertools.islice(chunks, 1))
            self._phase(f"poses {begin} to {begin + size - 1} of seed {self._job.options.seed}")
            try:
                part = future.result()
            except Exception as error:  # the worker died (the routine crashed it) or was lost
                part = self._compare_here(begin, size)
                self.deaths.append((begin, size, f"{type(error).__name__}: {error}"))
            yield begin, size, part

    def _submit(self, begin, size):
        return begin, size, self._workers.pool.submit(compare_on_worker, self._job, begin, size)

    def _compare_here(self, begin, size):
        """A failed chunk, compared again in this process (where the routine's crash is named)."""
        stream = PoseStream(self._local[0], self._job.options.seed)
        stream.skip(begin)
        return processes.compare_poses(stream.draw(size), first=begin == 0)
