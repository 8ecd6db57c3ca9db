"""Where the shipped templates and robot definitions are.

In a checkout (and an editable install) they are the top-level ``templates/`` and
``robots/`` folders; a regular install packs them as ``kingen.templates`` and
``kingen.robots`` (see pyproject.toml).
"""

import importlib.resources
from pathlib import Path

_CHECKOUT = Path(__file__).resolve().parent.parent


def _folder(name, marker):
    local = _CHECKOUT / name
    if (local / marker).is_file():
        return local
    return Path(str(importlib.resources.files(f"kingen.{name}")))


def templates_dir():
    """The folder of the jinja2 C templates and the host emulator source."""
    return _folder("templates", "kin_robot.c.j2")


def robots_dir():
    """The folder of the shipped robot definitions."""
    return _folder("robots", "hexapod.yaml")
