"""The ``kingen`` command line: list, render, build, package, solve, verify, bench.

Exit codes: 0 success, 1 verification failed (or the plugin broke, crashed or hung),
2 bad input or usage (one line on stderr naming file, field and problem), 3 internal
error (one line; the traceback only with ``KINGEN_DEBUG=1``), 143 terminated by
SIGTERM. Library code raises KingenError; only this module prints and chooses exit
codes. Plugin code (constructors, get_kin_config, routines) runs only in a child
process (:mod:`kingen.isolation`), bounded by ``--timeout``.
"""

import contextlib
import json
import math
import os
import signal
import sys
import traceback
from pathlib import Path

import click

from . import __version__, abi
from .defaults import DEFAULT_TIMEOUT, MAX_MM, MAX_PROCESSES, TARGETS
from .errors import InternalError, KingenError, PluginDefect
from .text import printable

EXIT_FAILED = 1
EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 3
EXIT_TERMINATED = 128 + signal.SIGTERM
MAX_BENCH_CALLS = 100_000_000

ROBOT = click.argument("robot", metavar="ROBOT")
OUT_DIR = click.option(
    "-o", "--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
    help="Output folder [default: build/<name>].",
)


def _dialog_fields(context, parameter, values):
    if values is not None and not all(math.isfinite(v) and abs(v) <= MAX_MM for v in values):
        raise click.BadParameter(f"each value must be finite and within +/-{MAX_MM:g} (mm or degrees)")
    return values


def _routine_name(context, parameter, value):
    if value is not None:
        try:
            from .host import check_routine_name

            check_routine_name(value)
        except KingenError as error:
            raise click.BadParameter(str(error)) from None
    return value


def _output_file(context, parameter, path):
    """Report paths are checked before the run, not after it."""
    if path is not None:
        folder = path.parent
        if path.is_dir():
            raise click.BadParameter(f"{path} is a folder")
        if not folder.is_dir():
            raise click.BadParameter(f"folder {folder} does not exist")
        if not os.access(folder, os.W_OK):
            raise click.BadParameter(f"folder {folder} is not writable")
    return path


TIMEOUT = click.option("--timeout", type=click.FloatRange(min=0.1, max=7 * 86400), default=DEFAULT_TIMEOUT,
                       envvar="KINGEN_TIMEOUT", show_default=True, metavar="SECONDS",
                       help="Longest a compiler run may take, and a plugin may go without progress, "
                            "before it is killed ($KINGEN_TIMEOUT).")


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
@click.version_option(__version__, prog_name="kingen")
def cli():
    """Robot YAML -> DELMIA V5 / IGRIP user-inverse-kinematics plugin, verified.

    ROBOT is a YAML path or the name of a shipped robot (see `kingen list`).
    """


@cli.command("list")
def list_robots():
    """The shipped robots with DOF, postures and limb models."""
    from .model import shipped_robots

    rows = [("robot", "dof", "postures", "limbs", "description")]
    for name in shipped_robots():
        robot = _robot(name)
        counts = ", ".join(f"{sum(l.model == m for l in robot.limbs)} {m}" for m in robot.models)
        rows.append((name, str(robot.dof), str(robot.postures), counts, _shorten(robot.description, 60)))
    _print_table(rows)


@cli.command()
@ROBOT
@OUT_DIR
def render(robot, out_dir):
    """Write kin_<name>.c into the output folder."""
    from .build import default_out_dir, write_source

    model = _robot(robot)
    path = write_source(model, out_dir or default_out_dir(model))
    _say(str(path))


@cli.command()
@ROBOT
@OUT_DIR
@click.option("--debug", is_flag=True, help="Compile with KINGEN_DEBUG (DELMIA-style printing; slow).")
@click.option("--target", type=click.Choice(TARGETS), default="linux", show_default=True,
              help="linux: lib<name>.so with $CC; windows: lib<name>.dll cross-compiled with mingw-w64.")
