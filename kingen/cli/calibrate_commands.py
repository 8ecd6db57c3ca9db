"""The commands that calibrate: ``calibrate`` (identify the machine as built from measurements,
write its robot file) and ``calibrate plan`` (choose the poses to measure)."""

import functools
import json
import math
import statistics
from pathlib import Path

import click

from ..defaults import CALIBRATION_NOISE
from .common import (EXIT_FAILED, ROBOT, FiniteRange, _out_folder, _output_file, cli, finite, load_model_and_data,
                     refuse_special_files, say)
from ..units import length_text, number_text

MEASURE = click.option("--measure", type=click.Choice(["pose", "position"]), default="pose", show_default=True,
                       help="What the device measures: the target's pose (x y z roll pitch yaw) or a reflector's "
                            "position (x y z).")
IDENTIFY = click.option("--identify", "spec", default="all", show_default=True, metavar="SPEC",
                        help="Parameter groups to identify, comma-separated: all, base, platform, length, direction, "
                             "zero, frame, target; -GROUP keeps a group at its nominal value (e.g. -target when "
                             "the target is known).")


NOISE_OPTIONS = (
    ("--noise-mm", "device_mm", 1e-9, 1000.0, "The device's position noise, one standard deviation per coordinate (mm)."),
    ("--noise-deg", "device_deg", 1e-12, 90.0, "The device's angle noise, one standard deviation per angle (degrees)."),
    ("--noise-joint-mm", "joint_mm", 1e-12, 1000.0, "A prismatic joint's reading noise, one standard deviation (mm)."),
    ("--noise-joint-deg", "joint_deg", 1e-12, 90.0, "A revolute joint's reading noise, one standard deviation (degrees)."))
"""(option, Noise field, least, most, help) of the stated noise (kingen.calibrate.noise.Noise)."""


def NOISE(function):
    """The noise options: the command gets ``stated``, a kingen.calibrate.noise.Noise."""
    @functools.wraps(function)
    def with_noise(*args, **kwargs):
        from ..calibrate.noise import Noise

        return function(*args, stated=Noise(**{field: kwargs.pop(field) for _, field, *_ in NOISE_OPTIONS}), **kwargs)

    for option, field, least, most, words in reversed(NOISE_OPTIONS):
        with_noise = click.option(option, field, type=FiniteRange(min=least, max=most), default=CALIBRATION_NOISE[field],
                                  show_default=True, help=words)(with_noise)
    return with_noise


class _CalibrateGroup(click.Group):
    """``calibrate ROBOT ...`` runs the ``run`` command (the word may be left out); ``calibrate plan ...`` plans."""

    def parse_args(self, ctx, args):
        if args and args[0] not in self.commands and args[0] not in ("--help", "-h"):
            args = ["run", *args]
        return super().parse_args(ctx, args)


@cli.group(cls=_CalibrateGroup, subcommand_metavar="ROBOT --measurements FILE [OPTIONS] | plan ROBOT --poses N [OPTIONS]")
def calibrate():
    """Identify the machine as built from measurements.

    kingen calibrate ROBOT --measurements FILE, with the options --measure pose|position,
    --identify SPEC, the stated noise (--noise-mm, --noise-deg, --noise-joint-mm,
    --noise-joint-deg), --validate FILE, -o DIR and --json FILE: generalised least squares on
    every limb's geometry, the measuring frame and the target, outliers left out and named;
    writes <name>_calibrated.yaml, calibration.json and report.html to DIR (default:
    build/<name>/calibrate). FILE is a CSV with the header q1 .. qN (joints as read: mm,
    degrees) then x, y, z, roll, pitch, yaw (mm, degrees; or x, y, z with --measure position),
    in the device's frame. Exit 0 calibrated, 1 not calibrated (the fit did not converge, the
    residuals are far beyond the stated noise, too many outliers, or the result is worse on
    the --validate measurements than the nominal robot; nothing written), 2 bad input.
    kingen calibrate run --help lists the options.

    kingen calibrate plan ROBOT --poses N: the poses to measure."""


@calibrate.command()
@ROBOT
@click.option("--measurements", "measurements_path", required=True, type=click.Path(dir_okay=False, path_type=Path),
              help="The measurement CSV.")
@MEASURE
@IDENTIFY
@click.option("--validate", "validate_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Held-out measurements (same layout) to report the calibrated robot's errors on.")
@click.option("-o", "--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None, callback=_out_folder,
              help="Output folder [default: build/<name>/calibrate].")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Also write calibration.json to this file.")
