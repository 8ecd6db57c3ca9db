"""Robot-file errors as compiler-style lines: ``file:line: field: problem``, from the YAML's
key lines (:class:`Locator`) and from pydantic's validation errors (:func:`diagnostic`)."""

import difflib

from ..errors import located
from .layouts import LAYOUTS
from .limbs import MODELS
from .reading import dotted


class Locator:
    """Turns a field path into 'file:line: field: problem' using the YAML's key lines."""

    def __init__(self, source, lines):
        self.source = source
        self.lines = lines

    def error(self, path, problem):
        line = None
        for cut in range(len(path), -1, -1):
            if tuple(path[:cut]) in self.lines:
                line = self.lines[tuple(path[:cut])]
                break
        return located(self.source, line, dotted(path), problem)


_FRIENDLY = {"extra_forbidden": "unknown key", "missing": "required key missing"}


def diagnostic(error, locate):
    """The first pydantic error as a located one-line KingenError; an unknown key beside a
    missing one it resembles is named as a misspelling of it."""
    errors = error.errors(include_url=False)
    for extra in (item for item in errors if item["type"] == "extra_forbidden"):
        siblings = [str(item["loc"][-1]) for item in errors
                    if item["type"] == "missing" and tuple(item["loc"][:-1]) == tuple(extra["loc"][:-1])]
        match = difflib.get_close_matches(str(extra["loc"][-1]), siblings, n=1)
        if match:
            return locate.error(_shown_path(extra["loc"]), f"unknown key '{extra['loc'][-1]}' (did you mean '{match[0]}'?)")
    first = errors[0]
    path = _shown_path(first["loc"])
    if first["type"] in ("union_tag_invalid", "union_tag_not_found"):
        path.append(first["ctx"]["discriminator"].strip("'"))
    problem = _FRIENDLY.get(first["type"], first["msg"])
    if problem.startswith("Value error, "):
        problem = problem[len("Value error, "):]
    value = first.get("input")
    if first["type"] not in _FRIENDLY and not isinstance(value, (dict, list)) and len(repr(value)) < 40:
        problem += f" (got {value!r})"
    return locate.error(path, problem)


def _shown_path(location):
    """A pydantic error location as the robot file's field path (union tags left out)."""
    tags = {*MODELS, *(layout.model_fields["type"].annotation.__args__[0] for layout in LAYOUTS)}
    path = []
    for part in location:
        if isinstance(part, str) and part in tags and path and (isinstance(path[-1], int) or path[-1] == "layout"):
            continue
        path.append(part)
    return path
