"""The commands that compute from the robot file itself: list, solve (a routine beside the
reference), fk (forward kinematics) and analyze (tilt limits, sweeps, workspace slices)."""

import contextlib
import json
import math
import sys
from pathlib import Path

import click

from ..defaults import AZIMUTH_STEP_DEG, TILT_MAX_DEG, TILT_STEP_DEG
from ..errors import KingenError
from ..runtime.text import counted, shorten
from ..units import fixed_text, number_text
from .common import (EXIT_FAILED, HOST, OUT_DIR, ROBOT, TIMEOUT, FiniteRange, _out_folder, _output_file, _pose,
                     _t6, calibration_options, cli, finite, in_child, load_model, output_width, print_table,
                     routine_to_check, say, say_fitted, solve_job, table_lines)


@cli.command("list")
def list_robots():
    """The shipped robots with DOF (the joints a routine answers: the limbs', then a wrist's),
    postures and limb models, a wrist's joints added (descriptions cut to fit the terminal's
    width, at least 20 characters of them; whole to a pipe or file)."""
    from ..robot.model import shipped_robots

    rows = [("robot", "dof", "postures", "limbs", "description")]
    for name in shipped_robots():
        robot = load_model(name)
        counts = ", ".join(f"{sum(l.model == m for l in robot.limbs)} {m}" for m in robot.models)
        if robot.wrist is not None:
            counts += f" + {len(robot.wrist.names)}-axis wrist"
        rows.append((name, str(robot.joint_count), str(robot.postures), counts, " ".join(robot.description.split())))
    width = output_width()
    if width is not None:
        lead = sum(max(len(row[column]) for row in rows) + 2 for column in range(4))
        rows = [row[:4] + (shorten(row[4], max(20, width - lead)),) for row in rows]
    print_table(rows)


@cli.command()
@ROBOT
@OUT_DIR
@click.option("--pose", nargs=6, type=float, metavar="X Y Z ROLL PITCH YAW", callback=_pose,
              help="Platform pose: mm and degrees, R = Rz(yaw) Ry(pitch) Rx(roll).")
@click.option("--t6", nargs=16, type=float, metavar="16 NUMBERS", callback=_t6,
              help="DELMIA's T6, row by row: n, o, a, p rows, each with its 0/1 last entry.")
@click.option("--degrees", is_flag=True, help="Show revolute joints in degrees (the plugin works in radians).")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write every posture (joints in mm and rad, warnings, indices) as JSON.")
@click.option("--switch", nargs=2, type=click.IntRange(min=0), default=None, metavar="A B",
              help="Predict a switch from posture A to B: B's joints, their assembly modes and the TCP jump.")
@click.option("--wide", is_flag=True,
              help="Always print the full table, the reference's joints beside the plugin's, however wide "
                   "[default: when it is wider than the terminal ($COLUMNS), the reference is one column of "
                   "differences and the columns wrap].")
