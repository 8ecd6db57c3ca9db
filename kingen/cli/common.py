"""What the command modules share: the ``kingen`` group, options, finding the robot, the host
and the routine to check, running foreign code in a child process, and printing."""

import functools
import math
import os
import shutil
import sys
import textwrap
from pathlib import Path

import click

from ..defaults import DEFAULT_HOST, DEFAULT_TIMEOUT, MAX_MM, VERSION
from ..errors import KingenError, PluginDefect
from ..runtime.file_gate import refuse_special_file
from ..runtime.text import counted, printable

EXIT_FAILED = 1
EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 3

ROBOT = click.argument("robot", metavar="ROBOT")


class FiniteRange(click.FloatRange):
    """A float option within [min, max] that is a finite number: click.FloatRange lets NaN
    through (it compares false with every bound). Every ranged float option of kingen uses it."""

    name = "finite float range"

    def convert(self, value, param, ctx):
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return number


def _checked(check, value):
    """``value`` after ``check(value)`` (skipped for None); its KingenError as click's BadParameter."""
    if value is not None:
        try:
            check(value)
        except KingenError as error:
            raise click.BadParameter(str(error)) from None
    return value


def _out_folder(context, parameter, path):
    """An output folder is checked before the work, not after it: it, or the existing folder
    it would be made in, must be a writable folder."""
    from ..runtime.files import writable_folder

    return _checked(writable_folder, path)


OUT_DIR = click.option(
    "-o", "--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None, callback=_out_folder,
    help="Output folder [default: build/<name>].",
)


def _dialog_fields(context, parameter, values):
    if values is not None and not all(math.isfinite(v) and abs(v) <= MAX_MM for v in values):
        raise click.BadParameter(f"each value must be finite and within +/-{MAX_MM:g} (mm or degrees)")
    return values


def _routine_name(context, parameter, value):
    """A ``--routine`` that is a C identifier (it is looked up as a symbol)."""
    from ..kinematics.routine import check_routine_name

    return _checked(check_routine_name, value)


def _pose(context, parameter, values):
    """A pose option: six finite numbers, x y z within +/-MAX_MM mm, angles within +/-720 degrees."""
    from ..robot.schema import MAX_DEGREES

    if values is not None and not (all(math.isfinite(v) for v in values) and all(abs(v) <= MAX_MM for v in values[:3])
                                   and all(abs(v) <= MAX_DEGREES for v in values[3:])):
        raise click.BadParameter(f"x y z must be finite and within +/-{MAX_MM:g} mm, angles within "
                                 f"+/-{MAX_DEGREES:g} degrees")
    return values


RIGID = 1e-6
"""How far T6's rotation may be from orthonormal (largest entry of |R^T R - I|) to be taken as one."""


def _t6(context, parameter, values):
    """A T6 option: 16 finite numbers, rows n, o, a, p each ending in 0, 0, 0, 1, position
    within +/-MAX_MM mm, and n, o, a a right-handed orthonormal frame (a rigid transform)."""
    if values is None:
        return values
    import numpy as np

    matrix = np.asarray(values, dtype=float).reshape(4, 4)
    if not np.all(np.isfinite(matrix)):
        raise click.BadParameter("16 finite numbers expected")
    if not np.array_equal(matrix[:, 3], [0.0, 0.0, 0.0, 1.0]):
        raise click.BadParameter("each row n, o, a, p ends in its 0/1 entry: 0 0 0 1")
    if np.max(np.abs(matrix[3, :3])) > MAX_MM:
        raise click.BadParameter(f"the position p must be within +/-{MAX_MM:g} mm")
    rotation = matrix[:3, :3]
    miss = float(np.max(np.abs(rotation @ rotation.T - np.eye(3))))
    if miss > RIGID or np.linalg.det(rotation) < 0:
        raise click.BadParameter(f"not a rigid transform: rows n, o, a are not a right-handed orthonormal frame "
                                 f"(largest |R R^T - I| entry {miss:.3g}, determinant {np.linalg.det(rotation):.3g})")
    return values


def _output_file(context, parameter, path):
    """Report paths are checked before the run, not after it: a folder that exists and may be
    written, or an existing file that is not a regular one (/dev/stdout, a FIFO) and may be
    written in place; a symbolic link is judged by its target, and refused when another user
    owns it (kingen.runtime.files.refuse_foreign)."""
    from ..runtime.files import refuse_foreign

    if path is not None:
        _checked(refuse_foreign, path)
        if path.is_dir():
            raise click.BadParameter(f"{path} is a folder")
        if path.exists() and not path.is_file():
            if not os.access(path, os.W_OK):
                raise click.BadParameter(f"{path} is not writable")
            return path
        target = Path(os.path.realpath(path)) if path.is_symlink() else path
        folder = target.parent
        if not folder.is_dir():
            raise click.BadParameter(f"folder {folder} does not exist")
        if not os.access(folder, os.W_OK):
            raise click.BadParameter(f"folder {folder} is not writable")
    return path


