"""Calibration's goals, measured and printed as Markdown, and with --json written as plain data
for benchmarks/run.py (the performance page's section).

    python benchmarks/calibrate.py [--part hexapod|planning|positions|constrained|wrist|speed|all] [--json FILE]

- hexapod: the 42 limb parameters perturbed by up to 1 mm, the measuring frame unknown
  (25 degrees and 150 mm off), 6-D measurements with noise 10 um and 20 urad per coordinate,
  joints read to 1 um; 30 planned poses; the pose error on 200 held-out poses (measured
  exactly) before (nominal robot, frame and target fitted) and after.
  (How honest the stated deviations are over new machines, tracker poses and noise:
  benchmarks/calibrate_montecarlo.py.)
- planning: predicted parameter deviations of the 30 planned poses against 30 random
  reachable ones (median over the parameters).
- positions: a reflector at an unknown point, positions only (noise 10 um), 30 planned poses,
  200 held-out: a 6-RUS with crank zeros and rods perturbed, and the Gantry-Tau with link
  lengths, origins and platform points perturbed.
- constrained: machines with task coordinates (prs_head, exechon_constrained), 6-D
  measurements: limb parameters perturbed by up to 0.5 mm / 0.05 deg and the constraints' axes by
  up to 0.05 deg, the measuring frame unknown, noise as above, 30 planned poses (on the nominal
  manifold), 200 held-out poses on the real machine's manifold (exact measurements); the pose
  error before and after, and how many identifiable parameters lie within 3 stated standard
  deviations of the truth (in the identified gauge: the fit of the same poses without noise), in
  one noise draw and as a share of CONSTRAINED_RUNS draws.
- wrist: a machine with a serial wrist (exechon_wrist), 6-D measurements of the tool: limb
  parameters perturbed by up to 0.5 mm / 0.05 deg (the tool's reach among them), the wrist's zero
  offsets by 0.1 deg, the constraints' and the wrist's axes by 0.05 deg, the measuring frame
  unknown, noise as above, 30 planned tool poses, 200 held-out tool poses (exact measurements):
  the pose error before and after, with the target (the measured frame on the tool) identified
  too (--identify all) and known (all,-target).
- speed: one identification of the hexapod from 50 poses; planning 30 of 5,000 candidates.
"""

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from kingen.calibrate import plan
from kingen.calibrate.identification import identify, region_poses, validation_problem
from kingen.calibrate.measurements import Measurements
from kingen.calibrate.noise import Noise
from kingen.calibrate.parameters import Parameters
from kingen.calibrate.prediction import synthesize
from kingen.conventions import t6_from_pose
from kingen.kinematics.reference import solve
from kingen.robot.model import load_robot

ABOUT = ("`kingen calibrate` on synthetic measurements of a perturbed robot, from 6-D poses and from positions "
         "([Calibrate a robot](how-to/calibrate.md)); the tests check the same against measurements made with the "
         "legs' closure written independently of kingen.")
"""What the section measures, for the performance page (links relative to docs/)."""
NOISE_MM, NOISE_RAD, JOINT_STEP = 0.01, 20e-6, 0.001
FRAME = [150.0, -80.0, 40.0, 2.0, -3.0, 25.0]


def truth_values(parameters, rng, scale_of):
    """Nominal values with each limb parameter moved by scale_of(entry) * uniform(-1, 1), the frame FRAME."""
    values = parameters.nominal.copy()
    for index, entry in enumerate(parameters.entries):
        if entry.limb is not None:
            values[index] += scale_of(entry) * rng.uniform(-1.0, 1.0)
    values[parameters.groups == "frame"] = FRAME
    return values


