"""Where independent jobs run: a pool of local processes, or Dask's distributed executor on a
cluster. The design search (:mod:`kingen.design.search`) evaluates its particles through it, and
verify (:mod:`kingen.verify.cluster`) compares its chunks through it with ``--scheduler``;
either gives the same results wherever its jobs run, since every job is a pure function of
its arguments."""

import contextlib
import os
import re
import signal
import threading
from dataclasses import dataclass

from ..errors import KingenError
from .cores import usable_cores
from .text import one_line, printable

SCHEDULER_TIMEOUT = 20.0
"""Seconds, in all, that connecting to a Dask scheduler given by ``--scheduler`` and its first
answers (who it is, its worker threads) may take; likewise closing the connection."""
DASK_SHARE = 0.75
"""The part of SCHEDULER_TIMEOUT Dask's own connection attempts get: where nothing listens, or
the host is unknown, Dask's reason is the one named, before the deadline cuts it off."""
SCHEDULER_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")
"""The protocols of Dask's network addresses (``inproc://`` reaches only this process)."""
_ADDRESS = re.compile(r"(?:(?P<scheme>[a-z]+)://)?(?P<host>\[[0-9A-Fa-f:.%\w]+\]|[\w.-]+):(?P<port>[0-9]{1,5})")
"""Dask's address form: [scheme://]host:port, an IPv6 host in brackets."""


@dataclass(frozen=True)
class Workers:
    """An open executor: ``pool`` (a ``concurrent.futures.Executor``), ``description`` ('2
    worker processes', 'a Dask cluster at ADDRESS (4 threads)') and ``count``, how many jobs
    it runs at once (processes, or the cluster's worker threads when it was opened)."""

    pool: object
    description: str
    count: int


def _start_worker(parent):
    """In a pool worker, forked or spawned by kingen's process ``parent`` (its pid): it dies
    with kingen, however kingen ends (SIGKILL included: ``PR_SET_PDEATHSIG``; at once if kingen
    ended before that was asked), and Ctrl-C and SIGTERM sent to the whole process group (a
    terminal's Ctrl-C, a service manager's stop) are the parent's to handle (it checkpoints and
    stops the pool; a worker that died of them first would break the pool)."""
    from .household import die_with_parent

    die_with_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})  # blocked while it was forked


def _started(pool):
    """``pool`` with its workers started now, SIGINT and SIGTERM blocked while they fork (they
    inherit the block and ignore both before lifting it): Ctrl-C during the start then neither kills a
    worker before it ignores SIGINT (a broken pool, exit 3) nor is lost in the fork's own
    handlers (the run went on to exit 0); it reaches kingen once the workers are up."""
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        pool.submit(int).result()
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)
    return pool


def scheduler_address(address):
    """``address`` if it has the form of a Dask scheduler's address: ``tcp://host:port``,
    ``tls://``, ``ws://``, ``wss://`` or ``ucx://`` likewise, or ``host:port`` (TCP); an IPv6
    host in brackets (``tcp://[::1]:8786``); the port 1 to 65535. KingenError otherwise,
    before anything connects."""
    match = _ADDRESS.fullmatch(address)
    if match is None:
        problem = "not of the form tcp://HOST:PORT, tls://HOST:PORT or HOST:PORT"
    elif match["scheme"] is not None and match["scheme"] not in SCHEDULER_SCHEMES:
        problem = f"unknown protocol {match['scheme']!r} (Dask knows {', '.join(SCHEDULER_SCHEMES)})"
    elif not 1 <= int(match["port"]) <= 65535:
        problem = f"port {int(match['port'])} is not within 1 to 65535"
    else:
        return address
    raise KingenError(f"--scheduler: {printable(repr(address))} is not a Dask scheduler address: {problem}")


def checked_scheduler(context, parameter, value):
    """Click callback of ``--scheduler``: None, or the address scheduler_address accepts."""
    return None if value is None else scheduler_address(value)


def _within(seconds, function, *arguments):
    """``function(*arguments)``, run in a daemon thread and waited for at most ``seconds``:
    its result or its exception; TimeoutError when it has not returned by then (the thread is
    left blocked, and ends with the process)."""
    outcome = {}

    def run():
        try:
            outcome["result"] = function(*arguments)
        except BaseException as error:  # handed to the waiting thread, which raises it
            outcome["error"] = error

    thread = threading.Thread(target=run, name="kingen scheduler", daemon=True)
    thread.start()
    thread.join(seconds)
    if thread.is_alive():
        raise TimeoutError(f"no answer within {seconds:g} s")
    if "error" in outcome:
        raise outcome["error"]
    return outcome["result"]


def _connect(address):
    """(A distributed Client connected to the scheduler at ``address``, its worker threads)."""
    from distributed import Client

    client = Client(address, timeout=DASK_SHARE * SCHEDULER_TIMEOUT, set_as_default=False)
    try:
        return client, sum(client.nthreads().values())
    except BaseException:
        client.close(timeout=SCHEDULER_TIMEOUT)
        raise


@contextlib.contextmanager
def _cluster(address):
    """Workers on the Dask cluster at ``address``: connected and asked its threads within
    SCHEDULER_TIMEOUT seconds in all, closed within as long again. KingenError naming the
    address when no scheduler answers in time, or what answers is not a Dask scheduler."""
    scheduler_address(address)
    try:
        import distributed  # noqa: F401 (only whether it is installed)
    except ImportError:
        raise KingenError("--scheduler: Dask's 'distributed' package is not installed "
                          "(pip install 'kingen[cluster]')") from None
    try:
        client, cores = _within(SCHEDULER_TIMEOUT, _connect, address)
    except Exception as error:  # a silent or foreign server: whatever Dask raised, it is the address's
        detail = str(error) if isinstance(error, OSError) else f"not a Dask scheduler: {type(error).__name__}: {error}"
        raise KingenError(f"--scheduler: no Dask scheduler at {printable(address)} ({one_line(detail)})") from None
    try:
        yield Workers(client.get_executor(), f"a Dask cluster at {address} ({cores} threads)", cores)
    finally:
        with contextlib.suppress(Exception):  # the jobs are done: a scheduler that fails to say goodbye is let go
            _within(SCHEDULER_TIMEOUT, client.close, SCHEDULER_TIMEOUT)


@contextlib.contextmanager
def executor(workers=None, scheduler=None):
    """An open Workers: Dask's distributed executor on the cluster at ``scheduler`` (an address
    such as tcp://host:8786), else a pool of ``workers`` processes (default: the usable cores).
    KingenError when ``distributed`` is not installed, the address is not one, or no scheduler
    answers within SCHEDULER_TIMEOUT seconds (_cluster)."""
    if scheduler is not None:
        with _cluster(scheduler) as workers:
            yield workers
        return
    from concurrent.futures import ProcessPoolExecutor

    count = workers or usable_cores()
    with ProcessPoolExecutor(count, initializer=_start_worker, initargs=(os.getpid(),)) as pool:
        yield Workers(_started(pool), f"{count} worker process{'es' if count != 1 else ''}", count)