TIMEOUT = click.option("--timeout", type=FiniteRange(min=0.1, max=7 * 86400), default=DEFAULT_TIMEOUT,
                       envvar="KINGEN_TIMEOUT", show_envvar=True, show_default=True, metavar="SECONDS",
                       help="Longest a compiler run may take, and a plugin may go without progress, "
                            "before it is killed.")
def HOST(function):
    """--host NAME with the host settings --units and --setp: the command gets ``host``, the
    registered host so configured (kingen.hosts; an unknown one is bad input, exit 2)."""
    @functools.wraps(function)
    def with_host(*args, host_name, units, setp, **kwargs):
        from ..hosts import get_host

        return function(*args, host=get_host(host_name).configured(units=units, setp=setp), **kwargs)

    with_host = click.option("--setp", "setp", multiple=True, metavar="NAME=VALUE", callback=_setp,
                             help="Set a pin or parameter of the loaded module (linuxcnc), as halcmd setp.")(with_host)
    with_host = click.option("--units", type=click.Choice(["mm", "inch"]), default=None,
                             help="The machine's LINEAR_UNITS (linuxcnc) [default: the robot file's units; mm for a file in metres].")(with_host)
    return click.option("--host", "host_name", default=DEFAULT_HOST, show_default=True, metavar="NAME",
                        cls=HostOption)(with_host)


class HostOption(click.Option):
    """--host, its help naming every registered host (kingen.hosts), read when help is shown:
    importing the hosts is left to the commands that use one."""

    def get_help_record(self, context):
        from ..hosts import HOSTS

        self.help = ("The host the routine is for, one of: "
                     + "; ".join(f"{name}, {host.description}" for name, host in HOSTS.items()) + ".")
        return super().get_help_record(context)


def _setp(context, parameter, values):
    settings = []
    for value in values:
        name, equals, number = value.partition("=")
        try:
            settings.append((name, float(number)))
        except ValueError:
            raise click.BadParameter(f"{value!r}: give NAME=VALUE with a number") from None
        if not equals or not name or not math.isfinite(settings[-1][1]):
            raise click.BadParameter(f"{value!r}: give NAME=VALUE with a finite number")
    return tuple(settings)


def calibration_options(function):
    """--link-lengths / --link-offsets: the Solver Attributes fields Length 1-6 and Offset 1-6."""
    function = click.option("--link-offsets", nargs=6, type=float, default=None, metavar="O1 .. O6",
                            callback=_dialog_fields,
                            help="Offset 1-6 of the Solver Attributes tab (link_offsets[]).")(function)
    function = click.option("--link-lengths", nargs=6, type=float, default=None, metavar="L1 .. L6",
                            callback=_dialog_fields,
                            help="Length 1-6 of the Solver Attributes tab (link_lengths[]).")(function)
    return function


def plugin_options(function):
    """--plugin / --source / --routine: verify a hand-written routine instead of kingen's."""
    function = click.option("--routine", default=None, callback=_routine_name,
                            help="Routine name in the library [default: kin_<name>].")(function)
    function = click.option("--source", type=click.Path(dir_okay=False, path_type=Path), default=None,
                            help="Compile this C source (a legacy plugin) against the stand-in header first.")(function)
    function = click.option("--plugin", "library", type=click.Path(dir_okay=False, path_type=Path), default=None,
                            help="Use this compiled library instead of building ROBOT's.")(function)
    return function


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(VERSION, prog_name="kingen")
def cli():
    """Robot YAML -> verified inverse-kinematics routines for DELMIA V5 / IGRIP, LinuxCNC and
    your own controller (a C library), with forward kinematics, analysis, design optimisation,
    calibration from measurements and path checking.

    ROBOT is a YAML path or the name of a shipped robot (see `kingen list`).
    """


def host_target(host, target, command):
    """The ``--target`` for ``host``: as given, or the host's default for ``command``; a
    target the host does not know is a usage error."""
    source = click.get_current_context().get_parameter_source("target")
    if source is click.core.ParameterSource.DEFAULT:
        return host.default_targets.get(command)
    if target not in host.targets:
        known = ", ".join(host.targets) or "none"
        raise click.BadParameter(f"host {host.name} has no target {target} (targets: {known})", param_hint="--target")
    return target


def in_child(job, arguments, timeout, host, decoders, on_message=None):
    """A job's result from a child process; a crash or a hang there, or a message that is not
    what ``decoders`` (kind -> decoder, 'result' included: kingen.runtime.isolation.run_in_child) accept,
    is a failed run (exit 1). ``on_message(kind, value)`` gets what the job sends besides
    stages, decoded, as it comes."""
    from ..runtime.isolation import run_in_child

    host.prepare_load()
    result, failure = run_in_child(job, arguments, timeout, on_message, first_stage=host.loading_stage,
                                   decoders=decoders)
    if failure is not None:
        raise PluginDefect(failure.detail)
    return result


