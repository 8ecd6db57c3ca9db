"""Griffe extension for the Python API page: kingen's docstrings name other objects with
Sphinx roles (``:func:`load_robot```, ``:meth:`solve```, ``:mod:`~kingen.runtime.isolation```),
which ``help()`` readers know but Markdown would print raw. Each role becomes the object's
name in code, linked to its entry when the site documents it (an optional cross-reference:
mkdocs-autorefs links it when found and leaves the code unlinked, without a warning, when
not). A ``~`` shows the last part of the name only, as in Sphinx. Docstrings are rewritten as
loaded for the site; the source is untouched.
"""

import html
import re

import griffe

ROLE = re.compile(r":(?:py:)?(?:func|meth|class|mod|data|attr|exc|obj|const):`(?P<tilde>~?)(?P<name>[^`]+)`")


def _target(obj, name):
    """The full dotted path ``name`` means in the scope of ``obj``: a dotted name as written,
    a bare one resolved as Python would (the object's members, then its parents')."""
    if "." in name:
        return name
    try:
        return obj.resolve(name)
    except (griffe.NameResolutionError, AttributeError):
        return name


def markdown_of_roles(obj, text):
    """``text`` with each Sphinx role replaced by an optional cross-reference to its target."""

    def replace(match):
        name = match["name"].strip()
        shown = name.rsplit(".", 1)[-1] if match["tilde"] else name
        identifier = html.escape(_target(obj, name), quote=True)
        return f'<autoref identifier="{identifier}" optional><code>{html.escape(shown)}</code></autoref>'

    return ROLE.sub(replace, text)


class SphinxRoles(griffe.Extension):
    """Rewrites the Sphinx roles of every docstring griffe loads for the site."""

    def on_object(self, *, obj, loader, **kwargs):
        if obj.docstring is not None and ":" in obj.docstring.value:
            obj.docstring.value = markdown_of_roles(obj, obj.docstring.value)
