"""The ``kingen`` command line: list, render, build, package, solve, verify, bench.

Exit codes: 0 success, 1 verification failed, 2 bad input or usage (one line on
stderr naming file, field and problem). Library code raises KingenError; only
this module prints and chooses exit codes.
"""

import contextlib
import json
import sys
from pathlib import Path

import click
import numpy as np

from . import __version__, abi
from .bench import benchmark
from .build import TARGETS, build_legacy, build_plugin, default_out_dir, write_atomic, write_source
from .conventions import t6_from_pose
from .errors import KingenError
from .host import Plugin
from .model import REVOLUTE, load_robot, shipped_robots
from .package import write_package
from .reference import solve as reference_solve
from .verify import chunk_size, junit_xml, verify as run_verify, verify_isolated

EXIT_FAILED = 1
EXIT_BAD_INPUT = 2

ROBOT = click.argument("robot", metavar="ROBOT")
OUT_DIR = click.option(
    "-o", "--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
    help="Output folder [default: build/<name>].",
)


def calibration_options(function):
    """--link-lengths / --link-offsets: the Solver Attributes fields Length 1-6 and Offset 1-6."""
    function = click.option("--link-offsets", nargs=6, type=float, default=None, metavar="O1 .. O6",
                            help="Offset 1-6 of the Solver Attributes tab (link_offsets[]).")(function)
    function = click.option("--link-lengths", nargs=6, type=float, default=None, metavar="L1 .. L6",
                            help="Length 1-6 of the Solver Attributes tab (link_lengths[]).")(function)
    return function


def plugin_options(function):
    """--plugin / --source / --routine: verify a hand-written routine instead of kingen's."""
    function = click.option("--routine", default=None,
                            help="Routine name in the library [default: kin_<name>].")(function)
    function = click.option("--source", type=click.Path(dir_okay=False, path_type=Path), default=None,
                            help="Compile this C source (a legacy plugin) against the stand-in header first.")(function)
    function = click.option("--plugin", "library", type=click.Path(dir_okay=False, path_type=Path), default=None,
                            help="Use this compiled library instead of building ROBOT's.")(function)
    return function


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="kingen")
def cli():
    """Robot YAML -> DELMIA V5 / IGRIP user-inverse-kinematics plugin, verified.

    ROBOT is a YAML path or the name of a shipped robot (see `kingen list`).
    """


@cli.command("list")
def list_robots():
    """The shipped robots with DOF, postures and limb models."""
    rows = [("robot", "dof", "postures", "limbs", "description")]
    for name in shipped_robots():
        robot = load_robot(name)
        counts = ", ".join(f"{sum(l.model == m for l in robot.limbs)} {m}" for m in robot.models)
        rows.append((name, str(robot.dof), str(robot.postures), counts, _shorten(robot.description, 60)))
    _print_table(rows)


@cli.command()
@ROBOT
@OUT_DIR
def render(robot, out_dir):
    """Write kin_<name>.c into the output folder."""
    model = load_robot(robot)
    path = write_source(model, out_dir or default_out_dir(model))
    click.echo(str(path))


@cli.command()
@ROBOT
@OUT_DIR
@click.option("--debug", is_flag=True, help="Compile with KINGEN_DEBUG (DELMIA-style printing; slow).")
@click.option("--target", type=click.Choice(TARGETS), default="linux", show_default=True,
              help="linux: lib<name>.so with $CC; windows: lib<name>.dll cross-compiled with mingw-w64.")
def build(robot, out_dir, debug, target):
    """Render and compile the plugin, host symbols left to the host, as for DELMIA."""
    model = load_robot(robot)
    result = build_plugin(model, out_dir, defines=("KINGEN_DEBUG",) if debug else (), target=target)
    state = "compiled" if result.compiled else "up to date"
    click.echo(f"{result.library} ({state}; routine {result.routine}, source {result.source})")


@cli.command()
@ROBOT
@OUT_DIR
@click.option("--target", type=click.Choice(TARGETS), default="windows", show_default=True,
              help="windows: source, nmake makefile, .def, BUILD.txt; linux: source and lib<name>.so.")