def refuse_special_files(*paths):
    """Each given file (None: not given) that is a FIFO, device or folder refused before
    anything opens it (kingen.runtime.file_gate.refuse_special_file), in the order given."""
    for path in paths:
        if path is not None:
            refuse_special_file(path)


def routine_to_check(model, host, out_dir, library=None, source=None, routine=None, timeout=DEFAULT_TIMEOUT):
    """(library path, routine) to check: kingen's own build for ``host``, a given library, or
    a compiled hand-written source. A given file that is a FIFO, device or folder is refused
    before anything opens it."""
    if library is not None and source is not None:
        raise click.UsageError("give at most one of --plugin and --source")
    refuse_special_files(library, source)
    own = host.routine_name(model)
    if library is None and source is None:
        if routine is not None and routine != own:
            raise click.UsageError(f"--routine needs --plugin or --source (kingen's routine is {own})")
        result = host.build(model, out_dir, timeout=timeout)
        return result.library, result.routine
    if source is not None:
        library = host.build_source(source, out_dir or host.out_dir(model) / "legacy", timeout=timeout)
    return library, routine or own


def solve_job(channel, host, model, library, routine, matrix, link_lengths, link_offsets):
    """In a child process: the routine's Calls on ``matrix`` (n, 4, 4)."""
    plugin = host.load(library, routine, model)
    channel.stage("the routine's call")
    return plugin.call(matrix, link_lengths, link_offsets)


def load_model(robot):
    """The validated robot named by a shipped name or a YAML path (see kingen.robot.model). Every
    command that computes starts here, so numpy's floating-point warnings are turned off
    here too: kingen judges NaN and inf itself, and the warnings would only be noise."""
    return load_model_and_data(robot)[0]


def load_model_and_data(robot):
    """(model, data, lines): load_model's robot with the plain data and field lines of its
    file, read once (kingen.robot.model.load_robot_and_data)."""
    import numpy as np

    from ..robot.model import load_robot_and_data

    np.seterr(all="ignore")
    return load_robot_and_data(robot)


def finite(data):
    if isinstance(data, float):
        return data if math.isfinite(data) else None
    if isinstance(data, dict):
        return {key: finite(value) for key, value in data.items()}
    if isinstance(data, list):
        return [finite(value) for value in data]
    return data


def processes_text(count):
    """'1 process', '2 processes': how many compared verify's poses."""
    return counted(count, "process", "processes")


def output_width():
    """The columns that solve and verify fit their lines to: $COLUMNS when it is a positive
    number, the terminal's width when stdout is a terminal, else None (no limit: a pipe or a
    file gets the full lines, as scripts always saw them)."""
    columns = os.environ.get("COLUMNS", "").strip()
    if columns.isdigit() and int(columns) > 0:
        return int(columns)
    if sys.stdout is not None and sys.stdout.isatty():
        return shutil.get_terminal_size().columns
    return None


def table_lines(rows, width=None):
    """The table's lines, columns two spaces apart. When a line would be wider than ``width``
    the columns wrap: blocks of as many columns as fit, each led by the first column again
    and separated by an empty line (a single column wider than ``width`` stays whole)."""
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    blocks = [list(range(len(widths)))]
    if width is not None and sum(widths) + 2 * (len(widths) - 1) > width:
        blocks = [[0]]
        for column in range(1, len(widths)):
            used = sum(widths[i] + 2 for i in blocks[-1])
            if len(blocks[-1]) > 1 and used + widths[column] > width:
                blocks.append([0])
            blocks[-1].append(column)
    lines = []
    for block in blocks:
        lines += [""] if lines else []
        lines += ["  ".join(row[i].ljust(widths[i]) for i in block).rstrip() for row in rows]
    return lines


def print_table(rows, width=None):
    """Print ``rows`` (lists of strings, the header first) as table_lines(rows, width)."""
    for line in table_lines(rows, width):
        say(line)


def say_fitted(text, width, indent="  "):
    """Print ``text`` wrapped to ``width`` columns (None: one line), continuation lines
    indented by ``indent``; the first words stay on the first line, words (paths) never split."""
    if width is None:
        say(text)
        return
    for line in textwrap.wrap(text, width, subsequent_indent=indent, break_long_words=False,
                              break_on_hyphens=False) or [""]:
        say(line)


def say(text, err=False):
    """Print one line on stdout (or stderr), unprintable characters escaped. A reader that
    went away (``| head``) or a closed stream ends the printing, not the command: its exit
    code still tells the verdict."""
    stream = sys.stderr if err else sys.stdout
    if stream is None:
        return
    try:
        click.echo(printable(text), file=stream)
    except (BrokenPipeError, ValueError, OSError):
        detach(err)


def detach(err):
    """Point a broken standard stream at /dev/null, so later writes and the final flush succeed."""
    from ..runtime.isolation import to_devnull

    to_devnull(2 if err else 1)
    if err:
        sys.stderr = open(os.devnull, "w")
    else:
        sys.stdout = open(os.devnull, "w")