@TIMEOUT
def build(robot, out_dir, debug, target, timeout):
    """Render and compile the plugin, host symbols left to the host, as for DELMIA."""
    from .build import build_plugin

    model = _robot(robot)
    result = build_plugin(model, out_dir, defines=("KINGEN_DEBUG",) if debug else (), target=target, timeout=timeout)
    state = "compiled" if result.compiled else "up to date"
    _say(f"{result.library} ({state}; routine {result.routine}, source {result.source})")


@cli.command()
@ROBOT
@OUT_DIR
@click.option("--target", type=click.Choice(TARGETS), default="windows", show_default=True,
              help="windows: source, nmake makefile, .def, BUILD.txt; linux: source and lib<name>.so.")
@TIMEOUT
def package(robot, out_dir, target, timeout):
    """A folder ready for the simulator, with SETUP.md: what to type into each dialog tab.

    The folder is written whole or not at all; an existing folder is replaced only when
    kingen wrote it."""
    from .build import default_out_dir
    from .package import write_package

    model = _robot(robot)
    paths = write_package(model, out_dir or default_out_dir(model) / f"package-{target}", target, timeout=timeout)
    for path in paths:
        _say(str(path))


@cli.command()
@ROBOT
@OUT_DIR
@click.option("--pose", nargs=6, type=float, metavar="X Y Z ROLL PITCH YAW",
              help="Platform pose: mm and degrees, R = Rz(yaw) Ry(pitch) Rx(roll).")
@click.option("--t6", nargs=16, type=float, metavar="16 NUMBERS",
              help="DELMIA's T6, row by row: n, o, a, p rows, each with its 0/1 last entry.")
@click.option("--degrees", is_flag=True, help="Show revolute joints in degrees (the plugin works in radians).")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write every posture (joints in mm and rad, warnings, indices) as JSON.")
@click.option("--switch", nargs=2, type=click.IntRange(min=0), default=None, metavar="A B",
              help="Predict a switch from posture A to B: B's joints, their assembly modes and the TCP jump.")
@calibration_options
@TIMEOUT
def solve(robot, out_dir, pose, t6, degrees, json_path, switch, link_lengths, link_offsets, timeout):
    """Every posture's joints and warning from the plugin, with the reference's beside it."""
    import numpy as np

    from .build import write_atomic
    from .conventions import branch_of_posture, t6_from_pose
    from .reference import solve as reference_solve

    if (pose is None) == (t6 is None):
        raise click.UsageError("give exactly one of --pose and --t6")
    model = _robot(robot)
    matrix = t6_from_pose(np.asarray([pose])) if pose is not None else np.asarray(t6, dtype=float).reshape(1, 4, 4)
    library, routine = _library(model, out_dir, timeout=timeout)
    calls = _in_child(_solve_job, (library, routine, matrix, link_lengths, link_offsets), timeout)
    expected = reference_solve(model, matrix, link_lengths, link_offsets, indices=True)
    direct = expected.direct_index[0] if expected.direct_index is not None else [None] * model.postures
    inverse = float(expected.min_inverse_index[0])
    inverse_text = f"{inverse:.6g}" if math.isfinite(inverse) else "n/a"
    in_yaml_units = [t.wraps and degrees for t in model.joint_types]
    scale = np.array([1.0 / t.yaml_scale if yaml else 1.0 for t, yaml in zip(model.joint_types, in_yaml_units)])
    units = [t.yaml_unit if yaml else t.unit for t, yaml in zip(model.joint_types, in_yaml_units)]
    names = [f"{name} ({unit})" for name, unit in zip(model.joint_names, units)]
    header = (["posture", "branches"] + names + ["warning", "| reference"] + names
              + ["warning", "direct index (mm)", "min inverse index"])
    rows = [header]
    digits = [bit for bit in model.branch_bits if bit >= 0]
    for k in range(model.postures):
        branches = "".join(str(branch_of_posture(k, bit)) for bit in digits) or "-"
        rows.append(
            [str(k), branches]
            + [f"{v:.9f}" for v in calls.solutions[0, :, k] * scale] + [_warning_name(calls.warnings[0, k]), "|"]
            + [f"{v:.9f}" for v in expected.joints[0, :, k] * scale] + [_warning_name(expected.warnings[0, k])]
            + [_index_text(direct[k]), inverse_text]
        )
    _print_table(rows)
    _say(f"routine returned {calls.returned[0]}")
    _say(_indices_note(model))
    if switch is not None:
        _predict_switch(model, matrix[0], expected.joints[0], switch, scale, units)
    if json_path is not None:
        write_atomic(json_path, json.dumps(_finite({
            "robot": model.name, "routine": routine, "t6": matrix[0].tolist(), "returned": int(calls.returned[0]),
            "joint_units": [t.unit for t in model.joint_types], "direct_index_min_mm": model.direct_index_min,
            "postures": [{
                "posture": k, "joints": calls.solutions[0, :, k].tolist(), "warning": _warning_name(calls.warnings[0, k]),
                "reference_joints": expected.joints[0, :, k].tolist(),
                "reference_warning": _warning_name(expected.warnings[0, k]),
                "direct_index_mm": None if direct[k] is None else float(direct[k]),
                "min_inverse_index": inverse,
            } for k in range(model.postures)],
        }), indent=2, allow_nan=False) + "\n")
    if calls.faults[0]:
        _say(f"the routine {'; '.join(t for b, t in abi.GUARD_FAULTS.items() if calls.faults[0] & b)}")
        return EXIT_FAILED
    return 0