def measure(parameters, truth, poses, rng, noisy=True):
    """Measurements of the truth at poses: joints read to JOINT_STEP, device noise when ``noisy``."""
    robot = parameters.robot
    joints, measured = synthesize(parameters, truth, poses, robot.working_posture)
    shown = joints / robot.joint_scale()
    joints = np.round(shown / JOINT_STEP) * JOINT_STEP * robot.joint_scale() if noisy else joints
    if noisy:
        measured = measured.copy()
        measured[:, :3] += rng.normal(0.0, NOISE_MM, measured[:, :3].shape)
        measured[:, 3:] += np.degrees(rng.normal(0.0, NOISE_RAD, measured[:, 3:].shape))
    return Measurements("synthetic", parameters.measure, joints, measured, tuple(range(2, len(poses) + 2)), ())


def reachable_poses(robot, count, seed):
    """``count`` seeded poses of the verification region good in the working posture (reference)."""
    poses = region_poses(robot, 4 * count, seed)
    good = solve(robot, t6_from_pose(poses)).warnings[:, robot.working_posture] == 0
    return poses[good][:count]


def planned(parameters, count=30):
    found = plan.candidates(parameters, parameters.selected("all"), Noise(NOISE_MM, math.degrees(NOISE_RAD), JOINT_STEP))
    rows = plan.greedy(found.weighted, count, plan.limb_columns(found, parameters))
    return found, rows


def rms(values):
    return float(np.sqrt(np.mean(np.square(values))))


def held_out_error(parameters, values, held):
    position, angle, _ = validation_problem(parameters, values, held).errors(values)
    return rms(position), None if angle is None else rms(angle)


def hexapod_case(seed=1):
    parameters = Parameters(load_robot("hexapod"), "pose")
    rng = np.random.default_rng(seed)
    truth = truth_values(parameters, rng, lambda entry: 1.0)
    found, rows = planned(parameters)
    held = measure(parameters, truth, reachable_poses(parameters.robot, 200, 99), rng, noisy=False)
    return parameters, truth, found.poses[rows], held, found, rows


def hexapod():
    parameters, truth, poses, held, _, _ = hexapod_case()
    fit = identify(parameters, measure(parameters, truth, poses, np.random.default_rng(7)), parameters.selected("all"))
    (before, before_angle), (after, after_angle) = (held_out_error(parameters, values, held)
                                                    for values in (fit.before, fit.values))
    return {"poses": len(poses), "held_out": 200, "before_um": before * 1000,
            "before_urad": math.radians(before_angle) * 1e6, "after_um": after * 1000,
            "after_urad": math.radians(after_angle) * 1e6, "converged": bool(fit.converged),
            "identified": int(fit.chosen.sum()), "condition_number": float(fit.indices["condition_number"]),
            "seconds": fit.seconds}


def planning(draws=5):
    parameters, _, _, _, found, rows = hexapod_case()
    limbs = plan.limb_columns(found, parameters)
    chosen_std = plan.predicted(found, rows, parameters)[0][found.chosen][limbs]
    figures = {"poses": len(rows), "parameters": len(chosen_std), "planned_median_um": float(np.median(chosen_std)) * 1000,
               "draws": []}
    for draw in range(draws):
        random = np.random.default_rng(draw).choice(len(found.poses), len(rows), replace=False)
        random_std = plan.predicted(found, random, parameters)[0][found.chosen][limbs]
        figures["draws"].append({"random_median_um": float(np.median(random_std)) * 1000,
                                 "ratio_of_medians": float(np.median(random_std) / np.median(chosen_std)),
                                 "median_of_ratios": float(np.median(random_std / chosen_std))})
    return figures


def positions():
    rows = []
    for name, scale_of, words in (
            ("rus_optimized", lambda entry: {"zero_offset": 0.1, "rod_length": 1.0}.get(entry.field, 0.0),
             "crank zeros 0.1 deg, rods 1 mm"),
            ("tau", lambda entry: 1.0 if entry.field in ("link_length", "origin", "platform_point") else 0.0,
             "link lengths, origins, platform points 1 mm")):
        parameters = Parameters(load_robot(name), "position", target=(0.0, 0.0, 0.0))
        rng = np.random.default_rng(4)
        truth = truth_values(parameters, rng, scale_of)
        truth[parameters.groups == "target"] = [10.0, -20.0, 20.0]
        found, chosen = planned(parameters)
        fit = identify(parameters, measure(parameters, truth, found.poses[chosen], rng), parameters.selected("all"))
        held = measure(parameters, truth, reachable_poses(parameters.robot, 200, 99), rng, noisy=False)
        rows.append({"robot": name, "perturbed": words, "poses": len(chosen), "held_out": 200,
                     "before_um": held_out_error(parameters, fit.before, held)[0] * 1000,
                     "after_um": held_out_error(parameters, fit.values, held)[0] * 1000})
    return rows


