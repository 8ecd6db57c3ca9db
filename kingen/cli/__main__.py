"""``python -m kingen.cli``: the command line."""

from . import run

run()
