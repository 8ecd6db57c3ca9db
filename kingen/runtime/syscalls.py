"""The seccomp filter of a job's runner (:mod:`kingen.runtime.sandbox`) and the keeper's
answers to what it reports.

The filter (libseccomp, through the pyseccomp binding) lets through every system call a
kinematics routine and kingen's own code make, and hands the keeper those a routine never
needs (seccomp user notifications): tracing or reading another process (``ptrace``,
``process_vm_*``), running a program (``execve``), a socket, mounts and namespaces, kernel
modules and keys, and a signal to a process outside the job (its parent, its process group,
every process). The keeper refuses each (the caller gets EPERM) and tells kingen what was
called, which fails the run naming it. It also sees each opening of a file for writing and
refuses (EACCES) and names those outside the job's folder (a character device such as
/dev/null excepted; the read-only file system is what stops them, this names them), and
the runner's own exit, when it names the processes the job left behind (they end with it).

A notification is answered after the call was judged from the caller's arguments as they
were then; the answers are for naming, never the only barrier where the kernel gives one
(namespaces, a read-only file system): the filter's verdicts on signals and writes are exact
only in the sandbox's namespaces."""

import ctypes
import errno
import functools
import os
import select
import signal
import socket
import stat

from .text import counted

WRITE_FLAGS = (os.O_WRONLY, os.O_RDWR, os.O_CREAT, os.O_TRUNC)
OPENING = {"open": (None, 0, 1), "openat": (0, 1, 2), "creat": (None, 0, None)}
"""For each call that opens a file: the argument holding its folder's descriptor (None: the
working folder), its path's, and its flags' (None: always for writing)."""
SIGNALLING = {"kill": 1, "tkill": 1, "tgkill": 2, "rt_sigqueueinfo": 1, "rt_tgsigqueueinfo": 2}
"""Calls that signal the process (or thread) their first argument names: their signal's argument."""
REFUSED = ("ptrace", "process_vm_readv", "process_vm_writev", "pidfd_getfd", "pidfd_send_signal", "execve",
           "execveat", "mount", "umount2", "pivot_root", "chroot", "unshare", "setns", "move_mount", "open_tree",
           "fsopen", "fsmount", "fsconfig", "fspick", "mount_setattr", "bpf", "perf_event_open", "userfaultfd",
           "keyctl", "add_key", "request_key", "init_module", "finit_module", "delete_module", "kexec_load",
           "kexec_file_load", "reboot", "swapon", "swapoff", "acct")
CLONE_NEWNS, CLONE_NEWCGROUP, CLONE_NEWUTS, CLONE_NEWIPC, CLONE_NEWUSER, CLONE_NEWPID, CLONE_NEWNET = (
    0x00020000, 0x02000000, 0x04000000, 0x08000000, 0x10000000, 0x20000000, 0x40000000)
NAMESPACE_FLAGS = (CLONE_NEWNS, CLONE_NEWCGROUP, CLONE_NEWUTS, CLONE_NEWIPC, CLONE_NEWUSER, CLONE_NEWPID,
                   CLONE_NEWNET)
"""clone(2)'s flags for new namespaces (mount, cgroup, UTS, IPC, user, PID, network)."""
AT_FDCWD = -100
"""The folder argument that means the caller's working folder."""
HIDDEN = ("clone3", "openat2")
"""Calls whose arguments the filter cannot read: answered ENOSYS, so that the C library falls back
on clone and openat, which it can."""
CONTINUE = 1
"""SECCOMP_USER_NOTIF_FLAG_CONTINUE: let the call run as made."""
MAX_TOLD = 16
"""The most refusals told kingen for one job (it stops the job at the first)."""


@functools.lru_cache(maxsize=None)
def filtering_available():
    """True when libseccomp and the kernel can filter with user notifications, else why not;
    asked once per process (importing the binding looks for libseccomp, which takes a while
    and may write temporary files: never in a sandbox)."""
    try:
        import pyseccomp
    except (ImportError, RuntimeError) as error:  # RuntimeError: libseccomp is not installed
        return f"libseccomp or its binding pyseccomp is missing: {error}"
    if not hasattr(pyseccomp._libseccomp, "seccomp_notify_receive") or pyseccomp.get_api() < 5:
        return "libseccomp or the kernel is too old for user notifications"
    return True


