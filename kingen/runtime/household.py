"""What a job's child process starts, and where it may write, ended and removed with it by
kingen's own process (:class:`Household`); and :func:`die_with_parent`, which every process
kingen forks asks for."""

import ctypes
import functools
import os
import shutil
import signal
import tempfile
import time
from contextlib import suppress


class Household:
    """Everything a job's child starts, ended and removed by the parent when the child ends.

    A plugin's constructor may fork, ``setsid`` and spin, or leave files in its temporary
    folder; the child itself may be killed before it cleans up. None of that may outlive the
    run, and the cleanup must not depend on the child, which runs foreign code:

    - the child runs in a process group of its own (set by the parent and by the child, so
      neither order of the two races): nothing it signals through its group (``kill(0,
      SIGSTOP)``) reaches kingen, and a terminal's Ctrl-C reaches kingen alone, which stops it;
    - this process is a child subreaper (``PR_SET_CHILD_SUBREAPER``) while the child lives, so
      a process the plugin started and detached (``setsid``, a double fork) becomes this
      process's child when its parent dies, rather than init's;
    - when the child has ended, its group is killed, and then every child of this process
      that was not one before the child started (orphans handed to the subreaper) is killed
      and reaped, round after round, since each kill hands that orphan's own children over,
      for at most the grace the parent gives;
    - the child's temporary folder (``TMPDIR`` and Python's ``tempfile`` there: module copies,
      reload copies, captured output) is made here and removed here, after all that.

    Linux only, each part a no-op where the kernel lacks it. What it cannot do alone (a
    plugin that stops or kills kingen itself, processes a plugin detached when kingen is
    killed with SIGKILL), the sandbox the child enters does (:mod:`kingen.runtime.sandbox`);
    this is what is left where the kernel refuses it. A process another thread of kingen
    forks while the child lives would be taken for an orphan: kingen forks none.
    :meth:`clear` says how many orphans it ended: a run whose plugin left some fails."""

    def __init__(self):
        self.folder = tempfile.mkdtemp(prefix="kingen-child-")
        self._known = set(children(os.getpid()))
        self._was_subreaper = _subreaper(True)

    def hosted(self, job):
        """``job`` as the child runs it: in its own process group, with the temporary folder."""
        return functools.partial(_hosted, self.folder, job)

    def start(self, child):
        """Start ``child`` (a multiprocessing Process running a hosted job) in its own group;
        on failure (no fork), nothing is left behind."""
        try:
            child.start()
        except BaseException:
            self.clear(child, 0.0)
            raise
        with suppress(OSError):  # it may have exited already
            os.setpgid(child.pid, child.pid)

    def clear(self, child, grace):
        """After ``child`` ended and was reaped: kill its group and every orphan it left, reap
        them (for at most ``grace`` seconds), remove the temporary folder, and stop being a
        subreaper unless this process was one before. Returns how many orphans were killed."""
        if child.pid is not None:
            with suppress(OSError):
                os.killpg(child.pid, signal.SIGKILL)
        orphans = _kill_orphans(self._known, time.monotonic() + grace)
        if not self._was_subreaper:
            _subreaper(False)
        shutil.rmtree(self.folder, ignore_errors=True)
        return orphans


def _hosted(folder, job, channel, *arguments):
    """In the child: join its own process group, make ``folder`` its temporary folder, run the job."""
    os.setpgid(0, 0)
    os.environ["TMPDIR"] = tempfile.tempdir = folder
    return job(channel, *arguments)


def _subreaper(on):
    """Make this process a child subreaper or not (``PR_SET_CHILD_SUBREAPER``); return whether
    it was one before (False where Linux cannot say)."""
    try:
        prctl = ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return False
    was = ctypes.c_int(0)
    prctl(37, ctypes.byref(was))  # PR_GET_CHILD_SUBREAPER
    prctl(36, int(on))  # PR_SET_CHILD_SUBREAPER
    return bool(was.value)


def children(pid, proc=None):
    """The pids of the processes whose parent is ``pid``, from /proc, or from the /proc open as
    descriptor ``proc`` (a PID namespace's own); empty without it."""
    found = []
    with suppress(OSError):
        for entry in os.listdir("/proc" if proc is None else proc):
            if entry.isdigit() and _parent(entry, proc) == pid:
                found.append(int(entry))
    return found


def _parent(pid, proc):
    """The parent pid in ``pid``'s stat file (in /proc, or the /proc of descriptor ``proc``);
    None when it has ended meanwhile."""
    try:
        descriptor = os.open(f"{pid}/stat" if proc is not None else f"/proc/{pid}/stat", os.O_RDONLY,
                             dir_fd=proc)
        try:
            fields = os.read(descriptor, 4096).rsplit(b")", 1)[1].split()
        finally:
            os.close(descriptor)
    except OSError:
        return None
    return int(fields[1])


def _kill_orphans(known, deadline):
    """SIGKILL and reap every child of this process not in ``known``, again for the children
    each kill hands over, until none is left or ``deadline`` (time.monotonic()) has passed;
    return how many were killed."""
    killed = set()
    while time.monotonic() < deadline:
        orphans = [pid for pid in children(os.getpid()) if pid not in known]
        if not orphans:
            break
        killed.update(orphans)
        for pid in orphans:
            with suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        for pid in orphans:
            with suppress(OSError):
                os.waitpid(pid, 0)
    return len(killed)


def die_with_parent(parent=None):
    """Ask Linux to SIGKILL this process when its parent dies, however the parent dies; with
    ``parent`` (its pid), end at once if that one has died already (this process then has
    another parent)."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGKILL))  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass
    if parent is not None and os.getppid() != parent:
        os._exit(1)


def dying_with_this_process():
    """A ``preexec_fn`` for :class:`subprocess.Popen`: the program it starts is killed when this
    process dies, SIGKILL included (PR_SET_PDEATHSIG, which the program keeps across exec)."""
    return functools.partial(die_with_parent, os.getpid())
