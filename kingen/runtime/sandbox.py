"""The sandbox a job's child process runs foreign code in (a plugin, a LinuxCNC module, a C
library): Linux namespaces, resource limits and a seccomp filter, each from the kernel.

:func:`confine` is called first thing in the child that kingen forks for a job. That child
(the *keeper*) never runs foreign code itself:

- it enters new user, PID, mount, IPC and (unless the job needs the network) network
  namespaces (``unshare(2)``), maps only its own user and group, and makes the whole file
  system read-only but the job's folder (``mount_setattr(2)``, recursive);
- it forks the new PID namespace's first process (its PID 1), which forks the *runner* and
  reaps what is handed to it: the runner and whatever it starts see no process outside the
  namespace (their parent is pid 1 to them), so they cannot signal or trace kingen, and
  every process in the namespace dies when the runner has ended; the runner mounts
  a /proc of its namespace, sets resource limits (``setrlimit``: CPU time, address space,
  file size, processes, no core files), and loads the seccomp filter of
  :mod:`kingen.runtime.syscalls` before it returns to run the job;
- the keeper then answers the filter's notifications (what it refuses it reports to kingen,
  through a channel of its own that the runner does not hold), waits for the namespace's
  end and ends as the runner ended (the same exit status or signal), so kingen's reports stay as
  they were.

Where the kernel refuses namespaces (an unprivileged container, a kernel that forbids user
namespaces to unprivileged users), the runner is an ordinary child with the limits and the
filter alone; without libseccomp, namespaces and limits alone; with neither, the job runs in
the keeper itself, as before the sandbox (a child process of the same user). Which of these
a job got is the first message the keeper sends (:func:`description`).
"""

import ctypes
import ctypes.util
import errno
import os
import platform
import resource
import signal
import socket
import sys

from . import syscalls, wire
from .household import children, die_with_parent
from .syscalls import AT_FDCWD, CLONE_NEWIPC, CLONE_NEWNET, CLONE_NEWNS, CLONE_NEWPID, CLONE_NEWUSER

MS_NOSUID, MS_NODEV, MS_NOEXEC, MS_BIND, MS_REC, MS_PRIVATE = 2, 4, 8, 4096, 16384, 1 << 18
AT_RECURSIVE, MOUNT_ATTR_RDONLY = 0x8000, 1
SYS_MOUNT_SETATTR = 442
"""mount_setattr(2)'s number on x86-64 and arm64 (the only machines the sandbox sets up on)."""

LIMITS = {
    resource.RLIMIT_CORE: 0,
    resource.RLIMIT_FSIZE: 256 << 20,
    resource.RLIMIT_AS: 16 << 30,
    resource.RLIMIT_CPU: 24 * 3600,
}
"""The runner's resource limits (both soft and hard; lowered only, never raised): no core
files, files of at most 256 MiB, 16 GiB of address space, 24 hours of processor time."""
PROCESSES = 256
"""The processes the runner's user may have in its user namespace (RLIMIT_NPROC), set only
there: outside one the limit counts every process of the user on the machine."""


class _MountAttr(ctypes.Structure):
    _fields_ = [("attr_set", ctypes.c_uint64), ("attr_clr", ctypes.c_uint64), ("propagation", ctypes.c_uint64),
                ("userns_fd", ctypes.c_uint64)]


_libc = ctypes.CDLL(None, use_errno=True)


def _checked(result, what):
    """``result`` of a libc call, or OSError naming ``what`` and the errno."""
    if result < 0:
        number = ctypes.get_errno()
        raise OSError(number, f"{what}: {os.strerror(number)}")
    return result


