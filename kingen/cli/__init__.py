"""The ``kingen`` command line: list, render, build, package, solve, verify, bench, fk, analyze,
optimize, golden, info, check-path, view. Commands live in :mod:`.routine_commands`, :mod:`.solve_commands` and
:mod:`.design_commands`; what
they share (options, the host and routine to use, printing) in :mod:`.common`.

Exit codes: 0 success, 1 verification failed (or the plugin broke, crashed or hung),
2 bad input or usage (one line on stderr naming file, field and problem), 3 internal
error (one line; the traceback only with ``KINGEN_DEBUG=1``), 143 terminated by
SIGTERM. Library code raises KingenError; only this package prints and chooses exit
codes. Foreign code (a library's constructors, its entry points, routines) runs only in a
child process (:mod:`kingen.runtime.isolation`), bounded by ``--timeout``.
"""

import gc
import os
import signal
import sys
import traceback

import click

from ..errors import InternalError, KingenError, PluginDefect
from . import (calibrate_commands, design_commands, loads_commands, path_commands, routine_commands,  # noqa: F401
               solve_commands, view_commands)  # (they register the commands)
from .common import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_INTERNAL, cli, say

EXIT_TERMINATED = 128 + signal.SIGTERM
GC_FIRST_THRESHOLD = 50_000
"""Allocations between the garbage collector's youngest collections in the ``kingen``
executable (Python's default: 700). A command's imports and schema create some 10^5
long-lived objects and almost no garbage; kingen's large data are numpy arrays, which the
collector does not track."""


def _terminate(signal_number, frame):
    """SIGTERM: unwind (temporary files are removed, child processes killed), then exit 143."""
    raise SystemExit(EXIT_TERMINATED)


def run():
    """The ``kingen`` executable (and ``python -m kingen.cli``): main() in a process that ends
    with it. The garbage collector's youngest generation is collected every GC_FIRST_THRESHOLD
    allocations instead of 700, and what the command leaves is frozen (gc.freeze) before the
    interpreter exits, whose final collections would otherwise walk every object again:
    together 0.14 s of the 0.62 s ``kingen verify hexapod --samples 1000`` took (median of 15,
    measured). In-process callers (tests) use main(), which changes neither."""
    gc.set_threshold(GC_FIRST_THRESHOLD, *gc.get_threshold()[1:])
    status = main()
    gc.freeze()
    sys.exit(status)


def main(argv=None):
    """Entry point: runs the CLI and maps every outcome to one stderr line and an exit code."""
    signal.signal(signal.SIGTERM, _terminate)
    try:
        outcome = cli.main(args=argv, prog_name="kingen", standalone_mode=False)
    except PluginDefect as error:
        say(f"kingen: plugin failed: {error}", err=True)
        return EXIT_FAILED
    except KingenError as error:
        say(f"kingen: error: {error}", err=True)
        return EXIT_BAD_INPUT
    except click.exceptions.NoArgsIsHelpError as error:
        for line in error.ctx.get_help().splitlines():
            say(line)
        return 0
    except click.ClickException as error:
        say(f"kingen: error: {' '.join(error.format_message().split())}", err=True)
        return EXIT_BAD_INPUT
    except click.exceptions.Abort:
        say("kingen: aborted", err=True)
        return 130
    except KeyboardInterrupt:
        say("kingen: interrupted", err=True)
        return 130
    except OSError as error:
        say(f"kingen: error: {error.filename or ''}: {error.strerror or error}", err=True)
        return EXIT_BAD_INPUT
    except (Exception, InternalError) as error:
        if os.environ.get("KINGEN_DEBUG") == "1":
            raise
        where = traceback.extract_tb(error.__traceback__)[-1] if error.__traceback__ else None
        origin = f" at {os.path.basename(where.filename)}:{where.lineno}" if where else ""
        say(f"kingen: internal error: {type(error).__name__}: {' '.join(str(error).split())}{origin}; "
             "please report this (with KINGEN_DEBUG=1 for the traceback)", err=True)
        return EXIT_INTERNAL
    return outcome if isinstance(outcome, int) else 0