@calibration_options
@HOST
@TIMEOUT
def solve(robot, out_dir, pose, t6, degrees, json_path, switch, wide, link_lengths, link_offsets, host, timeout):
    """Every posture's joints and warning from the plugin, with the reference's beside it."""
    import numpy as np

    from ..runtime.files import write_atomic
    from ..conventions import t6_from_pose
    from ..kinematics.reference import solve as reference_solve
    from ..kinematics.routine import calls_decoder
    from ..view.scene import posture_branches

    if (pose is None) == (t6 is None):
        raise click.UsageError("give exactly one of --pose and --t6")
    model = load_model(robot)
    matrix = t6_from_pose(np.asarray([pose])) if pose is not None else np.asarray(t6, dtype=float).reshape(1, 4, 4)
    library, routine = routine_to_check(model, host, out_dir, timeout=timeout)
    model = host.as_seen(model)
    calls = in_child(solve_job, (host, model, library, routine, matrix, link_lengths, link_offsets), timeout, host,
                     {"result": calls_decoder(len(matrix))})
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
    compact = (["posture", "branches"] + names
               + ["warning", "max |plugin - reference|", "reference warning", "direct index (mm)", "min inverse index"])
    rows, compact_rows = [header], [compact]
    for k, branches in enumerate(posture_branches(model)):
        plugin = [fixed_text(v, 9) for v in calls.solutions[0, :, k] * scale] + [_warning_name(calls.warnings[0, k])]
        indices = [_index_text(direct[k]), inverse_text]
        difference = np.abs(calls.solutions[0, :, k] - expected.joints[0, :, k]) * scale
        rows.append([str(k), branches] + plugin + ["|"] + [fixed_text(v, 9) for v in expected.joints[0, :, k] * scale]
                    + [_warning_name(expected.warnings[0, k])] + indices)
        compact_rows.append([str(k), branches] + plugin
                            + [f"{difference.max():.3g}" if np.isfinite(difference).all() else "n/a",
                               _warning_name(expected.warnings[0, k])] + indices)
    width = None if wide else output_width()
    print_table(rows if width is None or max(map(len, table_lines(rows))) <= width else compact_rows, width)
    say(f"routine returned {calls.returned[0]}")
    if model.task:
        say_fitted(_manifold_note(model, matrix), width)
    if model.wrist is not None and not model.wrist.whole_pose:  # a three-axis wrist reads the pose whole
        say_fitted(_turn_note(model, matrix, expected), width)
    say_fitted(_indices_note(model), width)
    if switch is not None:
        _predict_switch(model, matrix[0], expected, switch, scale, units, width)
    if json_path is not None:
        write_atomic(json_path, json.dumps(finite({
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
        say(f"the routine {host.describe_faults(int(calls.faults[0]))}")
        return EXIT_FAILED
    return 0


def _predict_switch(model, t6, expected, switch, scale, units, width):
    """What a host that recomputes the TCP from posture B's joints may do after A -> B
    (kingen.kinematics.posture_switch), printed with lines fitted to ``width`` columns (None:
    no limit); no prediction when A or B is unreachable at the pose."""
    import numpy as np

    from ..kinematics.posture_switch import predict_switch

    first, second = switch
    if max(first, second) >= model.postures:
        raise click.BadParameter(f"{model.name} has postures 0 to {model.postures - 1}", param_hint="--switch")
    predicted = predict_switch(model, t6, expected.joints[0], expected.warnings[0], first, second)
    if predicted.unreachable is not None:
        say_fitted(f"switch {first} -> {second}: posture {predicted.unreachable} is unreachable at this pose; "
                   "no switch to predict", width)
        return
    if predicted.modes is None:
        say_fitted(f"switch {first} -> {second}: forward kinematics not available ({model.dof} limbs; declare forward.free)", width)
        return
    moved = ", ".join(f"{name} {fixed_text(value * s, 6, sign=True)} {unit}" for name, value, s, unit in
                      zip(model.joint_names, predicted.change, scale, units))
    say_fitted(f"switch {first} -> {second}: the joints move by {moved}", width)
    if not predicted.modes:
        say_fitted(f"  posture {second}'s joints admit no pose: the host cannot recompute the TCP", width, "    ")
        return
    for number, (mode, distance) in enumerate(zip(predicted.modes, predicted.distances_mm)):
        pose = ", ".join(fixed_text(v, 3) for v in np.concatenate([mode.pose[:3], np.degrees(mode.pose[3:])]))
        say_fitted(f"  assembly mode {number}: pose ({pose}), {distance:.3f} mm from the commanded TCP", width, "    ")
    say_fitted(f"  a host that recomputes the TCP from posture {second}'s joints may jump up to {predicted.jump_mm:.3f} mm "
               f"({counted(len(predicted.modes), 'assembly mode')})", width, "    ")


def _index_text(value):
    if value is None:
        return "n/a"
    return "unreachable" if not math.isfinite(value) else f"{value:.6g}"


def _manifold_note(model, matrix):
    """Where a machine with task coordinates is for the T6 (1, 4, 4)'s task coordinates, and
    whether the T6 asks for that pose (docs/how-to/hybrid.md)."""
    from ..conventions import pose_from_t6
    from ..kinematics.hybrid.parasitic import off_manifold_words, solve_parasitic
    from ..kinematics.routine import SINGULAR_TOLERANCE

    machine = solve_parasitic(model, matrix)
    off = off_manifold_words(model, pose_from_t6(matrix)[0])
    where = " ".join(fixed_text(value, 9) for value in pose_from_t6(machine.t6)[0])
    world = dict(zip(("x", "y", "z", "roll", "pitch", "yaw"), ("X", "Y", "Z", "A", "B", "C")))
    read = ", ".join(world[name] for name in world if name in model.task)
    solved = ", ".join(world[name] for name in world if name not in model.task)
    asked = (f"off its manifold {off[0]}: the routine answers WARN_UNREACHABLE with that pose's joints" if off
             else "on its manifold") if model.parasitic_given else f"read for {read} only (this host solves {solved})"
    task = ", ".join(name for name in world if name in model.task)
    if not machine.radicand[0] >= -SINGULAR_TOLERANCE:
        return f"no pose of the machine has this {task} (the constraint's radicand is {machine.radicand[0]:.6g})"
    return f"the machine's pose for this {task}: x y z roll pitch yaw = {where} (mm, degrees); the T6 is {asked}"


def _turn_note(model, matrix, expected):
    """How far the asked tool frame (T6 (1, 4, 4)) is turned about the tool axis from the
    machine's tool frame in each posture the reference reaches (the five-axis reading ignores it)."""
    import numpy as np

    from ..kinematics.routine import WARNINGS
    from ..kinematics.hybrid.wrist import tool_t6, tool_turn

    turns = []
    for k in range(model.postures):
        if expected.warnings[0, k] != WARNINGS["WARN_UNREACHABLE"]:
            reached = tool_t6(model, expected.platform, expected.joints[:, model.dof:, k])
            turns.append(f"posture {k} {fixed_text(np.degrees(tool_turn(matrix, reached)[0]), 6)}")
    turns = ", ".join(turns) or "no posture reaches it"
    return f"the turn of the asked tool frame about the tool axis from the machine's (degrees; ignored): {turns}"


def _indices_note(model):
    """What the index columns mean for this robot, in one line."""
    inverse = "min inverse index: the smallest normalised radicand D over the limbs (1 - 1/Inv_I; 0 at a limb singularity)"
    if not model.has_direct_index:
        return (f"direct index: not available ({model.dof} limbs: the constraints that complete the platform "
                f"are {'not modelled' if not model.task else 'not in the index'}); {inverse}")
    threshold = (f"below {model.direct_index_min:g} mm the routine answers WARN_SINGULAR_SOLUTION"
                 if model.direct_index_min is not None else "no threshold set (singularity: direct_index_min)")
    return f"direct index: 0 at a direct (platform) singularity; {threshold}; {inverse}"


@cli.command(context_settings={"ignore_unknown_options": True})
@ROBOT
@click.option("--joints", required=True, type=str, metavar="Q1 .. Qn",
              help="The joints, mm (prismatic) and degrees (revolute), space-separated in one argument "
                   "or as the remaining arguments.")
@click.argument("more_joints", nargs=-1, type=click.UNPROCESSED, metavar="")
@click.option("--near", nargs=6, type=float, default=None, metavar="X Y Z ROLL PITCH YAW", callback=_pose,
              help="The pose to measure distances from and to take non-free coordinates from "
                   "[default: the verification home].")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write the assembly modes as JSON.")
@click.option("--search", type=FiniteRange(min=0.1, max=1000.0), default=2.0, show_default=True,
              help="Where no exhaustive method applies: the multi-start search covers this many times the "
                   "verification region around home.")
def fk(robot, joints, more_joints, near, json_path, search):
    """Forward kinematics: every platform pose (assembly mode) the joints admit, and how kingen
    knows they are all: exhaustively for six limbs (homotopy from a generic Stewart-Gough
    platform) and for three translating limbs (closed form), "not exhaustive" where the
    geometry has a continuum of solutions; otherwise a multi-start search over a stated region.

    Exit 0 with at least one pose, 1 when none is found (the best residual is shown)."""
    import numpy as np

    from ..runtime.files import write_atomic
    from ..kinematics.forward import assemblies, best_residual

    model = load_model(robot)
    try:
        values = [float(v) for v in joints.replace(",", " ").split()] + [float(v) for v in more_joints]
    except ValueError:
        raise click.BadParameter("numbers expected", param_hint="--joints") from None
    if len(values) != model.joint_count or not all(math.isfinite(v) for v in values):
        raise click.BadParameter(f"{model.name} has {model.joint_count} joints; give {model.joint_count} finite numbers",
                                 param_hint="--joints")
    if not model.has_forward:
        raise KingenError(f"{model.path}: forward: forward kinematics needs free pose coordinates for a robot "
                          f"with {model.dof} limbs: declare them, for example forward: {{free: [x, y, z]}}")
    internal = np.array(values) * model.joint_scale()
    near_pose = np.array(near if near is not None else model.verification.home, dtype=float)
    near_internal = np.concatenate([near_pose[:3], np.radians(near_pose[3:])])
    modes = assemblies(model, internal, near_internal, search)  # a wrist's: the tool's poses
    found = modes.found
    rows = [("mode", "x (mm)", "y (mm)", "z (mm)", "roll (deg)", "pitch (deg)", "yaw (deg)", "residual (mm)",
             "from near (mm)")]
    solutions = []
    for number, assembly in enumerate(found):
        pose = np.concatenate([assembly.pose[:3], np.degrees(assembly.pose[3:])])
        distance = float(np.linalg.norm(assembly.pose[:3] - near_internal[:3]))
        solutions.append({"pose": pose.tolist(), "residual_mm": assembly.residual_mm, "distance_from_near_mm": distance})
        rows.append((str(number), *(fixed_text(v, 6) for v in pose), number_text(assembly.residual_mm),
                     fixed_text(distance, 3)))
    if json_path is not None:
        write_atomic(json_path, json.dumps({"robot": model.name, "joints": values, "exhaustive": modes.exhaustive,
                                            "method": modes.method, "solutions": solutions},
                                           indent=2, allow_nan=False) + "\n")
    say(modes.method)
    if not found:
        parallel = model.parallel  # with a wrist: its legs, searched around the platform's home
        home = np.asarray(parallel.verification.home, dtype=float)
        best = best_residual(parallel, internal[:parallel.dof], np.concatenate([home[:3], np.radians(home[3:])])
                             if model.wrist is not None else near_internal, search)
        say(f"no pose found for these joints (best residual {best:.3g} mm)")
        return EXIT_FAILED
    print_table(rows)
    return 0


@cli.command()
@ROBOT
@click.option("--posture", type=click.IntRange(min=0), default=None,
              help="The posture (assembly mode) to analyse [default: the robot's working_posture].")
@click.option("-o", "--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None, callback=_out_folder,
              help="Output folder [default: build/<name>/analysis].")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Also write analysis.json to this file.")
@click.option("--tilt-convention", type=click.Choice(["axis", "euler"]), default="axis", show_default=True,
              help="axis: turn about the horizontal axis (cos a, sin a, 0); euler: roll = tilt cos a, "
                   "pitch = tilt sin a (the 6-RUS thesis's polar graph).")
@click.option("--tilt-step", type=FiniteRange(*TILT_STEP_DEG), default=0.1, show_default=True,
              help="Tilt step (deg): a limit is the largest multiple of it up to which every step passes.")
@click.option("--azimuth-step", type=FiniteRange(*AZIMUTH_STEP_DEG), default=15.0, show_default=True,
              help="Step (deg) between the azimuths of the tilt directions.")
@click.option("--tilt-max", type=FiniteRange(*TILT_MAX_DEG), default=90.0, show_default=True,
              help="Largest tilt (deg) tried, and the range (+-) of the angle sweeps.")
@click.option("--collision", "collision_model", type=click.Choice(["segments", "thesis"]), default="segments",
              show_default=True, help="segments: every pair of links and cranks, cranks at their angle; thesis: "
                                      "pairs 1-6, 2-3, 4-5, rods as infinite lines, cranks at angle 0.")
def analyze(robot, posture, out_dir, json_path, tilt_convention, tilt_step, azimuth_step, tilt_max,
            collision_model):
    """Tilt limits, sweeps and workspace slices of one posture: analysis.json, PNG figures
    and a self-contained report.html."""
    import time

    from ..design.analysis import Settings
    from ..design.analysis import analyze as run_analysis
    from ..kinematics.collision import model_problem
    from ..runtime.files import default_out_dir, write_files
    from ..design.figures import figures, report_html
    from .report_views import analysis_view

    model = load_model(robot)
    if posture is not None and posture >= model.postures:
        raise click.BadParameter(f"{model.name} has postures 0 to {model.postures - 1}", param_hint="--posture")
    problem = model_problem(model, collision_model)
    if problem:
        raise click.BadParameter(problem, param_hint="--collision")
    settings = Settings(tilt_convention, tilt_step, azimuth_step, tilt_max, collision_model)
    out_dir = out_dir or default_out_dir(model) / "analysis"
    start = time.perf_counter()
    with _steps(["tilt limits", "sweeps", "workspace slices", "figures"]) as step:
        analysis = run_analysis(model, posture, settings, progress=step)
        step("figures")
        pngs = figures(analysis)
    seconds = time.perf_counter() - start
    text = json.dumps(finite(analysis), indent=1, allow_nan=False) + "\n"
    view = analysis_view(model, analysis, settings.tilt_convention)
    outputs = {"analysis.json": text, **pngs, "report.html": report_html(model, analysis, pngs, seconds, view)}
    write_files({**{out_dir / name: data for name, data in outputs.items()},
                 **({} if json_path is None else {json_path: text})})
    say(f"analyze {model.name}, posture {analysis['posture']}: {_tilt_summary(analysis, settings)}")
    for name in outputs:
        say(str(out_dir / name))
    say(f"in {seconds:.1f} s")


def _tilt_summary(analysis, settings):
    """One line: the least tilt over the azimuths and what stops it, with the settings behind it."""
    limits = analysis["tilt_limits"]
    if analysis["singular_at_home"]:
        tilts = ("every azimuth's tilt limit is 0 deg" if limits
                 else f"tilt limits {analysis['available']['tilt_limits']}")
        return f"{analysis['singular_at_home']}; {tilts}"
    if not limits:
        return f"tilt limits {analysis['available']['tilt_limits']}"
    least = min(limits, key=lambda row: row["max_tilt_deg"])
    stopped = (f"stopped by {least['cause'].replace('_', ' ')}" if least["cause"] != "none"
               else f"nothing stops it up to --tilt-max {settings.tilt_max_deg:g}")
    return (f"least tilt {least['max_tilt_deg']:g} deg towards azimuth {least['azimuth_deg']:g} ({stopped}); "
            f"{len(limits)} azimuths every {settings.azimuth_step_deg:g} deg, steps of {settings.tilt_step_deg:g} deg, "
            f"{settings.tilt_convention} convention, {settings.collision} collisions")


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


def _warning_name(code):
    from ..kinematics.routine import WARNING_NAMES

    return WARNING_NAMES.get(int(code), f"UNWRITTEN({code})")
