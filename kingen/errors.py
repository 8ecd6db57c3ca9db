"""The one error type kingen raises for bad input; only the CLI prints it."""


class KingenError(Exception):
    """A one-line diagnostic a user can act on: ``file:line: field: problem``.

    The message is complete on its own; the CLI prints it on stderr and exits 2.
    """


def located(source, line, field, problem):
    """Build a KingenError in compiler style from its parts (any part may be None)."""
    where = ":".join(str(part) for part in (source, line) if part is not None)
    text = ": ".join(str(part) for part in (where or None, field or None, problem) if part)
    return KingenError(text)


def read_limited(path, limit, what):
    """The bytes of the file at ``path``; KingenError when it cannot be read or is larger
    than ``limit`` bytes (``what`` says what such a file is, for the message)."""
    try:
        with open(path, "rb") as stream:
            data = stream.read(limit + 1)
    except OSError as error:
        raise located(path, None, None, f"cannot be read: {error.strerror}") from None
    if len(data) > limit:
        raise located(path, None, None, f"larger than {size_text(limit)}; {what}")
    return data


def size_text(limit):
    """A byte limit in words: '64 MB' (MiB), '100 kB'."""
    return f"{limit >> 20} MB" if limit >= 1 << 20 else f"{limit // 1000} kB"


class PluginDefect(KingenError):
    """A library that breaks its host's interface before it can be verified (it does not
    load, lacks an entry point, answers impossible counts): a failed verification (exit 1),
    not bad input. ``check`` names the verify check it fails."""

    def __init__(self, message, check="load"):
        super().__init__(message)
        self.check = check


class InternalError(Exception):
    """A defect in kingen itself, raised where it is detected away from the CLI (in a
    child process): the CLI reports it as an internal error (exit 3)."""