def _predict_switch(model, t6, joints, switch, scale, units):
    """What a host that recomputes the TCP from posture B's joints may do after A -> B."""
    import numpy as np

    from .conventions import pose_from_t6, wrap_angle
    from .forward import assemblies

    first, second = switch
    if max(first, second) >= model.postures:
        raise click.BadParameter(f"{model.name} has postures 0 to {model.postures - 1}", param_hint="--switch")
    if not model.has_forward:
        _say(f"switch {first} -> {second}: forward kinematics not available ({model.dof} limbs; declare forward.free)")
        return
    pose = pose_from_t6(t6)
    commanded = np.concatenate([pose[:3], np.radians(pose[3:])])
    change = joints[:, second] - joints[:, first]
    change = np.where(model.revolute, wrap_angle(change), change)
    moved = ", ".join(f"{name} {value * s:+.6f} {unit}" for name, value, s, unit in
                      zip(model.joint_names, change, scale, units))
    _say(f"switch {first} -> {second}: the joints move by {moved}")
    found = assemblies(model, joints[:, second], commanded)
    if not found:
        _say(f"  posture {second}'s joints admit no pose: the host cannot recompute the TCP")
        return
    for number, assembly in enumerate(found):
        distance = float(np.linalg.norm(assembly.pose[:3] - commanded[:3]))
        pose = ", ".join(f"{v:.3f}" for v in np.concatenate([assembly.pose[:3], np.degrees(assembly.pose[3:])]))
        _say(f"  assembly mode {number}: pose ({pose}), {distance:.3f} mm from the commanded TCP")
    worst = max(float(np.linalg.norm(a.pose[:3] - commanded[:3])) for a in found)
    _say(f"  a host that recomputes the TCP from posture {second}'s joints may jump up to {worst:.3f} mm "
         f"({len(found)} assembly modes)")


def _index_text(value):
    if value is None:
        return "n/a"
    return "unreachable" if not math.isfinite(value) else f"{value:.6g}"


def _indices_note(model):
    """What the index columns mean for this robot, in one line."""
    inverse = "min inverse index: the smallest normalised radicand D over the limbs (1 - 1/Inv_I; 0 at a limb singularity)"
    if not model.has_direct_index:
        return (f"direct index: not available ({model.dof} limbs: the constraints that complete the platform "
                f"are not modelled); {inverse}")
    threshold = (f"below {model.direct_index_min:g} mm the routine answers WARN_SINGULAR_SOLUTION"
                 if model.direct_index_min is not None else "no threshold set (singularity: direct_index_min)")
    return f"direct index: 0 at a direct (platform) singularity; {threshold}; {inverse}"