def confine(folder, log_descriptor, log_key, network, filtering, keeper_closes=()):
    """In a job's child: enter the sandbox (the module's docstring) and return in the runner,
    which goes on to run the job with ``folder`` its only writable folder. The keeper (the
    calling process) does not return: it supervises the runner and ends as it ended. Its
    messages go to ``log_descriptor`` (kingen.runtime.wire frames under ``log_key``):
    ``isolation`` (description()) first, then ``refused`` and ``left`` (what the filter
    refused, what the job left running; kingen.runtime.syscalls). ``network``: keep the
    network (a Dask scheduler's jobs), neither network namespace nor refused sockets.
    ``filtering``: True when the filter can be loaded, else why not
    (kingen.runtime.syscalls.filtering_available, asked before the fork).
    ``keeper_closes``: descriptors only the runner keeps (the job's channel, which must
    close when the runner closes it)."""
    log = wire.Sender(log_descriptor, log_key)
    namespaces = _namespaces(folder, network)
    if namespaces is not True and filtering is not True:
        log.send("isolation", description(namespaces, filtering, network))
        log.close()
        _limit(False)
        return
    proc = os.open("/proc", os.O_RDONLY | os.O_DIRECTORY)
    keeper_end, runner_end = socket.socketpair()
    status_reading, status_writing = os.pipe()
    child = os.fork()
    if child == 0:
        keeper_end.close()
        log.close()
        os.close(proc)
        os.close(status_reading)
        if namespaces is True:  # (the listener's socket too: the keeper hears its end when the runner's ends)
            _init(status_writing, (*keeper_closes, runner_end.fileno()))
        os.close(status_writing)
        _runner(namespaces is True, filtering is True, runner_end, network)
        return
    runner_end.close()
    os.close(status_writing)
    for descriptor in keeper_closes:
        os.close(descriptor)
    try:
        listener = _listener(keeper_end)
        if filtering is True and listener is None:
            filtering = "the kernel refused to load it"
        log.send("isolation", description(namespaces, filtering, network))
        if listener is not None:
            runner = children(child, proc)[:1] if namespaces is True else [child]
            syscalls.Supervisor(listener, (runner or [child])[0], child, folder, namespaces is True, log,
                                proc).watch()
        _, status = os.waitpid(child, 0)
    except BaseException:  # kingen's defect here: the runner must not outlive it
        os.kill(child, signal.SIGKILL)
        raise
    told = os.read(status_reading, 4)
    log.close()
    _end_as(int.from_bytes(told, "little") if len(told) == 4 else status)


def _init(status_writing, closes):
    """In the first process of the new PID namespace (its PID 1, which ignores the signals
    it has no handler for, abort()'s included, and whose end ends every process in it): fork
    the runner and return in it; here, reap every process handed over until the runner has
    ended, write its wait status to ``status_writing`` and end. ``closes``: descriptors only
    the runner keeps."""
    die_with_parent()
    runner = os.fork()
    if runner == 0:
        return
    for descriptor in closes:
        os.close(descriptor)
    while True:
        try:
            pid, status = os.wait()
        except ChildProcessError:
            os._exit(1)
        if pid == runner:
            os.write(status_writing, status.to_bytes(4, "little"))
            os._exit(0)


def description(namespaces, filtering, network):
    """One line naming the isolation a job got: ``namespaces`` and ``filtering`` are True
    or the reason they are missing (text)."""
    parts = []
    if namespaces is True:
        kinds = "user, PID, mount and IPC" if network else "user, PID, network, mount and IPC"
        parts.append(f"sandbox: {kinds} namespaces of its own, the file system read-only but its folder")
    else:
        parts.append(f"no namespaces ({namespaces}): a child process of your user, with your user's access")
    parts.append("a seccomp filter" if filtering is True else f"no seccomp filter ({filtering})")
    parts.append("limits on processor time, memory, file size" + (" and processes" if namespaces is True else ""))
    return "; ".join(parts)