@NOISE
def run(robot, measurements_path, measure, spec, validate_path, out_dir, json_path, stated):
    """Calibrate ROBOT from measurements: what kingen calibrate ROBOT runs (the word run may be left out)."""
    from ..calibrate import report
    from ..calibrate.identification import identify, validation_problem
    from ..calibrate.measurements import read_measurements
    from ..calibrate.output import calibrated_name, calibrated_yaml
    from ..calibrate.parameters import Parameters
    from ..runtime.files import default_out_dir, write_files
    from .report_views import calibration_view

    refuse_special_files(measurements_path, validate_path)
    model, data, _ = load_model_and_data(robot)
    parameters = Parameters(model, measure)
    selected = parameters.selected(spec)
    measurements = read_measurements(measurements_path, model, measure)
    held_out = read_measurements(validate_path, model, measure) if validate_path is not None else None
    fit = identify(parameters, measurements, selected, stated)
    if not fit.converged:
        say(f"kingen: calibrate {model.name}: the fit did not converge ({fit.message}; {fit.evaluations} "
            "evaluations): no calibrated robot file written", err=True)
        return EXIT_FAILED
    before = fit.problem.errors(fit.before)[:2]
    after = fit.problem.errors(fit.values)[:2]
    validation = nominal = None
    if held_out is not None:
        check = validation_problem(parameters, fit.values, held_out)
        validation, nominal = check.errors(fit.values)[:2], check.errors(fit.before)[:2]
    outcome = report.result(parameters, fit, before, after, (validation, nominal), fit.seconds)
    refusal = fit.refusal or _worse_than_nominal(outcome)
    if refusal is not None:
        _say_outcome(model.name, outcome, fit)
        say(f"kingen: calibrate {model.name}: not calibrated: {refusal}: no calibrated robot file written", err=True)
        return EXIT_FAILED
    text = json.dumps(finite(outcome), indent=1, allow_nan=False) + "\n"
    name = calibrated_name(model.name)
    left_out = f" ({len(fit.outliers)} left out as outliers)" if fit.outliers else ""
    header = [f"kingen calibrate {model.name} from {measurements_path.name}: {len(measurements.joints)} {measure} "
              f"measurements{left_out}, after {length_text(outcome['residuals_after']['rms_mm'])} RMS (before "
              f"{length_text(outcome['residuals_before']['rms_mm'])})."]
    robot_text = calibrated_yaml(data, parameters, fit.values, header)
    _check_loads(robot_text, model.path.parent / f"{name}.yaml")
    pngs = {"residuals.png": report.residual_figure(before, after), "parameters.png": report.parameter_figure(outcome, parameters.entries)}
    settings = {"measure": measure, "measurements": str(measurements_path), "identify": spec}
    out_dir = out_dir or default_out_dir(model) / "calibrate"
    outputs = {f"{name}.yaml": robot_text, "calibration.json": text, **pngs,
               "report.html": report.report_html(model.name, outcome, pngs, settings, calibration_view(parameters, fit))}
    write_files({**{out_dir / file_name: content for file_name, content in outputs.items()},
                 **({} if json_path is None else {json_path: text})})
    _say_outcome(model.name, outcome, fit)
    for file_name in outputs:
        say(str(out_dir / file_name))
    return 0


def _worse_than_nominal(outcome):
    """Why the calibrated robot is not one (its --validate errors' RMS above the nominal robot's,
    the measuring frame and target fitted), or None."""
    after, nominal = outcome["validation"], outcome["validation_nominal"]
    if after is None:
        return None
    for key, written in (("rms_mm", length_text), ("rms_deg", lambda value: f"{number_text(value, 4)} deg")):
        if after[key] is not None and after[key] > nominal[key]:
            return (f"on the held-out measurements it is worse than the nominal robot ({written(after[key])} "
                    f"RMS against {written(nominal[key])})")
    return None


def _deviations_text(std, entries):
    """'median 12 um, largest 30 um (leg1.reference_length)' for each unit the identified
    parameters (finite ``std``) have: mm, then degrees."""
    parts = []
    for unit in ("mm", "deg"):
        found = [(value, entry.name) for value, entry in zip(std, entries) if math.isfinite(value) and entry.unit == unit]
        if found:
            largest = max(found)
            written = length_text if unit == "mm" else (lambda value: f"{number_text(value)} deg")
            parts.append(f"median {written(statistics.median(value for value, _ in found))}, largest "
                         f"{written(largest[0])} ({largest[1]})")
    return "; ".join(parts)


def _check_loads(text, path):
    """The calibrated robot file's text loads as a robot (else an internal error: kingen wrote it)."""
    from ruamel.yaml import YAML

    from ..robot.model import robot_from_data

    robot_from_data(YAML(typ="safe").load(text), path)