def _finite(data):
    if isinstance(data, float):
        return data if math.isfinite(data) else None
    if isinstance(data, dict):
        return {key: _finite(value) for key, value in data.items()}
    if isinstance(data, list):
        return [_finite(value) for value in data]
    return data


def _solve_job(channel, library, routine, matrix, link_lengths, link_offsets):
    from .host import Plugin

    plugin = Plugin(library, routine)
    channel.stage("the routine's call")
    return plugin.call(matrix, link_lengths, link_offsets)


@cli.command()
@ROBOT
@OUT_DIR
@plugin_options
@click.option("--samples", type=click.IntRange(min=1), default=10000, show_default=True,
              help="Poses drawn in the robot's verification region (memory does not grow with it).")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True, help="Seed of the pose generator.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write the report as JSON to this file (null: not a finite number).")
@click.option("--junit", "junit_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write the report as JUnit XML (one test case per check) to this file.")
@click.option("--golden", "snapshot_path", type=click.Path(dir_okay=False, exists=True, path_type=Path), default=None,
              help="Also check the routine against this recorded snapshot (kingen golden record).")
@click.option("--processes", type=click.IntRange(min=1, max=MAX_PROCESSES), default=None,
              help="Processes comparing the poses (the same report whatever the number)  "
                   "[default: one per core].")
@calibration_options
@TIMEOUT
def verify(robot, out_dir, library, source, routine, samples, seed, json_path, junit_path, snapshot_path, processes,
           link_lengths, link_offsets, timeout):
    """Compare a routine with the reference: exit 0 when all agree, 1 when not.

    By default builds ROBOT's plugin (if needed); --plugin or --source verify any routine
    that follows the DELMIA interface, hand-written ones included. Plugin code runs in a
    child process, so a routine that crashes, exits or hangs becomes a failed check.
    """
    from .build import write_atomic
    from .snapshot import load as load_snapshot
    from .verify import VerifyOptions, chunk_size, verify_library

    model = _robot(robot)
    snapshot = load_snapshot(snapshot_path, model) if snapshot_path is not None else None
    library, routine = _library(model, out_dir, library, source, routine, timeout)
    options = VerifyOptions(samples=samples, seed=seed, link_lengths=link_lengths, link_offsets=link_offsets,
                            timeout=timeout, snapshot=snapshot, processes=processes)
    with _progress(samples, chunk_size(model)) as progress:
        report = verify_library(model, library, routine, options, progress)
    _print_report(report, library)
    if json_path is not None:
        from .report import json_text

        write_atomic(json_path, json_text(report, options))
    if junit_path is not None:
        from .report import junit_xml

        write_atomic(junit_path, junit_xml(report))
    return 0 if report.passed else EXIT_FAILED


@cli.command()
@ROBOT
@OUT_DIR
@plugin_options
@click.option("--calls", type=click.IntRange(min=1, max=MAX_BENCH_CALLS), default=200000, show_default=True,
              help="Routine calls per timing (the per-call path uses at most 20000).")
@click.option("--floor", "floor_source", type=click.Path(dir_okay=False, exists=True, path_type=Path), default=None,
              help="A hand-written C routine for ROBOT (benchmarks/floors/): time it against the routine, "
                   "in turns, and print the ratio.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write the figures as JSON to this file.")
