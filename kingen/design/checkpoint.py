"""The design search's checkpoint file: plain JSON data, never code.

``kingen optimize`` writes ``checkpoint.json`` into its output folder after every iteration
and ``--resume`` reads it back. The file holds only numbers, text and lists: the format
name and version, the design problem's fingerprint and the swarm's state (positions,
velocities, personal bests, the random generator's state, the counters). Reading it can
at most refuse it: it is checked whole before any of it is used (its size, that this user
owns it and no other user may write it, every field's type, and that every
number is finite), so a checkpoint from someone else's hands runs nothing and steers
nothing. What the state means is :mod:`kingen.design.search`'s business; this module only
writes and reads the file.
"""

import errno
import os
import stat
from typing import List, Literal, Optional, Tuple

from pydantic import BaseModel, ConfigDict, ValidationError

from ..errors import KingenError
from ..runtime.file_gate import size_text
from ..runtime.files import private_writes, write_atomic

CHECKPOINT = "checkpoint.json"
"""The checkpoint's file name in optimize's output folder."""
FORMAT = "kingen optimize checkpoint"
VERSION = 1
MAX_CHECKPOINT_BYTES = 16 << 20
"""The largest checkpoint read: a swarm of 1,000 particles over 100 variables takes about 5 MB."""
OLD_PICKLE = "checkpoint.pkl"
"""Where kingen once kept a pickled checkpoint, which it never reads."""


class _Strict(BaseModel):
    model_config = ConfigDict(strict=True, extra="forbid", allow_inf_nan=False, frozen=True)


class Swarm(_Strict):
    """pymoo's particle swarm: the particles' positions ``x``, velocities ``v`` and objective
    values ``f`` (the negated least tilt, degrees), each particle's best position and value
    (``best_x``, ``best_f``), the iteration counter and the random generator (PCG64) state."""

    iteration: int
    x: List[List[float]]
    v: List[List[float]]
    f: List[float]
    best_x: List[List[float]]
    best_f: List[float]
    random_state: int
    random_increment: int
    random_has_uint32: int
    random_uinteger: int


class Checkpoint(_Strict):
    """Everything a search needs to continue (see kingen.design.search.SearchState); tilts in degrees."""

    format: Literal[FORMAT]
    version: Literal[VERSION]
    fingerprint: str
    seed: int
    iteration: int
    evaluations: int
    poses: int
    best_x: Optional[List[float]]
    best_objective: float
    best_table: Optional[List[Tuple[float, str]]]
    history: List[float]
    since_improvement: int
    seconds: float
    swarm: Swarm


def write(folder, checkpoint):
    """Write ``checkpoint`` (a Checkpoint) to ``folder``/CHECKPOINT atomically, readable and
    writable by this user alone (0600 whatever the umask); the folder is made if missing."""
    folder.mkdir(parents=True, exist_ok=True)
    with private_writes(folder):
        write_atomic(folder / CHECKPOINT, checkpoint.model_dump_json() + "\n")
    os.chmod(folder / CHECKPOINT, 0o600)


def read(folder):
    """The Checkpoint in ``folder``, checked whole: KingenError naming the file and the problem
    when there is none, it is not a regular file of this user's that no other user may write
    (a symbolic link is refused too: it is opened without following one, and judged by what
    was opened), it is larger than MAX_CHECKPOINT_BYTES, or it is not a checkpoint of this
    format and version with every field of its type and every number finite."""
    path = folder / CHECKPOINT
    data = _read_private(path)
    try:
        return Checkpoint.model_validate_json(data)
    except ValidationError as error:
        raise KingenError(f"{path}: not a kingen checkpoint ({_first_problem(error)})") from None


def _read_private(path):
    """The bytes of the checkpoint at ``path`` (see read)."""
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_NOFOLLOW | os.O_CLOEXEC)
    except FileNotFoundError:
        old = " (kingen does not read the old pickled checkpoint.pkl)" if (path.parent / OLD_PICKLE).exists() else ""
        raise KingenError(f"{path}: no checkpoint to resume from{old} (run without --resume first)") from None
    except OSError as error:
        problem = "is a symbolic link" if error.errno == errno.ELOOP else f"cannot be read: {error.strerror}"
        raise KingenError(f"{path}: {problem}{REFUSED}") from None
    with os.fdopen(descriptor, "rb") as stream:
        problem = _not_private(os.fstat(descriptor))
        if problem is not None:
            raise KingenError(f"{path}: {problem}{REFUSED}")
        data = stream.read(MAX_CHECKPOINT_BYTES + 1)
    if len(data) > MAX_CHECKPOINT_BYTES:
        raise KingenError(f"{path}: larger than {size_text(MAX_CHECKPOINT_BYTES)}, which no checkpoint is")
    return data


REFUSED = ": kingen resumes only from a checkpoint of your own that no other user could have written " \
          "(run without --resume)"


def _first_problem(error):
    """The first thing wrong with a checkpoint, in one line."""
    first = error.errors()[0]
    where = ".".join(str(part) for part in first["loc"]) or "the document"
    return f"{where}: {first['msg']}"


def _not_private(status):
    """Why another user could have written the file of ``status`` (not a regular file, owned by
    another user, writable by its group or others), or None."""
    if not stat.S_ISREG(status.st_mode):
        return "is not a regular file"
    if status.st_uid != os.getuid():
        return f"is owned by another user (uid {status.st_uid})"
    if status.st_mode & 0o022:
        return f"is writable by {'others' if status.st_mode & 0o002 else 'its group'}"
    return None
