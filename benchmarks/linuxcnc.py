"""LinuxCNC's stock kinematics modules against kingen, printed as Markdown (for docs/how-to/linuxcnc.md's
LinuxCNC section and the closing notes). Needs Debian's linuxcnc-uspace (the modules) and
linuxcnc-uspace-dev (the headers, to build kingen's).

    python benchmarks/linuxcnc.py [--samples N] [--poses N]

1. Inverse agreement: every stock module against kingen's reference on N seeded poses of the
   shipped robot at its sample geometry (worst joint error, poses), and what verify says.
2. Forward iterations from the same seeds (a servo cycle and 10 mm / 5 degrees away) for
   kingen's module and genhexkins on LinuxCNC's sample hexapod. genhexkins' own count is
   unreadable through its pins (switchkins runs the forward a second time for its GUI
   pins), so it is measured as the smallest limit-iterations with which each call succeeds.
"""

import argparse
import tempfile
from pathlib import Path

import numpy as np

from kingen.hosts import get_host
from kingen.hosts.linuxcnc.checks.forward import SEEDS, regular_poses
from kingen.hosts.linuxcnc.loader import Module
from kingen.robot.model import load_robot
from kingen.kinematics.poses import sample_poses
from kingen.verify import VerifyOptions, verify_library

STOCK = Path("/usr/lib/linuxcnc/modules")
PAIRS = (("genhexkins", "linuxcnc_hexapod"), ("lineardeltakins", "linear_delta"), ("rotarydeltakins", "rotary_delta"))
MAX_LIMIT = 40


def inverse_agreement(samples):
    host = get_host("linuxcnc")
    print("| stock module | robot file | poses | worst joint error | verify says |\n| --- | --- | --- | --- | --- |")
    for module, robot_name in PAIRS:
        seen = host.as_seen(load_robot(robot_name))
        report = verify_library(seen, STOCK / f"{module}.so", module, VerifyOptions(samples=samples), host=host)
        worst = f"{report.max_abs_error_mm:.3g} mm" if report.max_abs_error_mm else f"{report.max_abs_error_rad:.3g} rad"
        says = "; ".join(f"FAILED {check.name}: {check.detail}" for check in report.failures) or "PASSED"
        print(f"| {module} | {robot_name} | {report.samples} | {worst} | {says} |")


def iterations(poses_count):
    host = get_host("linuxcnc")
    robot = load_robot("linuxcnc_hexapod")
    seen = host.as_seen(robot)
    with tempfile.TemporaryDirectory() as folder:
        built = host.build(robot, Path(folder) / "module")
        kingen_module = Module(built.library, built.routine, seen, inch=True)
        stock = Module(STOCK / "genhexkins.so", "genhexkins", seen, inch=True)
        poses, joints = regular_poses(seen, sample_poses(seen, poses_count, seed=1))
        machine_joints = np.zeros((len(poses), 16))
        machine_joints[:, :6] = joints / kingen_module.joint_scale()
        generator = np.random.default_rng(0)
        print("\n| seeds | module | converged | iterations mean | max |\n| --- | --- | --- | --- | --- |")
        for label, (distance_mm, distance_deg) in SEEDS.items():
            offset = np.concatenate([_unit(generator, len(poses)) * distance_mm, _unit(generator, len(poses)) * distance_deg], 1)
            seeds = np.zeros((len(poses), 9))
            seeds[:, :3] = (poses[:, :3] + offset[:, :3]) / 25.4
            seeds[:, 3:6] = poses[:, 3:] + offset[:, 3:]
            _, returns, counts = kingen_module.forward(machine_joints, seeds)
            ok = returns == 0
            print(f"| {label} | kingen | {ok.sum()} of {len(poses)} | {counts[ok].mean():.2f} | {int(counts[ok].max())} |")
            needed = np.full(len(poses), np.nan)
            for limit in range(1, MAX_LIMIT + 1):
                open_ = np.isnan(needed)
                if not open_.any():
                    break
                _set(stock, "genhexkins.limit-iterations", limit)
                _, returns, _ = stock.forward(machine_joints[open_], seeds[open_])
                needed[np.flatnonzero(open_)[returns == 0]] = limit
            done = np.isfinite(needed)
            print(f"| {label} | genhexkins | {done.sum()} of {len(poses)} | {needed[done].mean():.2f} | "
                  f"{int(needed[done].max())} |")


def _set(module, name, value):
    from kingen.hosts.linuxcnc.loader import _hal

    assert _hal().kingen_hal_set(name.encode(), float(value)) == 0, name


def _unit(generator, count):
    vectors = generator.normal(size=(count, 3))
    return vectors / np.linalg.norm(vectors, axis=1, keepdims=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=100000)
    parser.add_argument("--poses", type=int, default=1000)
    arguments = parser.parse_args()
    inverse_agreement(arguments.samples)
    iterations(arguments.poses)


if __name__ == "__main__":
    main()
