"""kingen's error types: KingenError (bad input, one located line; :func:`located` builds
one) and PluginDefect (a library that breaks its host's interface), which only the CLI
prints, and InternalError (a defect in kingen itself)."""


class KingenError(Exception):
    """A one-line diagnostic a user can act on: ``file:line: field: problem``.

    The message is complete on its own; the CLI prints it on stderr and exits 2.
    """


def located(source, line, field, problem):
    """Build a KingenError in compiler style from its parts (any part may be None)."""
    where = ":".join(str(part) for part in (source, line) if part is not None)
    text = ": ".join(str(part) for part in (where or None, field or None, problem) if part)
    return KingenError(text)


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