@TIMEOUT
def bench(robot, out_dir, library, source, routine, calls, floor_source, json_path, timeout):
    """Print ns per routine call (C batch driver, per-call cffi) and poses per second."""
    from .build import build_legacy, default_out_dir, write_atomic

    model = _robot(robot)
    library, routine = _library(model, out_dir, library, source, routine, timeout)
    floor = None
    if floor_source is not None:
        floor = build_legacy(floor_source, (out_dir or default_out_dir(model)) / "floor", timeout=timeout)
    figures = _in_child(_bench_job, (model, library, routine, calls, floor), timeout)
    _say(f"bench {model.name} ({routine}, {model.postures} postures, {figures['calls']} calls)")
    _say(f"  routine via C batch driver: {figures['batch_ns_per_call']:10.1f} ns/call")
    _say(f"  routine via cffi per call:  {figures['cffi_ns_per_call']:10.1f} ns/call")
    _say(f"  numpy reference:            {figures['reference_poses_per_second']:10,.0f} poses/s")
    _say(f"  verify (everything):        {figures['verify_poses_per_second']:10,.0f} poses/s "
         f"({_processes(figures['verify_processes'])})")
    if floor is not None:
        against = figures["against_floor"]
        _say(f"  against the floor {floor_source} ({against['rounds']} rounds in turns, ns/call):")
        for label in ("floor", "routine"):
            _say(f"    {label + ':':9} min {against[label]['min']:9.1f}, median {against[label]['median']:9.1f}")
        _say(f"    ratio:    min {against['ratio_min']:9.3f}, median {against['ratio_median']:9.3f}")
    if json_path is not None:
        write_atomic(json_path, json.dumps(figures, indent=2, allow_nan=False) + "\n")


@cli.command(context_settings={"ignore_unknown_options": True})
@ROBOT
@click.option("--joints", required=True, type=str, metavar="Q1 .. Qn",
              help="The joints, mm (prismatic) and degrees (revolute), space-separated in one argument "
                   "or as the remaining arguments.")
@click.argument("more_joints", nargs=-1, type=click.UNPROCESSED, metavar="")
@click.option("--near", nargs=6, type=float, default=None, metavar="X Y Z ROLL PITCH YAW",
              help="The pose to measure distances from and to take non-free coordinates from "
                   "[default: the verification home].")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write the assembly modes as JSON.")
def fk(robot, joints, more_joints, near, json_path):
    """Forward kinematics: every platform pose (assembly mode) the joints admit.

    Exit 0 with at least one pose, 1 when none is found (the best residual is shown)."""
    import numpy as np

    from .build import write_atomic
    from .forward import assemblies, best_residual

    model = _robot(robot)
    try:
        values = [float(v) for v in joints.replace(",", " ").split()] + [float(v) for v in more_joints]
    except ValueError:
        raise click.BadParameter("numbers expected", param_hint="--joints") from None
    if len(values) != model.dof or not all(math.isfinite(v) for v in values):
        raise click.BadParameter(f"{model.name} has {model.dof} joints; give {model.dof} finite numbers",
                                 param_hint="--joints")
    if not model.has_forward:
        raise KingenError(f"{model.path}: forward: forward kinematics needs free pose coordinates for a robot "
                          f"with {model.dof} limbs: declare them, for example forward: {{free: [x, y, z]}}")
    internal = np.array(values) * model.joint_scale()
    near_pose = np.array(near if near is not None else model.verification.home, dtype=float)
    near_internal = np.concatenate([near_pose[:3], np.radians(near_pose[3:])])
    found = assemblies(model, internal, near_internal)
    rows = [("mode", "x (mm)", "y (mm)", "z (mm)", "roll (deg)", "pitch (deg)", "yaw (deg)", "residual (mm)",
             "from near (mm)")]
    solutions = []
    for number, assembly in enumerate(found):
        pose = np.concatenate([assembly.pose[:3], np.degrees(assembly.pose[3:])])
        distance = float(np.linalg.norm(assembly.pose[:3] - near_internal[:3]))
        solutions.append({"pose": pose.tolist(), "residual_mm": assembly.residual_mm, "distance_from_near_mm": distance})
        rows.append((str(number), *(f"{v:.6f}" for v in pose), f"{assembly.residual_mm:.3g}", f"{distance:.3f}"))
    if json_path is not None:
        write_atomic(json_path, json.dumps({"robot": model.name, "joints": values, "solutions": solutions},
                                           indent=2, allow_nan=False) + "\n")
    if not found:
        _say(f"no pose found for these joints (best residual {best_residual(model, internal, near_internal):.3g} mm)")
        return EXIT_FAILED
    _print_table(rows)
    return 0


