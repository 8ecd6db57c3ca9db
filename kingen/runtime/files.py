"""Writing outputs, whole or not at all, and kingen's cache folder: what every host's build
and package steps share.

Files are written through a temporary file and a rename; package folders through a hidden
sibling folder that then takes the target's place. The cache (``$KINGEN_CACHE``, else
``$XDG_CACHE_HOME/kingen``, else ``~/.cache/kingen``) holds per-content folders whose
stamp records the hash of what they built.
"""

import contextlib
import hashlib
import json
import os
import secrets
import pwd
import shutil
import stat
import tempfile
from pathlib import Path

from ..errors import KingenError

PACKAGE_MARKER = ".kingen-package"
"""Marks a folder kingen wrote, so that it may be replaced by a newer package."""


def umask():
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_atomic(path, content, executable=False):
    """Write text or bytes to ``path`` whole or not at all (see :func:`atomic_file`)."""
    data = content.encode() if isinstance(content, str) else content
    with atomic_file(path, executable) as stream:
        stream.write(data)


def write_files(files):
    """Write ``files`` ({path: text or bytes}) each whole or not at all (:func:`write_atomic`),
    none of them when any path would be written through another user's link
    (:func:`refuse_foreign`, asked of every path before the first is written)."""
    for path in files:
        refuse_foreign(path)
    for path, content in files.items():
        write_atomic(path, content)


@contextlib.contextmanager
def atomic_file(path, executable=False):
    """A binary stream whose bytes reach ``path`` whole or not at all: written to a temporary
    file beside it that takes its place when the block ends normally; on any exception the
    temporary file and the folders made for it are removed and ``path`` is left as it was.
    The file gets the permissions the user's umask gives a new file (0644 under umask 022;
    0755 when ``executable``), never the temporary file's 0600. A symbolic link of this user's
    or root's is kept and its target written; one of another user's, on the path or met
    resolving it, is refused (:func:`refuse_foreign`). An existing file that is not a regular
    file (a device such as /dev/null or /dev/stdout, a FIFO) is written in place, never
    replaced, unless another user owns it (refused: a FIFO nobody reads would hold kingen).
    KingenError names ``path`` and the cause (a full disk, a folder without permission)."""
    path = Path(path)
    refuse_foreign(path)
    try:
        status = os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        status = None
    except OSError as error:
        raise KingenError(f"{path}: cannot write ({error.strerror or error})") from None
    if status is not None and stat.S_ISDIR(status.st_mode):
        raise KingenError(f"{path}: is a folder, not a file")
    if status is not None and not stat.S_ISREG(status.st_mode):
        if not _trusted(status.st_uid):
            raise KingenError(f"{path}: is a special file of another user (uid {status.st_uid}){NOT_THROUGH}")
        try:
            with open(path, "wb") as stream:
                yield stream
        except OSError as error:
            raise KingenError(f"{path}: cannot write ({error.strerror or error})") from None
        return
    target = Path(os.path.realpath(path)) if path.is_symlink() else path
    created = _missing_folders(target.parent)
    temporary = None
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        # Named before it is made: a signal that unwinds kingen between the file's creation and
        # the name's assignment (inside tempfile.mkstemp) would leave it behind.
        temporary = target.parent / f".{target.name}.{secrets.token_hex(6)}"
        handle = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o600)
        with os.fdopen(handle, "wb") as stream:
            yield stream
        os.chmod(temporary, (0o777 if executable else 0o666) & ~umask())
        os.replace(temporary, target)
    except BaseException as error:
        if temporary is not None:
            Path(temporary).unlink(missing_ok=True)
        for folder in reversed(created):
            with contextlib.suppress(OSError):
                folder.rmdir()
        if isinstance(error, OSError):
            raise KingenError(f"{path}: cannot write ({error.strerror or error})") from None
        raise


NOT_THROUGH = ": kingen writes its outputs only through links and special files of your own or root's " \
              "(remove it or choose another -o)"
MAX_LINKS = 40
"""Symbolic links followed in resolving one path at most (Linux's own limit)."""


def _trusted(uid):
    """Whether a link or special file of ``uid`` may steer kingen's writes: this user's or root's."""
    return uid in (os.getuid(), 0)


