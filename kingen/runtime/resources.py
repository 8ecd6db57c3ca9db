"""Where the shipped templates and robot definitions are.

In a checkout (and an editable install) they are the top-level ``templates/`` and
``robots/`` folders; a regular install packs them inside the package as
``kingen/templates`` and ``kingen/robots`` (see pyproject.toml).
"""

from pathlib import Path

from ..errors import KingenError

_PACKAGE = Path(__file__).resolve().parent.parent


def _folder(name, marker):
    for folder in (_PACKAGE.parent / name, _PACKAGE / name):
        if (folder / marker).is_file():
            return folder
    raise KingenError(f"kingen's {name} folder is missing from this installation (looked for {marker})")


def templates_dir():
    """The folder of the shared jinja2 templates (limb model partials, the analysis report)."""
    return _folder("templates", "limbs/leg.c.j2")


def robots_dir():
    """The folder of the shipped robot definitions."""
    return _folder("robots", "hexapod.yaml")