@cli.command()
@ROBOT
@click.option("--posture", type=click.IntRange(min=0), default=None,
              help="The posture (assembly mode) to analyse [default: the robot's working_posture].")
@click.option("-o", "--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder [default: build/<name>/analysis].")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Also write analysis.json to this file.")
def analyze(robot, posture, out_dir, json_path):
    """Tilt limits, sweeps and workspace slices of one posture: analysis.json, PNG figures
    and a self-contained report.html."""
    import time

    from .analysis import analyze as run_analysis
    from .build import default_out_dir, write_atomic
    from .figures import figures, report_html

    model = _robot(robot)
    if posture is not None and posture >= model.postures:
        raise click.BadParameter(f"{model.name} has postures 0 to {model.postures - 1}", param_hint="--posture")
    out_dir = out_dir or default_out_dir(model) / "analysis"
    start = time.perf_counter()
    with _steps(["tilt limits", "sweeps", "workspace slices", "figures"]) as step:
        analysis = run_analysis(model, posture, progress=step)
        step("figures")
        pngs = figures(analysis)
    seconds = time.perf_counter() - start
    text = json.dumps(_finite(analysis), indent=1, allow_nan=False) + "\n"
    outputs = {"analysis.json": text, **pngs, "report.html": report_html(model, analysis, pngs, seconds)}
    for name, data in outputs.items():
        write_atomic(out_dir / name, data)
    if json_path is not None:
        write_atomic(json_path, text)
    limits = analysis["tilt_limits"]
    about = {0: "X", 90: "Y", 180: "-X", 270: "-Y"}
    summary = ", ".join(f"about {about[int(row['azimuth_deg'])]} {row['max_tilt_deg']} deg ({row['cause']})"
                        for row in limits if int(row["azimuth_deg"]) in about)
    _say(f"analyze {model.name}, posture {analysis['posture']}: {summary}")
    for name in outputs:
        _say(str(out_dir / name))
    _say(f"in {seconds:.1f} s")


def _steps(names):
    """A progress bar over named steps on a terminal; a no-op callable otherwise."""
    if sys.stderr is None or not sys.stderr.isatty():
        return contextlib.nullcontext(lambda text: None)
    bar = click.progressbar(length=len(names), label="analysing", file=sys.stderr)

    @contextlib.contextmanager
    def running():
        with bar:
            yield lambda text: bar.update(1)

    return running()


@cli.group()
def golden():
    """Recorded snapshots of poses, joints and warnings (checked by verify --golden)."""


@golden.command("record")
@ROBOT
@plugin_options
@click.option("--samples", type=click.IntRange(min=1, max=100000), default=100, show_default=True,
              help="Poses to record.")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True, help="Seed of the poses.")
@click.option("-o", "--output", "output", type=click.Path(dir_okay=False, path_type=Path), required=True,
              callback=_output_file, help="The snapshot file to write (rewritten whole).")
@TIMEOUT
def golden_record(robot, library, source, routine, samples, seed, output, timeout):
    """Record a snapshot from the reference, or from a trusted plugin (--plugin/--source)."""
    from .build import write_atomic
    from .snapshot import record, sample_t6

    model = _robot(robot)
    t6 = sample_t6(model, samples, seed)
    if library is None and source is None:
        if routine is not None:
            raise click.UsageError("--routine needs --plugin or --source")
        from .reference import solve as reference_solve

        expected = reference_solve(model, t6)
        joints, warnings, recorded_from = expected.joints, expected.warnings, "the reference"
    else:
        library, routine = _library(model, None, library, source, routine, timeout)
        calls = _in_child(_solve_job, (library, routine, t6, None, None), timeout)
        joints, warnings, recorded_from = calls.solutions, calls.warnings, f"plugin {Path(library).name} ({routine})"
    write_atomic(output, record(model, t6, joints, warnings, recorded_from, samples, seed))
    _say(f"{output}: {samples} poses x {model.postures} postures recorded from {recorded_from}")


