"""The command that checks a program before the machine runs it: check-path (a G-code file read
by LinuxCNC's own interpreter, or a CSV of poses, along its whole path)."""

import contextlib
import json
import math
import sys
from pathlib import Path

import click

from ..defaults import INTERPRETER_SECONDS, MAX_SAMPLES
from ..errors import KingenError
from .common import (EXIT_FAILED, OUT_DIR, ROBOT, TIMEOUT, FiniteRange, _output_file, cli, finite, load_model,
                     print_table, refuse_special_files, say)


class _Numbers(click.Option):
    """An option followed by three to six numbers (``--offset X Y Z [A B C]``): it takes the
    numbers that follow it, up to six, as one value."""

    def add_to_parser(self, parser, ctx):
        super().add_to_parser(parser, ctx)
        option = parser._long_opt.get(self.opts[0])
        original = option.process

        def process(value, state):
            values = [value]
            while state.rargs and len(values) < 6 and _is_number(state.rargs[0]):
                values.append(state.rargs.pop(0))
            original(" ".join(values), state)
        option.process = process
        return None


def _is_number(text):
    try:
        float(text)
    except ValueError:
        return False
    return True


def _offset(context, parameter, value):
    """The --offset numbers as a tuple of six (x y z mm, a b c degrees; a b c 0 when not given)."""
    if value is None:
        return None
    numbers = value.split()
    if not 3 <= len(numbers) <= 6 or not all(_is_number(number) for number in numbers):
        raise click.BadParameter(f"{value!r}: three to six numbers expected (X Y Z [A B C])", param_hint="'--offset'")
    offset = tuple(float(number) for number in numbers) + (0.0,) * (6 - len(numbers))
    if not all(math.isfinite(number) for number in offset):
        raise click.BadParameter(f"{value!r}: finite numbers expected", param_hint="'--offset'")
    return offset


@cli.command("check-path")
@ROBOT
@click.argument("program", metavar="PROGRAM", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--host", "host_name", type=click.Choice(["linuxcnc", "delmia"]), default="linuxcnc",
              show_default=True, help="Whose interpolation to follow between the points: linuxcnc (X Y Z A B C "
                                      "linear together), delmia (the orientation about one fixed axis).")
@click.option("--posture", type=click.IntRange(min=0), default=None,
              help="The posture the machine runs in [default: the robot file's working_posture].")
@click.option("--chord", type=FiniteRange(min=1e-4, max=1000.0), default=0.1, show_default=True, metavar="MM",
              help="Largest distance between regular samples, mm (and degrees of orientation).")
@click.option("--ini", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="A LinuxCNC .ini, read as LinuxCNC reads it: its [JOINT_n] MIN_LIMIT, MAX_LIMIT, MAX_VELOCITY, "
                   "MAX_ACCELERATION and [TRAJ] speed and acceleration are judged too; G-code is read in its [TRAJ] "
                   "LINEAR_UNITS with its [EMCIO] TOOL_TABLE, [RS274NGC] PARAMETER_FILE and SUBROUTINE_PATH.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write the report as JSON to this file.")
@click.option("--html", "html_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write an HTML page with the joints along the program to this file.")
@click.option("--csv", "csv_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write every sample (pose, joints, speeds, accelerations) to this CSV file.")
@click.option("--routine", "use_routine", is_flag=True, default=False,
              help="Solve the regular samples' joints by the robot's routine compiled for --host, through the host's "
                   "batch driver in a child process (the numpy reference still gives the singularity quantities, "
                   "the clearances and the refined samples), and report how it agreed with the reference.")
@click.option("--task-only", is_flag=True, default=False,
              help="A machine with task coordinates, CSV program: read each row's task coordinates and let the "
                   "parasitic ones follow (a row off the machine's manifold is a notice, not a failure).")
@click.option("--offset", cls=_Numbers, callback=_offset, default=None, metavar="X Y Z [A B C]",
              help="G-code: where the part is: the work offset of the coordinate system the program starts in (mm, "
                   "degrees), in place of the .ini's parameter file's [default: the parameter file's, else none].")
@click.option("--interpreter-seconds", type=FiniteRange(min=1.0, max=86400.0), default=INTERPRETER_SECONDS, show_default=True,
              metavar="S", help="G-code: CPU seconds LinuxCNC's interpreter may take to read the program (an endless "
                                "loop ends here, bad input at the line reached).")
@click.option("--max-samples", type=click.IntRange(min=1), default=MAX_SAMPLES, show_default=True, metavar="N",
              help="Regular samples the program may ask for at --chord (more is bad input at the line that asks).")
