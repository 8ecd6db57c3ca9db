"""Running foreign code in a child process: loading a library (its constructors run),
asking it about its routine and every routine call; and capturing what it prints.

The command line never executes plugin code in its own process. A job runs in a
forked child and talks to the parent through a pipe: stage names, progress, finished
checks and at last its result, each as plain data in an authenticated frame
(:mod:`kingen.runtime.wire`) that the parent checks field by field before it uses any of it. The
parent waits at most ``timeout`` seconds for each message, so a routine that stops making progress (an endless loop, a sleep per call)
is killed and named with the stage it was in; a child that dies (a segfault, a call to
``exit()``) becomes a :class:`ChildFailure` naming the signal or exit status and the
stage, and one killed from outside (SIGKILL from the out-of-memory killer, say) says so
rather than blaming the routine. The child dies with the parent (``PR_SET_PDEATHSIG`` on
Linux), and the parent kills it on the way out of any exception, SIGTERM included (the CLI
turns SIGTERM into ``SystemExit``); whatever the child started, and its temporary folder, go
with it (:class:`kingen.runtime.household.Household`).

The child enters the sandbox of :mod:`kingen.runtime.sandbox` before the job runs (namespaces,
a read-only file system but its folder, resource limits, a seccomp filter); the sandbox's
keeper tells the parent, on a channel of its own, which isolation the job got, what the
filter refused (a ``sandbox`` failure naming the call and the stage, the child stopped at
once) and what the job left running when it ended (a ``sandbox`` failure too).
"""

import ctypes
import faulthandler
import functools
import multiprocessing
import os
import select
import signal
import sys
import tempfile
import traceback
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Tuple

from . import wire
from ..errors import InternalError, KingenError, PluginDefect
from .household import Household, die_with_parent
from .sandbox import confine
from .syscalls import filtering_available
from .text import counted

FIRST_STAGE = "loading the routine"
"""The stage a job starts in, unless its caller names it (a host's ``loading_stage``)."""


@dataclass(frozen=True)
class ChildFailure:
    """Why a job ended without a result: ``kind`` 'crash' or 'timeout', and where."""

    kind: str
    stage: str
    detail: str


class Channel:
    """The child's end: ``stage(text)`` before each step, ``send(kind, value)`` for the rest
    (plain data: kingen.runtime.wire)."""

    def __init__(self, sender):
        self._sender = sender

    def stage(self, text):
        self._sender.send("stage", text)

    def send(self, kind, value):
        self._sender.send(kind, value)


def run_in_child(job, arguments, timeout, on_message=None, first_stage=FIRST_STAGE, decoders=None, network=False,
                 on_isolation=None):
    """Run ``job(channel, *arguments)`` in a forked child, in the sandbox of
    kingen.runtime.sandbox; return (result, None) or (None, ChildFailure). ``on_message(kind,
    value)`` gets every message other than stages, ``on_isolation(text)`` the line naming the
    isolation the job got (kingen.runtime.sandbox.description). A KingenError raised in the child is raised here (bad input found
    while loading); any other exception there is a kingen defect, raised as InternalError.
    ``network``: the job keeps the network (a Dask scheduler's).

    Everything the child sends arrives as plain data through an authenticated channel
    (kingen.runtime.wire); ``decoders`` maps a message kind ('result' included) to a function that
    turns its plain value into the object the caller expects, checked field by field
    (raising WireError). A message that fails its check or cannot be read or decoded is a
    ``crash`` failure naming the stage: the child is stopped, and nothing it sent is used.
    A call the sandbox refused is a ``sandbox`` failure naming it and the stage (the child is
    stopped at once), and so are processes the job left running when it ended (they end with
    it): even after a result, which is then not used."""
    decoders = {**CONTROL_DECODERS, **(decoders or {})}
    context = multiprocessing.get_context("fork")
    key, keeper_key = wire.new_key(), wire.new_key()
    reading, writing = os.pipe()
    keeper_reading, keeper_writing = os.pipe()
    # Not a daemon, so that the job may fork helpers (verify's reference process); it is
    # always stopped and reaped below, and it dies with this process (PR_SET_PDEATHSIG).
    household = Household()
    child = context.Process(target=_child_main, args=(
        (reading, writing, keeper_reading, keeper_writing), (key, keeper_key), household, job, arguments, network, filtering_available()),
        daemon=False)
    try:
        household.start(child)
    finally:
        os.close(writing)
        os.close(keeper_writing)
    receiver = wire.Receiver(reading, key)
    keeper = _KeeperNews(wire.Receiver(keeper_reading, keeper_key), on_isolation)
    stage, finished, outcome = first_stage, False, None
    try:
        while outcome is None:
            message, outcome = _next_message(receiver, decoders, timeout, stage)
            refusal = keeper.refusal(stage)
            outcome = outcome if refusal is None else (None, refusal)
            if outcome is not None or message is None:
                finished = outcome is None
                break
            kind, value = message
            finished = kind in LAST_MESSAGES
            if kind == "stage":
                stage = value
            elif kind == "result":
                outcome = value, None
            elif kind == "defect":
                raise PluginDefect(*value)
            elif kind == "error":
                raise KingenError(value)
            elif kind == "internal":
                raise InternalError(value)
            elif on_message is not None:
                on_message(kind, value)
    finally:
        receiver.close()
        stopped = _end(child, finished)
        orphans = household.clear(child, EXIT_GRACE)
        keeper.close(stage)
    refusal = keeper.refusal(stage)
    if refusal is not None:
        return None, refusal
    if outcome is not None:
        left = keeper.left(orphans)
        return outcome if outcome[1] is not None or left is None else (None, left)
    if stopped:
        return None, ChildFailure("crash", stage, f"the plugin closed kingen's channel to the host process during "
                                                 f"{stage}, which then did not end within {EXIT_GRACE:g} s: it "
                                                 "was stopped")
    if killed_from_outside(child.exitcode):
        return None, ChildFailure("crash", stage, f"the host process was {killer(child.exitcode)} during {stage}, "
                                                 "not ended by the routine: run it again")
    return None, ChildFailure("crash", stage, f"the plugin ended the host process ({ending(child.exitcode)}) "
                                             f"during {stage}")