def _namespaces(folder, network):
    """Enter new namespaces and make the file system read-only but ``folder``: True, or the
    reason it could not (the kernel's refusal), having changed nothing that matters then."""
    flags = CLONE_NEWUSER | CLONE_NEWPID | CLONE_NEWNS | CLONE_NEWIPC | (0 if network else CLONE_NEWNET)
    uid, gid = os.getuid(), os.getgid()
    if platform.machine() not in ("x86_64", "aarch64"):
        return f"the sandbox does not know this machine's system calls ({platform.machine()})"
    if _libc.syscall(SYS_MOUNT_SETATTR, -1, None, 0, None, 0) < 0 and ctypes.get_errno() == errno.ENOSYS:
        return "the kernel has no mount_setattr (Linux 5.12 or later has)"
    try:
        _checked(_libc.unshare(flags), "unshare")
    except OSError as error:
        return f"the kernel refuses them: {error.strerror}"
    try:
        _write("/proc/self/setgroups", "deny")
        _write("/proc/self/uid_map", f"{uid} {uid} 1")
        _write("/proc/self/gid_map", f"{gid} {gid} 1")
        _checked(_libc.mount(None, b"/", None, MS_REC | MS_PRIVATE, None), "mount --make-rprivate /")
        where = os.fsencode(os.path.realpath(folder))
        _checked(_libc.mount(where, where, None, MS_BIND | MS_REC, None), "mount --bind")
        _mount_setattr(b"/", AT_RECURSIVE, MOUNT_ATTR_RDONLY, 0)
        _mount_setattr(where, 0, 0, MOUNT_ATTR_RDONLY)
    except OSError as error:
        # Entered but not set up: nothing of it can be undone, so the job may not run here.
        raise OSError(error.errno, f"the sandbox could not be set up: {error.strerror}") from None
    return True


def _mount_setattr(path, flags, set_attributes, clear_attributes):
    attributes = _MountAttr(set_attributes, clear_attributes, 0, 0)
    _checked(_libc.syscall(SYS_MOUNT_SETATTR, AT_FDCWD, path, flags, ctypes.byref(attributes),
                           ctypes.sizeof(attributes)), "mount_setattr")


def _write(path, text):
    with open(path, "w") as stream:
        stream.write(text)


def _runner(namespaced, filtering, keeper_end, network):
    """In the runner, before the job: die with the keeper, a /proc of its own PID namespace,
    the limits, and the filter (whose listener goes to the keeper; this process keeps none)."""
    die_with_parent()
    sys.dont_write_bytecode = True  # an import's cache file would be a write outside the folder
    # cffi looks for a library it cannot load by name, which runs ldconfig or a compiler (execve)
    ctypes.util.find_library = _found_nowhere
    if namespaced:
        _own_proc()
    _limit(namespaced)
    try:
        if filtering:
            listener = syscalls.load_filter(network)
            socket.send_fds(keeper_end, [b"L"], [listener])
            os.close(listener)
    finally:
        keeper_end.close()


def _found_nowhere(name):
    """ctypes.util.find_library in the runner: no library is found by name."""
    return None


def _own_proc():
    """A /proc that shows this PID namespace alone (in a mount namespace of the runner's
    own, so that the keeper keeps seeing kingen's); best effort: a kernel that refuses it
    (a /proc partly hidden by a container) leaves the old one, which shows pids this
    namespace cannot reach."""
    try:
        _checked(_libc.unshare(CLONE_NEWNS), "unshare")
        _checked(_libc.mount(b"proc", b"/proc", b"proc", MS_NOSUID | MS_NODEV | MS_NOEXEC, None), "mount proc")
    except OSError:
        pass


def _limit(namespaced):
    """Lower this process's resource limits to LIMITS (and PROCESSES in a user namespace)."""
    limits = {**LIMITS, **({resource.RLIMIT_NPROC: PROCESSES} if namespaced else {})}
    for kind, value in limits.items():
        soft, hard = resource.getrlimit(kind)
        value = value if hard == resource.RLIM_INFINITY else min(value, hard)
        try:
            resource.setrlimit(kind, (value, value))
        except (ValueError, OSError):
            pass


def _listener(keeper_end):
    """The filter's listener the runner sends, or None when it sent none (it has no filter,
    or it died before)."""
    try:
        _, descriptors, _, _ = socket.recv_fds(keeper_end, 1, 1)
    except OSError:
        descriptors = []
    finally:
        keeper_end.close()
    return descriptors[0] if descriptors else None


def _end_as(status):
    """End this process as ``status`` (os.waitpid's) says its runner ended."""
    if os.WIFSIGNALED(status):
        number = os.WTERMSIG(status)
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
        signal.signal(number, signal.SIG_DFL)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, [number])
        os.kill(os.getpid(), number)
    os._exit(os.waitstatus_to_exitcode(status) if os.WIFEXITED(status) else 1)