@OUT_DIR
@TIMEOUT
def check_path(robot, program, host_name, posture, chord, ini, json_path, html_path, csv_path, use_routine, task_only,
               offset, interpreter_seconds, max_samples, out_dir, timeout):
    """Will PROGRAM run on ROBOT? PROGRAM is a G-code file (.ngc, .nc, .gcode), read by LinuxCNC's
    own interpreter, or a CSV of poses (x, y, z, roll, pitch, yaw in mm and degrees; optional t
    in s or feed in mm/min). The path between the points is sampled at most --chord apart and
    refined until no boundary can hide between two samples; each sample is checked for reach,
    joint travel, the limb singular band, the direct index, a change of assembly mode, collisions
    between links (where the robot file gives radii), and the joint speed and acceleration its
    feed asks for (a G-code program timed as LinuxCNC's trajectory planner moves it: G61, G61.1,
    G64 with its blend arcs, look-ahead, the .ini's axis limits; a CSV's rows from rest to rest).

    A machine with task coordinates (robot file ``task``) is followed along its manifold: each
    sample is the machine's pose at its task coordinates (the G-code words its LinuxCNC module
    reads), its parasitic ones computed; a CSV row off the manifold fails unless --task-only.

    A machine with a wrist (robot file ``wrist``): a G-code program commands X Y Z (the tool tip)
    and A, C (the tool axis) as its LinuxCNC five-axis module reads them (B and the turn about the
    tool axis not read); a CSV gives tool poses. A three-axis wrist reads the whole tool pose: G-code
    X Y Z A B C are the tool tip and its roll, pitch, yaw, as for a hexapod. The wrist's joints are
    judged with the legs'.

    A G-code program is read by LinuxCNC's interpreter with the .ini's tool table ([EMCIO]
    TOOL_TABLE; without one, tools 1 to 999 at no offset) and work offsets ([RS274NGC]
    PARAMETER_FILE, or --offset); every motion it emits is followed: traverses, feeds, arcs and
    full circles, probes (to their programmed end), rigid taps (down and back), the moves of canned
    and lathe cycles, cutter compensation and subroutines, with the tool length offset applied.

    Prints a one-line verdict and the problems by line. Exit 0 when the program runs within
    every limit judged, 1 when not or when nothing was judged, 2 bad input (an error LinuxCNC's
    interpreter raises included)."""
    from ..paths.check import Settings, check_program
    from ..paths.program import is_gcode
    from ..paths.report import problem_rows, reading_line, report_json, runs, verdict_line
    from ..runtime.files import write_atomic

    model = load_model(robot)
    if posture is not None and posture >= model.postures:
        raise click.BadParameter(f"{posture}: {model.name} has postures 0 .. {model.postures - 1}",
                                 param_hint="'--posture'")
    if task_only and not model.task:
        raise click.BadParameter(f"{model.name} has no task coordinates (robot file task)", param_hint="'--task-only'")
    refuse_special_files(program, ini)
    for given in (program, ini):
        if given is not None and not given.is_file():
            raise KingenError(f"{given}: no such file")
    settings = Settings(host=host_name, posture=posture, chord=chord, ini=ini, routine=use_routine,
                        out_dir=out_dir, timeout=timeout, task_only=task_only, offset=offset,
                        interpreter_seconds=interpreter_seconds, max_samples=max_samples)
    with contextlib.ExitStack() as stack:
        sink = _csv_sink(stack, csv_path, model) if csv_path is not None else None
        progress = stack.enter_context(_progress())
        outcome = check_program(model, program, settings, sink=sink, progress=progress)
    document = report_json(outcome)
    if json_path is not None:
        write_atomic(json_path, json.dumps(finite(_plain(document)), indent=1, allow_nan=False) + "\n")
    if html_path is not None:
        from ..paths.page import page_html
        from .report_views import path_view

        write_atomic(html_path, page_html(outcome, document, path_view(outcome)))
    say(verdict_line(outcome))
    if outcome.reading is not None:
        say(f"  {reading_line(outcome)}")
    for line in outcome.manifold.lines() if outcome.manifold is not None else ():
        say(f"  {line}")
    if outcome.five_axis is not None:
        say(f"  {outcome.five_axis.line(is_gcode(program), outcome.findings.peaks, model.joint_names)}")
    rows = problem_rows(outcome)
    if len(rows) > 1:
        print_table(rows)
    for kind, verdict in document["checks"].items():
        if verdict.startswith("not exercised"):
            say(f"  {kind}: {verdict}")
    return 0 if runs(outcome) else EXIT_FAILED


def _csv_sink(stack, csv_path, model):
    """A sink that streams every sample to ``csv_path`` (written whole when ``stack`` closes
    normally, not at all otherwise), its header written."""
    import numpy as np

    from ..paths.report import csv_header, csv_rows
    from ..runtime.files import atomic_file

    stream = stack.enter_context(atomic_file(csv_path))
    stream.write(csv_header(model).encode())
    scale = np.where(model.revolute, 180.0 / np.pi, 1.0)

    def sink(lines, batch, rates):
        stream.write(csv_rows(lines, batch, rates, scale).encode())
    return sink


def _plain(data):
    """``data`` with numpy scalars as Python numbers (for JSON)."""
    if isinstance(data, dict):
        return {key: _plain(value) for key, value in data.items()}
    if isinstance(data, (list, tuple)):
        return [_plain(value) for value in data]
    if hasattr(data, "item"):
        return data.item()
    return data


@contextlib.contextmanager
def _progress():
    """On a terminal, a line counting the moves and samples checked; a no-op otherwise."""
    if sys.stderr is None or not sys.stderr.isatty():
        yield None
        return

    def show(findings):
        click.echo(f"\rchecking: {findings.moves} moves, {findings.samples} samples", nl=False, err=True)

    try:
        yield show
    finally:
        click.echo("\r\033[K", nl=False, err=True)