def _next_message(receiver, decoders, timeout, stage):
    """(the child's next message as (kind, decoded value), or None when it closed the channel;
    None), or (None, the ChildFailure of a timeout or of a message that is not kingen's)."""
    try:
        message = receiver.receive(timeout)
        return (None if message is None else (message[0], _decoded(decoders, *message))), None
    except TimeoutError:
        return None, (None, ChildFailure("timeout", stage, f"no progress for {timeout:g} s during {stage}; "
                                                           "the routine was stopped (--timeout)"))
    except wire.WireError as error:
        return None, (None, ChildFailure("crash", stage, f"kingen's channel to the host process carried {error} "
                                                         f"during {stage}: the host process was stopped and "
                                                         "nothing it sent was used"))


class _KeeperNews:
    """What the sandbox's keeper (kingen.runtime.sandbox.confine) tells kingen, on a channel
    of its own that the code it confines does not hold: the isolation, what it refused, what
    the job left running. Read whenever the job's own channel gave something (the keeper
    writes before it answers the call, so a refusal arrives before what followed it)."""

    def __init__(self, receiver, on_isolation):
        self._receiver, self._on_isolation = receiver, on_isolation
        self._open = True
        self.refused, self._left = [], []

    def _read(self, stage, wait):
        while self._open and select.select([self._receiver.fileno()], [], [], wait)[0]:
            try:
                message = self._receiver.receive(EXIT_GRACE)
            except (TimeoutError, wire.WireError):
                message = None
            if message is None or not isinstance(message[1], str):
                self._open = False
            elif message[0] == "isolation" and self._on_isolation is not None:
                self._on_isolation(message[1])
            elif message[0] == "refused":
                self.refused.append((message[1], stage))
            elif message[0] == "left":
                self._left.append(message[1])

    def refusal(self, stage):
        """The ``sandbox`` failure of the first call the sandbox refused (None: none so far)."""
        self._read(stage, 0)
        if not self.refused:
            return None
        text, when = self.refused[0]
        return ChildFailure("sandbox", when, f"the plugin {text} during {when}, which the sandbox refused: the "
                                             "run was stopped")

    def left(self, orphans):
        """The ``sandbox`` failure of processes the job left running (the keeper's count, or
        ``orphans`` the household ended), None when it left none."""
        if self._left:
            return ChildFailure("sandbox", "the end of the job", f"the plugin {self._left[0]}, which kingen ended")
        if orphans:
            return ChildFailure("sandbox", "the end of the job", f"the plugin left {counted(orphans, 'process', 'processes')} "
                                                                 "running when its job ended, which kingen ended")
        return None

    def close(self, stage):
        """Read what the keeper sent up to its end (it has ended), then close the channel."""
        self._read(stage, EXIT_GRACE)
        self._receiver.close()


_TEXT = functools.partial(wire.typed, str)
CONTROL_DECODERS = {"stage": _TEXT, "defect": functools.partial(wire.typed, Tuple[str, str]), "error": _TEXT,
                    "internal": _TEXT}
"""The messages every job's child sends besides its own: stages, and how it ended if not
with a result."""


def _decoded(decoders, kind, value):
    """A received message's value as its kind's decoder makes it (plain data where the caller
    gave none)."""
    return decoders[kind](value) if kind in decoders else value


def ending(exit_code):
    """How a process ended, in words, from multiprocessing's exit code: 'signal SIGSEGV',
    'exit status 3'."""
    if exit_code is not None and exit_code < 0:
        return f"signal {signal.Signals(-exit_code).name}"
    return f"exit status {exit_code}"


OUTSIDE_SIGNALS = (signal.SIGKILL, signal.SIGTERM, signal.SIGINT, signal.SIGHUP)
"""Signals that come from outside a process (the out-of-memory killer, ``kill``, a closed
terminal), never from a fault of the code it runs: a crashing routine ends its process with
SIGSEGV, SIGBUS, SIGFPE, SIGILL or SIGABRT."""