CONSTRAINED = ("prs_head", "exechon_constrained")
LIMB_MM, LIMB_DEG, AXIS_DEG = 0.5, 0.05, 0.05
CONSTRAINED_RUNS = 20
"""Noise draws on the same poses behind the constrained machines' coverage of 3 standard deviations."""


def constrained_scale(entry):
    """The constrained machines' perturbation bound of ``entry``: its axes', its mm, its degrees."""
    if entry.group == "axis":
        return AXIS_DEG
    return LIMB_MM if entry.unit == "mm" else LIMB_DEG


def constrained_case(name, count=30, held_out=200, seed=3):
    """(parameters, truth, planned poses, held-out measurements) of a constrained machine."""
    parameters = Parameters(load_robot(name), "pose")
    rng = np.random.default_rng(seed)
    truth = truth_values(parameters, rng, constrained_scale)
    found, rows = planned(parameters, count)
    held = measure(parameters, truth, reachable_poses(parameters.robot, held_out, 99), rng, noisy=False)
    return parameters, truth, found.poses[rows], held


def constrained():
    rows = []
    for name in CONSTRAINED:
        parameters, truth, poses, held = constrained_case(name)
        selected = parameters.selected("all")
        gauge = identify(parameters, measure(parameters, truth, poses, None, noisy=False), selected)
        fit = identify(parameters, measure(parameters, truth, poses, np.random.default_rng(7)), selected)
        chosen = fit.chosen & gauge.chosen
        inside = np.abs(fit.values - gauge.values) <= 3.0 * fit.std
        coverage = []
        for run in range(CONSTRAINED_RUNS):
            draw = identify(parameters, measure(parameters, truth, poses, np.random.default_rng(200 + run)), selected)
            coverage.append(np.where(draw.chosen, np.abs(draw.values - gauge.values) <= 3.0 * draw.std, True))
        coverage = np.mean(coverage, axis=0)[gauge.chosen]
        (before, before_angle), (after, after_angle) = (held_out_error(parameters, values, held)
                                                        for values in (fit.before, fit.values))
        rows.append({"robot": name, "parameters": len(parameters), "identified": int(fit.chosen.sum()),
                     "poses": len(poses), "held_out": len(held.joints), "before_um": before * 1000,
                     "before_urad": math.radians(before_angle) * 1e6, "after_um": after * 1000,
                     "after_urad": math.radians(after_angle) * 1e6, "within_3_sigma": int(np.sum(inside[chosen])),
                     "judged": int(chosen.sum()), "converged": bool(fit.converged), "seconds": fit.seconds,
                     "runs": CONSTRAINED_RUNS, "least": float(coverage.min()), "median": float(np.median(coverage))})
    return rows


WRIST_ZERO_DEG = 0.1


def wrist_scale(entry):
    """The wrist machine's perturbation bound of ``entry``: the wrist's zeros', else as constrained_scale."""
    if entry.group in ("frame", "target"):
        return 0.0
    return WRIST_ZERO_DEG if entry.wrist is not None and entry.group == "zero" else constrained_scale(entry)