def load_filter(network):
    """Load the filter into this process (and the processes it will start); return its
    listener's descriptor (the keeper's to answer). ``network``: sockets are allowed, and
    openings for writing are not looked at (a Dask client writes where it likes, libuuid's
    clock file for one: the read-only file system stops it, unnamed)."""
    import pyseccomp as seccomp

    rules = seccomp.SyscallFilter(seccomp.ALLOW)

    def rule(action, name, *arguments):
        try:
            rules.add_rule(action, name, *arguments)
        except (OSError, ValueError, RuntimeError):  # not a call on this architecture
            pass

    for name in REFUSED + tuple(SIGNALLING) + ("exit_group",) + (() if network else ("socket",)):
        rule(seccomp.NOTIFY, name)
    for name in HIDDEN:
        rule(seccomp.ERRNO(errno.ENOSYS), name)
    for flag in NAMESPACE_FLAGS:
        rule(seccomp.NOTIFY, "clone", seccomp.Arg(0, seccomp.MASKED_EQ, flag, flag))
    for name, (_, _, flags) in {} if network else OPENING.items():
        for flag in WRITE_FLAGS if flags is not None else ():
            rule(seccomp.NOTIFY, name, seccomp.Arg(flags, seccomp.MASKED_EQ, flag, flag))
        if flags is None:
            rule(seccomp.NOTIFY, name)
    rules.load()
    return os.dup(seccomp._libseccomp.seccomp_notify_fd(rules._filter))


def _int(value):
    """A system call's argument as the C int it was."""
    return ctypes.c_int32(value & 0xFFFFFFFF).value


def _status(proc, pid, field):
    """A number from ``pid``'s status file (``Tgid``, ``PPid``; ``NSpid``: its pid in its
    innermost namespace) in the /proc of descriptor ``proc``; None when it is gone."""
    try:
        descriptor = os.open(f"{pid}/status", os.O_RDONLY, dir_fd=proc)
        try:
            text = os.read(descriptor, 4096).decode()
        finally:
            os.close(descriptor)
    except OSError:
        return None
    for line in text.splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[-1])
    return None