def killed_from_outside(exit_code):
    """Whether multiprocessing's ``exit_code`` says the process was killed by one of
    OUTSIDE_SIGNALS (rather than crashing, exiting or finishing)."""
    return exit_code is not None and exit_code < 0 and -exit_code in OUTSIDE_SIGNALS


def killer(exit_code):
    """For a process killed_from_outside: 'killed by signal SIGKILL (9) from outside (possibly
    the out-of-memory killer)'; the hint only for SIGKILL, the one that killer sends."""
    hint = " (possibly the out-of-memory killer)" if -exit_code == signal.SIGKILL else ""
    return f"killed by {ending(exit_code)} ({-exit_code}) from outside{hint}"


LAST_MESSAGES = ("result", "defect", "error", "internal")
"""What a child sends last, just before it exits by itself."""
EXIT_GRACE = 5.0
"""Seconds a child that sent its last message (or closed its end) gets to exit by itself."""


def _end(child, finished):
    """Reap the child: one that ``finished`` its job gets EXIT_GRACE seconds to exit by itself;
    any other (stopped for a timeout, or left on an exception here, SIGTERM included) is killed
    at once, since a routine that spins in native code never gets to run a signal handler.
    Returns whether a finished child had to be killed (its last message sent, or its end of
    the pipe closed, it went on running)."""
    if finished:
        child.join(timeout=EXIT_GRACE)
    stopped = child.is_alive()
    if stopped:
        child.kill()
    child.join()
    return finished and stopped


def _child_main(descriptors, keys, household, job, arguments, network, filtering):
    reading, writing, keeper_reading, keeper_writing = descriptors
    os.close(reading)
    os.close(keeper_reading)
    die_with_parent()
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    faulthandler.disable()
    _silence_standard_streams()
    sender = wire.Sender(writing, keys[0])
    channel = Channel(sender)
    try:
        confine(household.folder, keeper_writing, keys[1], network, filtering, keeper_closes=(writing,))
        channel.send("result", household.hosted(job)(channel, *arguments))
    except PluginDefect as error:
        channel.send("defect", (str(error), error.check))
    except KingenError as error:
        channel.send("error", str(error))
    except BaseException as error:  # a kingen defect: reported by the parent as an internal error
        channel.send("internal", f"{type(error).__name__}: {error} ({_origin(error)})")
    finally:
        sender.close()


def _origin(error):
    frames = traceback.extract_tb(error.__traceback__)
    return f"{os.path.basename(frames[-1].filename)}:{frames[-1].lineno}" if frames else "unknown place"


HEAP_KEEP_BYTES = 32 << 20
"""Blocks up to this size come from the heap, and this much freed heap stays mapped."""


def keep_freed_memory():
    """Ask glibc to serve numpy's large temporaries from the heap and keep them mapped once
    freed (M_MMAP_THRESHOLD, M_TRIM_THRESHOLD), instead of unmapping each one: a verify
    allocates the same chunk-sized arrays thousands of times, and each fresh mapping costs
    page faults (on the 2-core machine, 1.8 s of system time in a million-pose hexapod
    verify, 0.3 s with this). Memory stays bounded by the largest chunk; no-op without glibc."""
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return
    mallopt(-3, HEAP_KEEP_BYTES)  # M_MMAP_THRESHOLD
    mallopt(-1, HEAP_KEEP_BYTES)  # M_TRIM_THRESHOLD


def _silence_standard_streams():
    """What foreign code prints goes nowhere unless a job captures it on purpose: it must
    not mix into kingen's own output (which may be a JSON stream read by a script)."""
    to_devnull(1, 2)


def to_devnull(*descriptors):
    """Point each of ``descriptors`` (standard streams) at /dev/null. The descriptor opened
    for it is closed unless it is itself one of them: when a standard stream was closed
    before, /dev/null opens as that very number."""
    null = os.open(os.devnull, os.O_WRONLY)
    for descriptor in descriptors:
        os.dup2(null, descriptor)
    if null not in descriptors:
        os.close(null)


@contextmanager
def captured_output(limit=4096):
    """Capture what native code writes on file descriptors 1 and 2 (printf included).

    Yields a dict that holds, after the block, ``bytes`` (how many were written) and
    ``text`` (the first ``limit`` bytes, decoded). C's stdio buffers are flushed on both
    sides of the block (``fflush(NULL)``), so nothing printed before or inside it is misplaced.
    """
    result = {"bytes": 0, "text": ""}
    for stream in (sys.stdout, sys.stderr):
        if stream is not None:
            stream.flush()
    flush = ctypes.CDLL(None).fflush
    flush(None)
    saved = [os.dup(1), os.dup(2)]
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 1)
        os.dup2(sink.fileno(), 2)
        try:
            yield result
        finally:
            flush(None)
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for descriptor in saved:
                os.close(descriptor)
            result["bytes"] = sink.seek(0, os.SEEK_END)
            sink.seek(0)
            result["text"] = sink.read(limit).decode(errors="replace")