@cli.command()
@click.argument("library", type=click.Path(dir_okay=False, exists=True, path_type=Path))
def info(library):
    """What a compiled library says about itself (read from its bytes, never loaded)."""
    from .library_info import binary_format, build_info

    details = build_info(library)
    _say(f"library: {library}")
    _say(f"format: {binary_format(library)}")
    if details is None:
        _say("kingen build information: none (not built by kingen)")
        return 0
    _say(f"robot: {details.get('robot', '?')}")
    _say(f"routine: {details.get('routine', '?')}")
    _say(f"dof: {details.get('dof', '?')}, postures: {details.get('postures', '?')}")
    _say(f"definition sha256: {details.get('sha256', '?')}")
    _say(f"kingen version: {details.get('kingen', '?')}")
    return 0


def _bench_job(channel, model, library, routine, calls, floor):
    from .bench import ROUNDS, benchmark, compare
    from .host import Plugin
    from .isolation import keep_freed_memory

    keep_freed_memory()  # as verify's child does, so that its poses per second are verify's
    plugin = Plugin(library, routine)
    channel.stage("the timings")
    tick = lambda: channel.send("progress", None)  # noqa: E731
    figures = benchmark(model, plugin, calls=calls, tick=tick)
    if floor is not None:
        channel.stage("the timings against the floor")
        timings = compare(model, {"floor": Plugin(floor, model.routine), "routine": plugin}, calls=calls, tick=tick)
        figures["against_floor"] = {
            **timings, "rounds": ROUNDS,
            "ratio_min": timings["routine"]["min"] / timings["floor"]["min"],
            "ratio_median": timings["routine"]["median"] / timings["floor"]["median"],
        }
    return figures


def _in_child(job, arguments, timeout):
    """A job's result from a child process; a crash or a hang there is a failed run (exit 1)."""
    from .isolation import run_in_child

    result, failure = run_in_child(job, arguments, timeout)
    if failure is not None:
        raise PluginDefect(failure.detail)
    return result


def _library(model, out_dir, library=None, source=None, routine=None, timeout=DEFAULT_TIMEOUT):
    """(library path, routine) to check: kingen's own build, a given library, or a compiled legacy source."""
    from .build import build_legacy, build_plugin, default_out_dir

    if library is not None and source is not None:
        raise click.UsageError("give at most one of --plugin and --source")
    if library is None and source is None:
        if routine is not None and routine != model.routine:
            raise click.UsageError(f"--routine needs --plugin or --source (kingen's routine is {model.routine})")
        result = build_plugin(model, out_dir, timeout=timeout)
        return result.library, result.routine
    if source is not None:
        library = build_legacy(source, out_dir or default_out_dir(model) / "legacy", timeout=timeout)
    return library, routine or model.routine


def _robot(robot):
    """The validated robot named by a shipped name or a YAML path (see kingen.model). Every
    command that computes starts here, so numpy's floating-point warnings are turned off
    here too: kingen judges NaN and inf itself, and the warnings would only be noise."""
    import numpy as np

    from .model import load_robot

    np.seterr(all="ignore")
    return load_robot(robot)


def _progress(total, chunk):
    """A progress bar on stderr for runs of several chunks at a terminal; otherwise nothing."""
    if total <= chunk or sys.stderr is None or not sys.stderr.isatty():
        return contextlib.nullcontext(None)
    bar = click.progressbar(length=total, label="verifying", file=sys.stderr)

    @contextlib.contextmanager
    def running():
        with bar:
            yield lambda done: bar.update(done - bar.pos)

    return running()


