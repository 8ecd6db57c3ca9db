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
import pwd
import shutil
import tempfile
from pathlib import Path

from .errors import KingenError

PACKAGE_MARKER = ".kingen-package"
"""Marks a folder kingen wrote, so that it may be replaced by a newer package."""


def umask():
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_atomic(path, content, executable=False):
    """Write text or bytes to ``path`` through a temporary file and a rename (see
    :func:`atomic_file`): ``path`` holds either its old content or all of ``content``."""
    data = content.encode() if isinstance(content, str) else content
    with atomic_file(path, executable) as stream:
        stream.write(data)


@contextlib.contextmanager
def atomic_file(path, executable=False):
    """A binary stream to a temporary file beside ``path``, which takes ``path``'s place when
    the block ends normally; on any exception it is removed and ``path`` is left as it was.
    The file gets the permissions the user's umask gives a new file (0644 under umask 022;
    0755 when ``executable``), never the temporary file's 0600."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(handle, "wb") as stream:
            yield stream
        os.chmod(temporary, (0o777 if executable else 0o666) & ~umask())
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def default_out_dir(robot):
    """build/<name>: where a robot's outputs go unless -o says otherwise."""
    return Path("build") / robot.name


def write_folder(out_dir, fill, marker_text):
    """Write the folder ``out_dir`` whole or not at all: ``fill(staging)`` writes the files
    into a hidden sibling folder, which then takes ``out_dir``'s place, marked as kingen's
    (PACKAGE_MARKER holding ``marker_text``). An existing ``out_dir`` is replaced only if it
    is empty or kingen wrote it; anything else is refused, never overwritten."""
    out_dir = Path(out_dir)
    if out_dir.exists() and not (out_dir.is_dir() and (not any(out_dir.iterdir())
                                                       or (out_dir / PACKAGE_MARKER).is_file())):
        raise KingenError(f"{out_dir}: exists and is not a kingen package folder; choose another -o")
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


def cached(folder, library, make):
    """``library`` in cache ``folder``, made by ``make()`` unless the folder's stamp records
    exactly its hash (a truncated or foreign file is rebuilt, never trusted)."""
    stamp = folder / "stamp.json"
    if read_stamp(stamp, "library_sha256") == file_digest(library) is not None:
        return
    try:
        make()
        write_atomic(stamp, json.dumps({"library_sha256": file_digest(library)}) + "\n")
    except PermissionError as error:
        raise KingenError(f"kingen's cache folder {folder} is not writable ({error.strerror}): "
                          "set KINGEN_CACHE to a folder of your own") from None
