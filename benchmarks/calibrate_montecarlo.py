"""Calibration's stated standard deviations against a Monte-Carlo, printed as Markdown and with
--json written as plain data (a section of the performance page, benchmarks/sections.py; its
bounded form is tests/test_calibrate_noise.py's).

    python benchmarks/calibrate_montecarlo.py [--seeds 30] [--poses 50] [--robot hexapod] [--json FILE]

Each seed draws a new machine (every limb parameter moved by up to PLANTED_MM or PLANTED_DEG),
a new tracker pose (the measuring frame anywhere within FRAME_MM and FRAME_DEG) and new noise:
the device's 10 um per position coordinate and 20 urad per angle, the joints read with 1 um
(normal, independent), exactly the noise calibrate is told (--noise-*). The poses are the
plan's for that noise. The machine is identified from the noisy measurements and, for its
gauge (the identified parameters' values with those kept nominal held), from exact ones; each
identified parameter's z is (noisy - exact) / stated std. A normal law gives an RMS z of 1,
|z| within 3 in 99.73 % of the draws, and beyond 3 a count whose 99th percentile is the bound
reported: drawn (NULL_DRAWS times) from the normal law with each seed's stated correlations
between its parameters, for one noise draw moves correlated parameters together (the
binomial's, which takes them independent, is reported beside it).
"""

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
from scipy.stats import binom

from kingen.calibrate import plan
from kingen.calibrate.identification import identify
from kingen.calibrate.measurements import Measurements
from kingen.calibrate.noise import Noise
from kingen.calibrate.parameters import Parameters
from kingen.calibrate.prediction import synthesize
from kingen.robot.model import load_robot

ABOUT = ("Whether the standard deviations `kingen calibrate` states are the spread of what it identifies: "
         "each seed a new machine, a new tracker pose and new noise of the size calibrate is told "
         "([Calibrate a robot](how-to/calibrate.md): the noise model); z is the identified value's "
         "distance from the noise-free fit's (the same machine and poses) in stated standard deviations.")
"""What the section measures, for the performance page (links relative to docs/)."""
NOISE = Noise(device_mm=0.01, device_deg=math.degrees(20e-6), joint_mm=0.001, joint_deg=math.degrees(1e-6))
PLANTED_MM, PLANTED_DEG = 0.5, 0.05
FRAME_MM, FRAME_DEG = 200.0, 30.0
BEYOND = 3.0
NULL_DRAWS = 4000
"""Draws of the normal law with each seed's stated correlations behind the bound of the count beyond BEYOND."""
NORMAL_OUTSIDE = 2.0 * (1.0 - 0.5 * (1.0 + math.erf(BEYOND / math.sqrt(2.0))))
"""The share of a normal law's draws beyond BEYOND standard deviations (0.27 %)."""


def truth_of(parameters, rng):
    """A drawn machine: nominal values, each limb parameter moved by up to PLANTED_MM or
    PLANTED_DEG, the measuring frame within FRAME_MM and FRAME_DEG of the base frame."""
    values = parameters.nominal.copy()
    for index, entry in enumerate(parameters.entries):
        if entry.limb is not None:
            values[index] += (PLANTED_MM if entry.unit == "mm" else PLANTED_DEG) * rng.uniform(-1.0, 1.0)
    values[parameters.groups == "frame"] = rng.uniform(-1.0, 1.0, 6) * np.array([FRAME_MM] * 3 + [FRAME_DEG] * 3)
    return values


def measured(parameters, truth, poses, rng):
    """Measurements of the machine ``truth`` at ``poses`` (mm, degrees): exact without ``rng``,
    else with NOISE drawn from it."""
    robot = parameters.robot
    joints, values = synthesize(parameters, truth, poses, robot.working_posture)
    if rng is not None:
        joint_sigma = np.where(robot.revolute, math.radians(NOISE.joint_deg), NOISE.joint_mm)
        joints = joints + rng.normal(0.0, 1.0, joints.shape) * joint_sigma
        sigma = np.array([NOISE.device_mm] * 3 + [NOISE.device_deg] * 3)[:values.shape[1]]
        values = values + rng.normal(0.0, 1.0, values.shape) * sigma
    return Measurements("synthetic", parameters.measure, joints, values, tuple(range(2, len(poses) + 2)), ())