def _print_report(report, library):
    _say(f"verify {report.robot}: {report.samples} poses x {report.postures} postures, {library} ({report.routine})")
    for check in report.checks:
        _say(f"  {'ok' if check.passed else 'FAILED':6} {check.name}: {check.detail}")
        for diagnosis in check.diagnoses:
            _say(f"         diagnosis: {diagnosis}")
    from .report import statistics_lines

    for line in statistics_lines(report):
        _say(f"  {line}")
    for notice in report.notices:
        _say(f"  notice: {notice}")
    verdict = "PASSED" if report.passed else f"FAILED ({len(report.failures)} of {len(report.checks)} checks)"
    speed = (f" in {report.seconds:.2f} s ({report.poses_per_second:,.0f} poses/s, {_processes(report.processes)})"
             if report.seconds > 0 else "")
    _say(verdict + speed)


def _processes(count):
    """'1 process', '2 processes': how many compared verify's poses."""
    return f"{count} process" if count == 1 else f"{count} processes"


def _warning_name(code):
    return abi.WARNING_NAMES.get(int(code), f"UNWRITTEN({code})")


def _shorten(text, width):
    text = " ".join(text.split())
    return text if len(text) <= width else text[: width - 3] + "..."


def _print_table(rows):
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    for row in rows:
        _say("  ".join(cell.ljust(width) for cell, width in zip(row, widths)).rstrip())


def _say(text, err=False):
    """Print one line on stdout (or stderr), unprintable characters escaped. A reader that
    went away (``| head``) or a closed stream ends the printing, not the command: its exit
    code still tells the verdict."""
    stream = sys.stderr if err else sys.stdout
    if stream is None:
        return
    try:
        click.echo(printable(text), file=stream)
    except (BrokenPipeError, ValueError, OSError):
        _detach(err)


def _detach(err):
    """Point a broken standard stream at /dev/null, so later writes and the final flush succeed."""
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 2 if err else 1)
    os.close(null)
    if err:
        sys.stderr = open(os.devnull, "w")
    else:
        sys.stdout = open(os.devnull, "w")


def _terminate(signal_number, frame):
    """SIGTERM: unwind (temporary files are removed, child processes killed), then exit 143."""
    raise SystemExit(EXIT_TERMINATED)


def main(argv=None):
    """Entry point: runs the CLI and maps every outcome to one stderr line and an exit code."""
    signal.signal(signal.SIGTERM, _terminate)
    try:
        outcome = cli.main(args=argv, prog_name="kingen", standalone_mode=False)
    except PluginDefect as error:
        _say(f"kingen: plugin failed: {error}", err=True)
        return EXIT_FAILED
    except KingenError as error:
        _say(f"kingen: error: {error}", err=True)
        return EXIT_BAD_INPUT
    except click.exceptions.NoArgsIsHelpError as error:
        _say(error.ctx.get_help())
        return 0
    except click.ClickException as error:
        _say(f"kingen: error: {' '.join(error.format_message().split())}", err=True)
        return EXIT_BAD_INPUT
    except click.exceptions.Abort:
        _say("kingen: aborted", err=True)
        return 130
    except KeyboardInterrupt:
        _say("kingen: interrupted", err=True)
        return 130
    except OSError as error:
        _say(f"kingen: error: {error.filename or ''}: {error.strerror or error}", err=True)
        return EXIT_BAD_INPUT
    except (Exception, InternalError) as error:
        if os.environ.get("KINGEN_DEBUG") == "1":
            raise
        where = traceback.extract_tb(error.__traceback__)[-1] if error.__traceback__ else None
        origin = f" at {os.path.basename(where.filename)}:{where.lineno}" if where else ""
        _say(f"kingen: internal error: {type(error).__name__}: {' '.join(str(error).split())}{origin}; "
             "please report this (with KINGEN_DEBUG=1 for the traceback)", err=True)
        return EXIT_INTERNAL
    return outcome if isinstance(outcome, int) else 0


if __name__ == "__main__":
    sys.exit(main())