class Supervisor:
    """The keeper's side: answer the filter's notifications until ``child`` (the keeper's
    child: the runner, or the first process of the runner's PID namespace) ends. ``runner``
    is the process that runs the job (pids are this process's); ``folder`` the job's only
    writable folder; ``namespaced``: the runner is in a PID namespace of its own (pids in
    its calls are that namespace's); ``log`` (a kingen.runtime.wire.Sender) gets
    ``refused`` and ``left`` messages; ``proc`` is a descriptor of this process's /proc."""

    def __init__(self, listener, runner, child, folder, namespaced, log, proc):
        import pyseccomp

        self._seccomp = pyseccomp
        self._library = pyseccomp._libseccomp
        self._library.seccomp_notify_id_valid.argtypes = (ctypes.c_int, ctypes.c_uint64)
        self.listener, self.runner, self.child, self.namespaced, self.log, self.proc = (
            listener, runner, child, namespaced, log, proc)
        self.folder = os.path.realpath(folder)
        self.told = 0
        self._namespace = self._link(runner, "ns/pid")

    def watch(self):
        """Answer every notification until the runner has ended (then close the listener)."""
        ended = os.pidfd_open(self.child)
        try:
            while True:
                ready = select.select([self.listener, ended], [], [])[0]
                if ended in ready:  # (the listener then reads as ready for good)
                    return
                self._answer()
        finally:
            os.close(ended)
            os.close(self.listener)

    def _answer(self):
        request = ctypes.POINTER(self._seccomp._Notif)()
        response = ctypes.POINTER(self._seccomp._NotifResp)()
        if self._library.seccomp_notify_alloc(ctypes.byref(request), ctypes.byref(response)) < 0:
            raise MemoryError("libseccomp could not allocate a notification")
        try:
            if self._library.seccomp_notify_receive(self.listener, request) < 0:
                return  # its caller died meanwhile
            call = request.contents
            name = self._seccomp.resolve_syscall(self._seccomp.Arch.NATIVE, call.data.nr).decode()
            refusal = self._judged(name, call.pid, list(call.data.args))
            if self._library.seccomp_notify_id_valid(self.listener, call.id) < 0:
                return
            response.contents.id = call.id
            response.contents.val = 0
            response.contents.error = -refusal if refusal else 0
            response.contents.flags = 0 if refusal else CONTINUE
            self._library.seccomp_notify_respond(self.listener, response)
        finally:
            self._library.seccomp_notify_free(request, response)

    def _judged(self, name, caller, arguments):
        """The errno refusing ``name`` called by ``caller`` with ``arguments``, or 0 to let it
        run; a refusal is told kingen."""
        if name == "exit_group":
            if caller == self.runner:
                self._tell_left()
            return 0
        if name in SIGNALLING:
            target, number = _int(arguments[0]), _int(arguments[SIGNALLING[name]])
            if self._may_signal(caller, target):
                return 0
            return self._tell("refused", f"called {name}({target}, {_signal_name(number)})", errno.EPERM)
        if name in OPENING:
            where, path, _ = OPENING[name]
            folder = _int(arguments[where]) if where is not None else -100
            opened = self._path(caller, arguments[path], folder)
            if opened is not None and self._writable(opened):
                return 0
            return self._tell("refused", f"opened {opened or 'a file'} for writing", errno.EACCES)
        if name == "socket":
            return self._tell("refused", f"called socket({_family(_int(arguments[0]))})", errno.EPERM)
        if name in ("execve", "execveat"):
            program = self._path(caller, arguments[0 if name == "execve" else 1], -100)
            return self._tell("refused", f"called {name}({program or 'a program'})", errno.EPERM)
        if name == "clone":
            return self._tell("refused", "called clone() for new namespaces", errno.EPERM)
        return self._tell("refused", f"called {name}()", errno.EPERM)

    def _tell(self, kind, text, number=0):
        if self.told < MAX_TOLD:
            self.told += 1
            self.log.send(kind, text)
        return number

    def _may_signal(self, caller, target):
        """Whether ``caller`` (a thread, by this process's pid) may signal ``target`` (a pid as
        the caller sees it): its own process, or one the runner started (not the runner's
        parent, nor anything outside the job); the runner only itself."""
        if target <= 0:
            return False
        group = self._status(caller, "Tgid")
        target_group = self._status(self._pid(target), "Tgid")
        if target_group is None or target_group == group:
            return target_group is not None
        return target_group != self.runner and self._descends(target_group)

    def _pid(self, seen):
        """This process's pid of the job's process the job calls ``seen`` (None: none)."""
        if not self.namespaced:
            return seen
        for entry in os.listdir(self.proc):
            if entry.isdigit() and self._status(entry, "NSpid") == seen and \
                    self._link(entry, "ns/pid") == self._namespace:
                return int(entry)
        return None

    def _descends(self, pid):
        for _ in range(256):
            parent = self._status(pid, "PPid")
            if parent in (None, 0, 1):
                return False
            if parent == self.runner:
                return True
            pid = parent
        return False

    def _tell_left(self):
        """Name the processes the job leaves running as the runner exits (other than the
        runner; a process that has ended but was not reaped is not running)."""
        left = []
        for entry in os.listdir(self.proc):
            if entry.isdigit() and int(entry) not in (self.runner, self.child) and self._running(entry):
                pid = int(entry)
                if (self._link(pid, "ns/pid") == self._namespace) if self.namespaced else self._descends(pid):
                    left.append(pid)
        if left:
            self._tell("left", f"left {counted(len(left), 'process', 'processes')} running when its job ended")

    def _running(self, pid):
        try:
            descriptor = os.open(f"{pid}/stat", os.O_RDONLY, dir_fd=self.proc)
            try:
                return os.read(descriptor, 4096).rsplit(b")", 1)[1].split()[0] not in (b"Z", b"X")
            finally:
                os.close(descriptor)
        except (OSError, IndexError):
            return False

    def _path(self, caller, address, folder):
        """The absolute path at ``address`` in ``caller``'s memory, relative to its descriptor
        ``folder`` (-100: its working folder); None when it cannot be read."""
        try:
            memory = os.open(f"{caller}/mem", os.O_RDONLY, dir_fd=self.proc)
            try:
                text = b""
                while b"\0" not in text and len(text) < 4096:
                    part = os.pread(memory, 256, address + len(text))
                    if not part:
                        break
                    text += part
            finally:
                os.close(memory)
            path = os.fsdecode(text.split(b"\0")[0])
            if not os.path.isabs(path):
                path = os.path.join(self._link(caller, "cwd" if folder == AT_FDCWD else f"fd/{folder}"), path)
            return os.path.normpath(path)
        except (OSError, TypeError):
            return None

    def _writable(self, path):
        """Whether the job may open ``path`` for writing: within its folder, or a character device."""
        real = os.path.realpath(path)
        if real == self.folder or real.startswith(self.folder + os.sep):
            return True
        try:
            return stat.S_ISCHR(os.stat(real).st_mode)
        except OSError:
            return False

    def _link(self, pid, name):
        try:
            return os.readlink(f"{pid}/{name}", dir_fd=self.proc)
        except OSError:
            return None

    def _status(self, pid, field):
        return None if pid is None else _status(self.proc, pid, field)


def _signal_name(number):
    try:
        return signal.Signals(number).name
    except ValueError:
        return str(number)


def _family(number):
    try:
        return socket.AddressFamily(number).name
    except ValueError:
        return str(number)