def montecarlo(seeds, poses=50, robot="hexapod", first_seed=1000):
    """The figures of ``seeds`` draws on ``poses`` planned poses of ``robot``."""
    started = time.perf_counter()
    parameters = Parameters(load_robot(robot), "pose")
    selected = parameters.selected("all")
    found = plan.candidates(parameters, selected, NOISE)
    chosen_poses = found.poses[plan.greedy(found.weighted, poses, plan.limb_columns(found, parameters))]
    z, evaluations, outliers, factors, null = [], [], 0, [], 0
    for seed in range(first_seed, first_seed + seeds):
        rng = np.random.default_rng(seed)
        truth = truth_of(parameters, rng)
        gauge = identify(parameters, measured(parameters, truth, chosen_poses, None), selected, NOISE)
        fit = identify(parameters, measured(parameters, truth, chosen_poses, rng), selected, NOISE)
        if not (fit.converged and gauge.converged and np.array_equal(fit.chosen, gauge.chosen)):
            raise SystemExit(f"seed {seed}: converged {fit.converged}, {gauge.converged}; the same parameters "
                             f"identified {np.array_equal(fit.chosen, gauge.chosen)}")
        z.append(((fit.values - gauge.values) / fit.std)[fit.chosen])
        null = null + _beyond_under_normal(fit.covariance, np.random.default_rng(seed + 1))
        evaluations.append(fit.evaluations)
        outliers += len(fit.outliers)
        factors.append(fit.inference.variance_factor)
    z = np.array(z)
    names = np.array(parameters.names)[fit.chosen]
    coverage = np.mean(np.abs(z) <= BEYOND, axis=0)
    spread = np.sqrt(np.mean(z ** 2, axis=0))
    draws = z.size
    return {"robot": robot, "seeds": seeds, "poses": poses, "parameters": int(z.shape[1]), "draws": int(draws),
            "rms_z": float(np.sqrt(np.mean(z ** 2))), "least_coverage": float(coverage.min()),
            "least_covered": str(names[int(np.argmin(coverage))]), "beyond": int(np.sum(np.abs(z) > BEYOND)),
            "beyond_expected": draws * NORMAL_OUTSIDE, "beyond_likely": int(np.percentile(null, 99)),
            "beyond_likely_independent": int(binom.isf(0.01, draws, NORMAL_OUTSIDE)),
            "worst_z": float(np.max(np.abs(z))), "parameter_rms_z": [float(spread.min()), float(spread.max())],
            "variance_factor": [float(min(factors)), float(np.median(factors)), float(max(factors))],
            "evaluations": [int(min(evaluations)), int(max(evaluations))], "outliers": outliers,
            "seconds": time.perf_counter() - started}


def _beyond_under_normal(covariance, rng):
    """(NULL_DRAWS,) how many of the parameters lie beyond BEYOND in draws of the normal law of
    ``covariance`` (its correlations)."""
    scale = np.sqrt(np.diag(covariance))
    correlation = covariance / np.outer(scale, scale)
    draws = rng.multivariate_normal(np.zeros(len(scale)), correlation, NULL_DRAWS, method="eigh")
    return np.sum(np.abs(draws) > BEYOND, axis=1)


def markdown(part):
    """The figures as the performance page's lines (a paragraph and a table)."""
    return "\n".join([
        f"{part['seeds']} seeds, each a new {part['robot']} (limb parameters moved by up to {PLANTED_MM:g} mm / "
        f"{PLANTED_DEG:g} deg), a new tracker pose (within {FRAME_MM:g} mm and {FRAME_DEG:g} deg) and new noise "
        f"(10 um, 20 urad, joints 1 um: as stated to calibrate), on {part['poses']} planned poses; z = (identified "
        f"- identified without noise) / stated std, {part['draws']} draws over {part['parameters']} identified "
        f"parameters ({part['seconds']:.0f} s).", "",
        "| RMS z | per parameter: RMS z least, most | least coverage of 3 sigma | beyond 3 sigma (normal law: "
        "expected, 99th percentile with the stated correlations, independent) | largest z | variance factor (least, "
        "median, most) | evaluations | outliers |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
        f"| {part['rms_z']:.3f} | {part['parameter_rms_z'][0]:.2f}, {part['parameter_rms_z'][1]:.2f} | "
        f"{part['least_coverage'] * 100:.1f} % ({part['least_covered']}) | {part['beyond']} ({part['beyond_expected']:.1f}, "
        f"{part['beyond_likely']}, {part['beyond_likely_independent']}) | {part['worst_z']:.2f} | {part['variance_factor'][0]:.2f}, "
        f"{part['variance_factor'][1]:.2f}, {part['variance_factor'][2]:.2f} | {part['evaluations'][0]} to "
        f"{part['evaluations'][1]} | {part['outliers']} |"])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=30)
    parser.add_argument("--poses", type=int, default=50)
    parser.add_argument("--robot", default="hexapod")
    parser.add_argument("--json", type=Path, help="Also write the figures to this file as JSON.")
    arguments = parser.parse_args()
    figures = montecarlo(arguments.seeds, arguments.poses, arguments.robot)
    print(markdown(figures))
    if arguments.json:
        arguments.json.write_text(json.dumps(figures, indent=1) + "\n")


if __name__ == "__main__":
    main()
