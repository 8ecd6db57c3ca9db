"""Where independent jobs run: a pool of local processes, or Dask's distributed executor on a
cluster. The design search (:mod:`kingen.optimize`) evaluates its particles through it, and
verify (:mod:`kingen.verify.cluster`) compares its chunks through it with ``--scheduler``;
either gives the same results wherever its jobs run, since every job is a pure function of
its arguments."""

import contextlib
import signal
from dataclasses import dataclass

from .errors import KingenError

SCHEDULER_TIMEOUT = "20s"
"""How long a Dask scheduler given by ``--scheduler`` may take to answer."""


@dataclass(frozen=True)
class Workers:
    """An open executor: ``pool`` (a ``concurrent.futures.Executor``), ``description`` ('2
    worker processes', 'a Dask cluster at ADDRESS (4 threads)') and ``count``, how many jobs
    it runs at once (processes, or the cluster's worker threads when it was opened)."""

    pool: object
    description: str
    count: int


def _ignore_interrupts():
    """In a worker: Ctrl-C is the parent's to handle (it checkpoints and stops the pool)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def executor(workers=None, scheduler=None):
    """An open Workers: Dask's distributed executor on the cluster at ``scheduler`` (an address
    such as tcp://host:8786), else a pool of ``workers`` processes (default: the usable cores).
    KingenError when ``distributed`` is not installed or no scheduler answers within
    SCHEDULER_TIMEOUT."""
    if scheduler is not None:
        try:
            from distributed import Client
        except ImportError:
            raise KingenError("--scheduler: Dask's 'distributed' package is not installed "
                              "(pip install 'kingen[cluster]')") from None
        try:
            client = Client(scheduler, timeout=SCHEDULER_TIMEOUT)
        except OSError as error:
            raise KingenError(f"--scheduler: no Dask scheduler at {scheduler} ({error})") from None
        with client:
            cores = sum(client.nthreads().values())
            yield Workers(client.get_executor(), f"a Dask cluster at {scheduler} ({cores} threads)", cores)
        return
    from concurrent.futures import ProcessPoolExecutor

    from .verify.processes import comparing_processes

    count = workers or comparing_processes()
    with ProcessPoolExecutor(count, initializer=_ignore_interrupts) as pool:
        yield Workers(pool, f"{count} worker process{'es' if count != 1 else ''}", count)