def refuse_foreign(path):
    """Refuse (KingenError) to write at ``path`` when resolving it meets a symbolic link that
    another user owns (neither this user nor root), in a folder of the path or at its end:
    such a link, planted in a folder others may write, would turn an output into a write
    outside the output folder (as Linux's protected_symlinks refuses in sticky folders). The
    path is resolved component by component as the kernel does, following at most MAX_LINKS
    links; the first missing component ends the walk (nothing beyond it exists to follow)."""
    pending = list(Path(path).parts)
    current = Path.cwd()
    followed = 0
    while pending:
        part = pending.pop(0)
        if part in ("", "."):
            continue
        if part == "..":
            current = current.parent
            continue
        candidate = current / part
        try:
            status = os.lstat(candidate)
        except OSError:
            return
        if not stat.S_ISLNK(status.st_mode):
            current = candidate
            continue
        if not _trusted(status.st_uid):
            raise KingenError(f"{path}: {candidate} is a symbolic link of another user (uid {status.st_uid})"
                              f"{NOT_THROUGH}")
        followed += 1
        if followed > MAX_LINKS:
            return
        pending[:0] = Path(os.readlink(candidate)).parts


def _missing_folders(folder):
    """The folders from the first missing ancestor of ``folder`` down to it, outermost first."""
    missing = []
    while not folder.exists() and folder != folder.parent:
        missing.append(folder)
        folder = folder.parent
    return list(reversed(missing))