def package(robot, out_dir, target):
    """A folder ready for the simulator, with SETUP.md: what to type into each dialog tab."""
    model = load_robot(robot)
    paths = write_package(model, out_dir or default_out_dir(model) / f"package-{target}", target)
    for path in paths:
        click.echo(str(path))


@cli.command()
@ROBOT
@OUT_DIR
@click.option("--pose", nargs=6, type=float, metavar="X Y Z ROLL PITCH YAW",
              help="Platform pose: mm and degrees, R = Rz(yaw) Ry(pitch) Rx(roll).")
@click.option("--t6", nargs=16, type=float, metavar="16 NUMBERS",
              help="DELMIA's T6, row by row: n, o, a, p rows, each with its 0/1 last entry.")
@click.option("--degrees", is_flag=True, help="Show revolute joints in degrees (the plugin works in radians).")
@calibration_options
def solve(robot, out_dir, pose, t6, degrees, link_lengths, link_offsets):
    """Every posture's joints and warning from the plugin, with the reference's beside it."""
    if (pose is None) == (t6 is None):
        raise click.UsageError("give exactly one of --pose and --t6")
    model = load_robot(robot)
    matrix = t6_from_pose(np.asarray([pose])) if pose is not None else np.asarray(t6, dtype=float).reshape(1, 4, 4)
    plugin = _plugin(model, out_dir)
    calls = plugin.call(matrix, link_lengths, link_offsets)
    expected = reference_solve(model, matrix, link_lengths, link_offsets)
    scale = np.where(np.array(model.joint_types) == REVOLUTE, 180.0 / np.pi if degrees else 1.0, 1.0)
    units = ["deg" if (t == REVOLUTE and degrees) else ("rad" if t == REVOLUTE else "mm") for t in model.joint_types]
    names = [f"{name} ({unit})" for name, unit in zip(model.joint_names, units)]
    header = ["posture", "branches"] + names + ["warning", "| reference"] + names + ["warning"]
    rows = [header]
    digits = [bit for bit in model.branch_bits if bit >= 0]
    for k in range(model.postures):
        branches = "".join(str((k >> bit) & 1) for bit in digits) or "-"
        rows.append(
            [str(k), branches]
            + [f"{v:.9f}" for v in calls.solutions[0, :, k] * scale] + [_warning_name(calls.warnings[0, k]), "|"]
            + [f"{v:.9f}" for v in expected.joints[0, :, k] * scale] + [_warning_name(expected.warnings[0, k])]
        )
    _print_table(rows)
    click.echo(f"routine returned {calls.returned[0]}")


@cli.command()
@ROBOT
@OUT_DIR
@plugin_options
@click.option("--samples", type=click.IntRange(min=1), default=10000, show_default=True,
              help="Poses drawn in the robot's verification region.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the pose generator.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Write the report as JSON to this file.")
@click.option("--junit", "junit_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Write the report as JUnit XML (one test case per check) to this file.")
@calibration_options
def verify(robot, out_dir, library, source, routine, samples, seed, json_path, junit_path, link_lengths, link_offsets):
    """Compare a routine with the reference: exit 0 when all agree, 1 when not.

    By default builds ROBOT's plugin (if needed); --plugin or --source verify any routine
    that follows the DELMIA interface, hand-written ones included, in a child process so
    that a routine that crashes becomes a failed check.
    """
    model = load_robot(robot)
    plugin = _plugin(model, out_dir, library, source, routine)
    run = run_verify if library is None and source is None else verify_isolated
    with _progress(samples, chunk_size(model)) as progress:
        report = run(model, plugin, samples=samples, seed=seed, progress=progress,
                     link_lengths=link_lengths, link_offsets=link_offsets)
    _print_report(report, plugin)
    if json_path is not None:
        write_atomic(json_path, json.dumps(report.as_json(), indent=2) + "\n")
    if junit_path is not None:
        write_atomic(junit_path, junit_xml(report))
    return 0 if report.passed else EXIT_FAILED


@cli.command()
@ROBOT
@OUT_DIR
@plugin_options
@click.option("--calls", type=click.IntRange(min=1), default=200000, show_default=True,
              help="Routine calls per timing (the per-call path uses at most 20000).")