def wrist():
    parameters = Parameters(load_robot("exechon_wrist"), "pose")
    rng = np.random.default_rng(3)
    truth = parameters.nominal + np.array([wrist_scale(entry) for entry in parameters.entries]) * rng.uniform(
        -1.0, 1.0, len(parameters))
    truth[parameters.groups == "frame"] = FRAME
    found, rows = planned(parameters)
    held = measure(parameters, truth, reachable_poses(parameters.robot, 200, 99), rng, noisy=False)
    data = measure(parameters, truth, found.poses[rows], np.random.default_rng(7))
    figures = []
    for spec in ("all", "all,-target"):
        fit = identify(parameters, data, parameters.selected(spec))
        (before, before_angle), (after, after_angle) = (held_out_error(parameters, values, held)
                                                        for values in (fit.before, fit.values))
        figures.append({"identify": spec, "parameters": len(parameters), "identified": int(fit.chosen.sum()),
                        "poses": len(rows), "held_out": len(held.joints), "before_um": before * 1000,
                        "before_urad": math.radians(before_angle) * 1e6, "after_um": after * 1000,
                        "after_urad": math.radians(after_angle) * 1e6, "converged": bool(fit.converged),
                        "seconds": fit.seconds})
    return figures


def speed(repeats=3):
    parameters, truth, _, _, _, _ = hexapod_case()
    poses = region_poses(parameters.robot, 50, 5)
    data = measure(parameters, truth, poses, np.random.default_rng(2))
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        identify(parameters, data, parameters.selected("all"))
        times.append(time.perf_counter() - started)
    started = time.perf_counter()
    planned(parameters)
    return {"poses": len(poses), "repeats": repeats, "identify_s": min(times),
            "planning_s": time.perf_counter() - started}


def _hexapod_markdown(part):
    lines = [f"42 limb parameters perturbed by up to 1 mm, measuring frame {FRAME} (mm, deg) unknown, noise "
             f"{NOISE_MM * 1000:g} um / {NOISE_RAD * 1e6:g} urad, joints read to {JOINT_STEP * 1000:g} um, "
             f"{part['poses']} planned poses, {part['held_out']} held-out poses (exact measurements).", "",
             "| | position RMS (um) | orientation RMS (urad) |", "| --- | --- | --- |",
             f"| before (nominal, frame fitted) | {part['before_um']:.2f} | {part['before_urad']:.2f} |",
             f"| after | {part['after_um']:.2f} | {part['after_urad']:.2f} |", "",
             f"Reduction {100 * (1 - part['after_um'] / part['before_um']):.2f} %; converged {part['converged']}, "
             f"{part['identified']} identified, condition number {part['condition_number']:.4g}, "
             f"{part['seconds']:.2f} s."]
    return "Hexapod, 6-D measurements", lines


def _planning_markdown(part):
    return "Planning pays", [
        f"Predicted standard deviations (noise {NOISE_MM * 1000:g} um, {NOISE_RAD * 1e6:g} urad) of the "
        f"{part['parameters']} identifiable limb parameters: {part['poses']} planned poses (median "
        f"{part['planned_median_um']:.1f} um) against {part['poses']} random reachable poses, "
        f"{len(part['draws'])} draws:", "",
        "| draw | random median (um) | ratio of medians | median of ratios |", "| --- | --- | --- | --- |",
        *(f"| {number} | {draw['random_median_um']:.1f} | {draw['ratio_of_medians']:.2f} | "
          f"{draw['median_of_ratios']:.2f} |" for number, draw in enumerate(part["draws"]))]


def _positions_markdown(part):
    return "Positions only", [
        f"A reflector at an unknown point, positions only (noise {NOISE_MM * 1000:g} um).", "",
        "| robot | perturbed | planned poses | before RMS (um) | after RMS (um) | held-out poses |",
        "| --- | --- | --- | --- | --- | --- |",
        *(f"| {row['robot']} | {row['perturbed']} | {row['poses']} | {row['before_um']:.1f} | {row['after_um']:.2f} "
          f"| {row['held_out']} |" for row in part)]