def writable_folder(folder):
    """Refuse (KingenError) an output folder kingen could not write, before any work: the
    folder, or its nearest existing ancestor that kingen would create it in, must be a
    writable folder; a symbolic link to nothing is refused (kingen cannot make a folder there)."""
    folder = Path(folder)
    refuse_foreign(folder)
    missing = _missing_folders(folder)
    if missing and missing[0].is_symlink():
        raise KingenError(f"{folder}: {missing[0]} is a symbolic link to {os.readlink(missing[0])}, "
                          "which does not exist")
    existing = missing[0].parent if missing else folder
    if not existing.is_dir():
        raise KingenError(f"{folder}: {existing} is not a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise KingenError(f"{folder}: folder {existing} is not writable")


def default_out_dir(robot):
    """build/<name>: where a robot's outputs go unless -o says otherwise."""
    return Path("build") / robot.name


def write_folder(out_dir, fill, marker_text):
    """Write the folder ``out_dir`` whole or not at all: ``fill(staging)`` writes the files
    into a hidden sibling folder, which then takes ``out_dir``'s place, marked as kingen's
    (PACKAGE_MARKER holding ``marker_text``). An existing ``out_dir`` is replaced only if it
    is empty or kingen wrote it; anything else is refused, never overwritten, and so is the
    current folder or one holding it (``-o .``), which cannot be replaced whole."""
    given, out_dir = out_dir, Path(os.path.abspath(out_dir))
    refuse_foreign(out_dir)
    here = Path.cwd()
    if out_dir == here or out_dir in here.parents:
        raise KingenError(f"{given}: is the folder you are in{'' if out_dir == here else ' or holds it'}, which "
                          "kingen cannot replace with the package folder; choose a folder of the package's own "
                          "(-o NAME)")
    if out_dir.exists() and not (out_dir.is_dir() and (not any(out_dir.iterdir())
                                                       or (out_dir / PACKAGE_MARKER).is_file())):
        raise KingenError(f"{given}: exists and is not a kingen package folder; choose another -o")
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.", dir=out_dir.parent))
    try:
        fill(staging)
        write_atomic(staging / PACKAGE_MARKER, marker_text)
        os.chmod(staging, 0o777 & ~umask())
        _replace_folder(staging, out_dir)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _replace_folder(new, old):
    """Put folder ``new`` where ``old`` is: the old one is moved aside first, removed last."""
    if not old.exists():
        os.replace(new, old)
        return
    aside = Path(tempfile.mkdtemp(prefix=f".{old.name}.old.", dir=old.parent))
    try:
        os.replace(old, aside / old.name)
        try:
            os.replace(new, old)
        except OSError:
            os.replace(aside / old.name, old)
            raise
    finally:
        shutil.rmtree(aside, ignore_errors=True)


def digest(*parts):
    """sha256 (hex) of text parts joined by NUL: a cache or build key."""
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()


def file_digest(path):
    """sha256 (hex) of a file's bytes, or None when it cannot be read."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return None


def read_stamp(stamp, key):
    """``key`` of the JSON stamp file ``stamp``, or None when it is missing or unreadable."""
    try:
        return json.loads(stamp.read_text()).get(key)
    except (OSError, ValueError, AttributeError):
        return None


def cache_dir():
    """kingen's cache folder: ``$KINGEN_CACHE``, else ``$XDG_CACHE_HOME/kingen``, else
    ``~/.cache/kingen`` (home from $HOME or the password database; an empty or relative value
    is ignored), else a per-user folder in the temp dir."""
    if os.environ.get("KINGEN_CACHE"):
        return Path(os.environ["KINGEN_CACHE"]).absolute()
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    if os.path.isabs(xdg):
        return Path(xdg) / "kingen"
    for home in (os.environ.get("HOME", ""), _password_home()):
        if os.path.isabs(home) and home != "/":
            return Path(home) / ".cache" / "kingen"
    return Path(tempfile.gettempdir()) / f"kingen-cache-{os.getuid()}"


def _password_home():
    try:
        return pwd.getpwuid(os.getuid()).pw_dir
    except KeyError:
        return ""


def cached(folder, library, make, sources=()):
    """``library`` in cache ``folder``, made by ``make()`` unless it is there intact: the
    folder and the cache above it private to this user (see private_folder), every file of
    ``sources`` ({path in folder: text}, what ``make`` writes) holding exactly the text kingen
    computes, and the library holding the hash the stamp beside it records (a truncated or
    foreign file is rebuilt, never trusted)."""
    private_folder(folder.parent)
    private_folder(folder)
    stamp = folder / "stamp.json"
    texts = dict(sources)
    intact = all(_reads(folder / name) == text for name, text in texts.items())
    for path in (library, stamp, *(folder / name for name in texts)):
        private_file(path)
    if intact and read_stamp(stamp, "library_sha256") == file_digest(library) is not None:
        return
    try:
        with private_writes(folder):
            make()
            write_atomic(stamp, json.dumps({"library_sha256": file_digest(library)}) + "\n")
    except PermissionError as error:
        raise KingenError(f"kingen's cache folder {folder} is not writable ({error.strerror}): "
                          "set KINGEN_CACHE to a folder of your own") from None


@contextlib.contextmanager
def private_writes(folder):
    """Create ``folder`` (and its parents) if missing, mode 0700, and within the block create
    files and folders with umask 077: what kingen caches is this user's alone, whatever the
    umask. The umask is restored on leaving, also on an error (OSError from the mkdir included)."""
    mask = os.umask(0o077)
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        yield
    finally:
        os.umask(mask)


def _reads(path):
    try:
        return Path(path).read_text()
    except (OSError, UnicodeDecodeError):
        return None


def private_folder(folder):
    """Refuse (KingenError) a cache folder kingen would run code from that another user could
    have written: one owned by another user, writable by group or others, or a symlink (as
    git's safe.directory refuses a repository another user owns). A missing folder is fine:
    kingen creates it, private."""
    try:
        status = os.lstat(folder)
    except FileNotFoundError:
        return
    if stat.S_ISLNK(status.st_mode) or not stat.S_ISDIR(status.st_mode):
        problem = "is a symbolic link" if stat.S_ISLNK(status.st_mode) else "is not a folder"
    elif status.st_uid != os.getuid():
        problem = f"is owned by another user (uid {status.st_uid})"
    elif status.st_mode & 0o022:
        problem = f"is writable by {'others' if status.st_mode & 0o002 else 'its group'}"
    else:
        return
    raise KingenError(f"kingen's cache folder {folder} {problem}: kingen will not run code another user could "
                      "have put there; set KINGEN_CACHE to a folder of your own")


def private_file(path):
    """Refuse (KingenError) a cached file another user owns or may write; a missing one is fine."""
    try:
        status = os.lstat(path)
    except FileNotFoundError:
        return
    if stat.S_ISREG(status.st_mode) and status.st_uid == os.getuid() and not status.st_mode & 0o022:
        return
    raise KingenError(f"kingen's cached file {path} is not a private regular file of this user: kingen will not "
                      "use it; set KINGEN_CACHE to a folder of your own")