def bench(robot, out_dir, library, source, routine, calls):
    """Print ns per routine call (C batch driver, per-call cffi) and poses per second."""
    model = load_robot(robot)
    plugin = _plugin(model, out_dir, library, source, routine)
    figures = benchmark(model, plugin, calls=calls)
    click.echo(f"bench {model.name} ({plugin.routine}, {model.postures} postures, {calls} poses)")
    click.echo(f"  routine via C batch driver: {figures['batch_ns_per_call']:10.1f} ns/call")
    click.echo(f"  routine via cffi per call:  {figures['cffi_ns_per_call']:10.1f} ns/call")
    click.echo(f"  numpy reference:            {figures['reference_poses_per_second']:10,.0f} poses/s")
    click.echo(f"  verify (everything):        {figures['verify_poses_per_second']:10,.0f} poses/s")


def _plugin(model, out_dir, library=None, source=None, routine=None):
    """The Plugin to check: kingen's own build, a given library, or a compiled legacy source."""
    if library is not None and source is not None:
        raise click.UsageError("give at most one of --plugin and --source")
    if library is None and source is None:
        if routine is not None and routine != model.routine:
            raise click.UsageError(f"--routine needs --plugin or --source (kingen's routine is {model.routine})")
        result = build_plugin(model, out_dir)
        return Plugin(result.library, result.routine)
    if source is not None:
        library = build_legacy(source, out_dir or default_out_dir(model) / "legacy")
    return Plugin(library, routine or model.routine)


def _progress(total, chunk):
    """A progress bar on stderr for runs of several chunks at a terminal; otherwise nothing."""
    if total <= chunk or not sys.stderr.isatty():
        return contextlib.nullcontext(None)
    bar = click.progressbar(length=total, label="verifying", file=sys.stderr)

    @contextlib.contextmanager
    def running():
        with bar:
            yield lambda done: bar.update(done - bar.pos)

    return running()


def _print_report(report, plugin):
    click.echo(f"verify {report.robot}: {report.samples} poses x {report.postures} postures, "
               f"{plugin.path} ({report.routine})")
    for check in report.checks:
        click.echo(f"  {'ok' if check.passed else 'FAILED':6} {check.name}: {check.detail}")
        for diagnosis in check.diagnoses:
            click.echo(f"         diagnosis: {diagnosis}")
    for notice in report.notices:
        click.echo(f"  notice: {notice}")
    verdict = "PASSED" if report.passed else f"FAILED ({len(report.failures)} of {len(report.checks)} checks)"
    speed = f" in {report.seconds:.2f} s ({report.poses_per_second:,.0f} poses/s)" if report.seconds > 0 else ""
    click.echo(verdict + speed)


def _rounded(values):
    return [round(v, 6) for v in values]


def _warning_name(code):
    return abi.WARNING_NAMES.get(int(code), f"UNWRITTEN({code})")


def _shorten(text, width):
    text = " ".join(text.split())
    return text if len(text) <= width else text[: width - 3] + "..."


def _print_table(rows):
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    for row in rows:
        click.echo("  ".join(cell.ljust(width) for cell, width in zip(row, widths)).rstrip())


def main(argv=None):
    """Entry point: runs the CLI and maps errors to one stderr line and an exit code."""
    try:
        outcome = cli.main(args=argv, prog_name="kingen", standalone_mode=False)
    except KingenError as error:
        click.echo(f"kingen: error: {error}", err=True)
        return EXIT_BAD_INPUT
    except click.exceptions.NoArgsIsHelpError as error:
        click.echo(error.ctx.get_help())
        return 0
    except click.ClickException as error:
        click.echo(f"kingen: error: {error.format_message()}", err=True)
        return EXIT_BAD_INPUT
    except click.exceptions.Abort:
        click.echo("kingen: aborted", err=True)
        return 130
    except OSError as error:
        click.echo(f"kingen: error: {error.filename or ''}: {error.strerror or error}", err=True)
        return EXIT_BAD_INPUT
    return outcome if isinstance(outcome, int) else 0


if __name__ == "__main__":
    sys.exit(main())
