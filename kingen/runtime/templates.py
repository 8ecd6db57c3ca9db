"""Template environments: jinja2 environments for kingen's templates, one per kind of file
(C, Markdown, HTML, plain text) and templates folder, with jinja2's compiled templates kept
in kingen's cache (:class:`PrivateBytecodeCache`).

A template is found by the caller's ``partials`` function first (the limb models' partials,
handed in by :mod:`kingen.hosts.render`), then in the folder it is asked from (a host's
templates), then in the shared ``templates/``.
"""

import functools
import pickle

import jinja2

from ..defaults import VERSION
from ..errors import KingenError
from .files import atomic_file, cache_dir, private_file, private_folder, private_writes
from .resources import templates_dir
from .text import finalizer, markdown

TEMPLATE_KINDS = {".c.j2": "c", ".md.j2": "markdown", ".html.j2": "html"}
"""Which escaping (:func:`kingen.runtime.text.finalizer`) a template's substitutions get, by suffix
(HTML: jinja2's autoescape); every other template is plain text. Headers (``.h.j2``) hold no
user text and get none."""


class PrivateBytecodeCache(jinja2.BytecodeCache):
    """jinja2's compiled templates, kept in kingen's cache folder (``<cache>/<name>``, looked
    up at each use), so that a process renders without compiling its templates first (about
    50 ms a process). Compiled code is loaded only from a private folder's private files (as
    kingen.runtime.files.cached runs only what this user built) and written whole, private, or not
    at all: a cache that cannot be read or written costs the compilation, never the render."""

    def __init__(self, name):
        self.name = name

    def _path(self, bucket):
        return cache_dir() / self.name / f"{bucket.key}.jinja"

    def load_bytecode(self, bucket):
        path = self._path(bucket)
        try:
            for folder in (path.parent.parent, path.parent):
                private_folder(folder)
            private_file(path)
            with open(path, "rb") as stream:
                bucket.load_bytecode(stream)
        except FileNotFoundError:  # not compiled yet
            pass
        except (KingenError, OSError, EOFError, ValueError, pickle.UnpicklingError):  # not ours, or cut short
            bucket.reset()

    def dump_bytecode(self, bucket):
        path = self._path(bucket)
        try:
            private_folder(path.parent.parent)
            with private_writes(path.parent):
                private_folder(path.parent)
                with atomic_file(path) as stream:
                    bucket.write_bytecode(stream)
        except (KingenError, OSError):  # not ours, or not writable: the next process compiles again
            pass


@functools.lru_cache(maxsize=None)
def _environment(kind, folder, partials):
    folders = [str(folder)] if folder is not None else []
    loaders = [jinja2.FileSystemLoader([*folders, str(templates_dir())])]
    if partials is not None:
        loaders.insert(0, jinja2.FunctionLoader(partials))
    return jinja2.Environment(
        loader=jinja2.ChoiceLoader(loaders),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=kind == "html",
        finalize=finalizer(kind) if kind not in (None, "html") else None,
        bytecode_cache=PrivateBytecodeCache(f"templates-{VERSION}-{kind}"),  # compiled per settings
    )


def template(name, folder=None, partials=None):
    """The jinja2 template ``name`` from ``partials`` (a jinja2 FunctionLoader function:
    name -> (source, filename, uptodate) or None), ``folder`` (a host's templates) or the
    shared templates/, in the environment that escapes its substitutions for its kind of
    file (C, Markdown, HTML, plain text): strict undefined."""
    kind = None if name.endswith(".h.j2") else next(
        (kind for suffix, kind in TEMPLATE_KINDS.items() if name.endswith(suffix)), "plain")
    environment = _environment(kind, folder, partials)
    environment.filters["markdown"] = markdown
    return environment.get_template(name)