def _say_outcome(name, outcome, fit):
    def words(summary):
        angle = f", {number_text(summary['rms_deg'])} deg RMS" if summary["rms_deg"] is not None else ""
        return f"{length_text(summary['rms_mm'])} RMS (max {length_text(summary['max_mm'])}){angle}"

    identified = int(sum(row["identifiable"] for row in outcome["parameters"]))
    say(f"calibrate {name}: {identified} parameters identified from {outcome['poses']} poses "
        f"({len(fit.unidentifiable)} kept nominal, not identifiable), {fit.evaluations} evaluations, "
        f"{outcome['seconds']:.2f} s")
    say(f"  residuals before {words(outcome['residuals_before'])}; after {words(outcome['residuals_after'])}")
    if outcome["validation"] is not None:
        say(f"  held-out validation: {words(outcome['validation'])} (nominal robot: "
            f"{words(outcome['validation_nominal'])})")
    for row in outcome["outliers"]:
        angle = f", {row['angle_deg']:.3g} deg" if row["angle_deg"] is not None else ""
        say(f"  outlier left out: {fit.problem.measurements.path}:{row['line']}: error {length_text(row['position_mm'])}"
            f"{angle}, {row['noise_ratio']:.3g} times the stated noise")
    if outcome["std_reported"]:
        say(f"  redundancy {outcome['redundancy']} of {outcome['equations']} equations; residuals "
            f"{math.sqrt(outcome['variance_factor']):.3g} times the stated noise (variance factor "
            f"{outcome['variance_factor']:.3g}): standard deviations from the stated noise"
            f"{', scaled up by it' if outcome['variance_factor'] > 1 else ''}")
    else:
        say(f"  redundancy {outcome['redundancy']} of {outcome['equations']} equations: too little to state standard "
            "deviations (measure more poses)")
    say(f"  condition number {outcome['condition_number']:.4g}, smallest singular value "
        f"{outcome['min_singular_value']:.4g}, noise amplification {outcome['noise_amplification']:.4g}")
    for line in fit.unidentifiable:
        say(f"  not identifiable: {line}")


@calibrate.command()
@ROBOT
@click.option("--poses", "count", type=click.IntRange(min=1, max=10000), required=True, help="Poses to choose.")
@MEASURE
@IDENTIFY
@click.option("-o", "--output", "output", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="The poses' CSV [default: build/<name>/calibrate/poses.csv].")
@NOISE
def plan(robot, count, measure, spec, output, stated):
    """Choose N poses to measure for calibrating ROBOT: greedy D-optimal, then the limb parameters' variances' product, among 5,000 seeded
    poses of the verification region that the reference finds reachable, within travel and
    away from singularities (and collisions, with collision radii). Writes them as a CSV in
    calibrate's layout (nominal joints; the measured columns hold the nominal pose: replace
    them with what the device measures) and prints the predicted condition number and
    parameter deviations for the given noise."""
    import numpy as np

    from ..calibrate import plan as planning
    from ..calibrate.measurements import write_measurements
    from ..calibrate.parameters import Parameters
    from ..errors import KingenError
    from ..runtime.files import default_out_dir, write_atomic

    model, _, _ = load_model_and_data(robot)
    parameters = Parameters(model, measure)
    selected = parameters.selected(spec)
    found = planning.candidates(parameters, selected, stated)
    identifiable = int(np.count_nonzero(found.chosen))
    per_pose = found.blocks.shape[1]
    needed = -(-identifiable // per_pose)
    if count < needed:
        raise KingenError(f"--poses: {count} poses for {identifiable} identifiable parameters: at least {needed} "
                          f"are needed ({per_pose} equations per pose)")
    if count > len(found.poses):
        raise KingenError(f"--poses: {count} poses asked, {len(found.poses)} candidates qualify")
    rows = planning.greedy(found.weighted, count, planning.limb_columns(found, parameters))
    std, indices = planning.predicted(found, rows, parameters)
    output = output or default_out_dir(model) / "calibrate" / "poses.csv"
    write_atomic(output, write_measurements(model, measure, found.joints[rows], found.measured[rows]))
    manifold = ", on the machine's manifold" if model.task else ""
    say(f"plan {model.name}: {count} of {len(found.poses)} candidate poses (seeded in the verification region"
        f"{manifold}: reachable, within travel, away from singularities{', clear of collisions' if model.collision else ''}), "
        f"{identifiable} identifiable parameters")
    say(f"  predicted condition number {indices['condition_number']:.4g}; with noise {stated.device_mm:g} mm and "
        f"{stated.device_deg:g} deg, parameter deviations (one std): {_deviations_text(std, parameters.entries)}")
    say(str(output))
    return 0
