"""The file-reading gate: a file kingen is given is read only when it is a regular file,
without blocking and within a size limit, and its CSV rows only as far as they are CSV;
anything else is one located KingenError.

A FIFO, device, socket or folder is refused from its metadata, before anything opens it
(reading a FIFO waits for a writer forever, a device never ends).
"""

import csv
import os
import stat

from ..errors import located

_SPECIAL_FILES = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                  (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def refuse_special_file(path):
    """KingenError naming ``path`` when it exists and is not a regular file (symbolic links
    followed): a FIFO, device, socket or folder is refused from its metadata alone, before
    anything opens it (reading a FIFO waits for a writer forever, a device never ends). A
    path that does not exist or cannot be looked up is left to whoever opens it."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return
    _refuse_mode(path, mode)


def _refuse_mode(path, mode):
    if not stat.S_ISREG(mode):
        kind = next((words for test, words in _SPECIAL_FILES if test(mode)), "a special file")
        raise located(path, None, None, f"not a regular file ({kind}); give the file itself")


def read_limited(path, limit, what):
    """The bytes of the regular file at ``path``; KingenError when it is not one (refused
    before it is opened, see refuse_special_file), cannot be read or is larger than ``limit``
    bytes (``what`` says what such a file is, for the message). Never blocks: the file is
    opened with O_NONBLOCK and checked again once open (it may have been swapped meanwhile)."""
    refuse_special_file(path)
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
        with os.fdopen(descriptor, "rb") as stream:
            _refuse_mode(path, os.fstat(descriptor).st_mode)
            data = stream.read(limit + 1)
    except OSError as error:
        raise located(path, None, None, f"cannot be read: {error.strerror}") from None
    if len(data) > limit:
        raise located(path, None, None, f"larger than {size_text(limit)}; {what}")
    return data


def size_text(limit):
    """A byte limit in words: '64 MB' (MiB), '100 kB'."""
    return f"{limit >> 20} MB" if limit >= 1 << 20 else f"{limit // 1000} kB"


def csv_rows(path, lines):
    """(line number, cells) of each CSV row of ``lines`` (an iterable of text lines, such as an
    open file, of the file at ``path``); what the csv module cannot read (a field over its
    limit, a bad quote) is the located KingenError '<path>:<line>: not CSV: ...'."""
    reader = csv.reader(lines)
    try:
        for row in reader:
            yield reader.line_num, row
    except csv.Error as error:
        raise located(path, reader.line_num, None, f"not CSV: {error}") from None