def _constrained_markdown(part):
    return "Machines with task coordinates", [
        f"Limb parameters perturbed by up to {LIMB_MM:g} mm / {LIMB_DEG:g} deg, the constraints' axes by up to "
        f"{AXIS_DEG:g} deg, measuring frame {FRAME} (mm, deg) unknown, noise {NOISE_MM * 1000:g} um / "
        f"{NOISE_RAD * 1e6:g} urad, joints read to {JOINT_STEP * 1000:g} um; planned poses on the nominal manifold, "
        "held-out poses on the real machine's (exact measurements). Within 3 sigma: identifiable parameters whose "
        "identified value lies within 3 stated standard deviations of the noise-free fit's (one noise draw); over "
        "draws: the share of further noise draws in which each does, least and median over the parameters.", "",
        "| robot | identified / parameters | planned poses | held-out poses | before RMS (um, urad) | "
        "after RMS (um, urad) | within 3 sigma | over draws: least, median | seconds |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        *(f"| {row['robot']} | {row['identified']} / {row['parameters']} | {row['poses']} | {row['held_out']} | "
          f"{row['before_um']:.1f}, {row['before_urad']:.1f} | {row['after_um']:.2f}, {row['after_urad']:.2f} | "
          f"{row['within_3_sigma']} of {row['judged']} | {row['least'] * 100:.0f} %, {row['median'] * 100:.0f} % "
          f"({row['runs']} draws) | {row['seconds']:.1f} |" for row in part)]


def _wrist_markdown(part):
    return "A machine with a serial wrist", [
        f"exechon_wrist measured on its tool: limb parameters (the tool's reach among them) perturbed by up to "
        f"{LIMB_MM:g} mm / {LIMB_DEG:g} deg, the wrist's zero offsets by {WRIST_ZERO_DEG:g} deg, the constraints' and "
        f"the wrist's axes by {AXIS_DEG:g} deg, measuring frame {FRAME} (mm, deg) unknown, noise "
        f"{NOISE_MM * 1000:g} um / {NOISE_RAD * 1e6:g} urad, joints read to {JOINT_STEP * 1000:g} um; planned tool "
        "poses, held-out tool poses of the real machine (exact measurements).", "",
        "| --identify | identified / parameters | planned poses | held-out poses | before RMS (um, urad) | "
        "after RMS (um, urad) | converged | seconds |", "| --- | --- | --- | --- | --- | --- | --- | --- |",
        *(f"| {row['identify']} | {row['identified']} / {row['parameters']} | {row['poses']} | {row['held_out']} | "
          f"{row['before_um']:.1f}, {row['before_urad']:.1f} | {row['after_um']:.2f}, {row['after_urad']:.2f} | "
          f"{row['converged']} | {row['seconds']:.1f} |" for row in part)]


def _speed_markdown(part):
    return "Speed", [f"One identification of the hexapod from {part['poses']} poses: {part['identify_s']:.2f} s "
                     f"(best of {part['repeats']}); planning 30 of 5,000 candidates: {part['planning_s']:.2f} s."]


MARKDOWN = {"hexapod": _hexapod_markdown, "planning": _planning_markdown,
            "positions": _positions_markdown, "constrained": _constrained_markdown, "wrist": _wrist_markdown,
            "speed": _speed_markdown}


def markdown(figures):
    """The measured parts as Markdown, one ### heading each."""
    blocks = []
    for name, render in MARKDOWN.items():
        if name in figures:
            title, lines = render(figures[name])
            blocks.append("\n".join([f"### {title}", "", *lines]))
    return "\n\n".join(blocks) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--part", choices=[*MARKDOWN, "all"], default="all")
    parser.add_argument("--json", type=Path, help="Also write the figures to this file as JSON.")
    arguments = parser.parse_args()
    parts = {"hexapod": hexapod, "planning": planning,
             "positions": positions, "constrained": constrained, "wrist": wrist, "speed": speed}
    figures = {name: part() for name, part in parts.items() if arguments.part in (name, "all")}
    print(markdown(figures))
    if arguments.json:
        arguments.json.write_text(json.dumps(figures, indent=1) + "\n")


if __name__ == "__main__":
    main()
