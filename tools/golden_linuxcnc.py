"""Golden values from LinuxCNC's own kinematics modules (Debian's linuxcnc-uspace,
/usr/lib/linuxcnc/modules), not from kingen's reference:

    python tools/golden_linuxcnc.py hexapod flexapod stewart_gough_example
    python tools/golden_linuxcnc.py linuxcnc_hexapod linear_delta rotary_delta

The stock robots (LinuxCNC's sample hexapod, linear and rotary delta) are at their modules'
default geometry: the module is loaded as shipped, given each pose in the robot file's
units, and its joints are the golden joints as they stand (genhexkins: absolute strut
lengths, reference_length 0; the deltas: carriage heights, crank degrees, at the working
posture 7). For the other leg robots:

genhexkins is loaded through the HAL stand-in kingen's LinuxCNC tests use, on a mm machine,
its base.N / platform.N pins set to the robot file's points (for the Stewart-Gough layout,
computed here from the layout's equation in docs/explanation/conventions.md, not by kingen's layout
code); its kinematicsInverse is given each pose as LinuxCNC's EmcPose (x y z mm, a b c
degrees: pmRpyMatConvert's R = Rz(c) Ry(b) Rx(a), the same convention as kingen's poses)
and answers each strut's absolute length. The joint kingen reports is that length minus
the leg's reference length L0 (docs/explanation/conventions.md, Leg). Prints YAML golden entries.
"""

import math
import sys
from pathlib import Path

import numpy as np

from kingen.hosts.linuxcnc.loader import Module
from kingen.robot.model import load_robot
from kingen.robot.reading import read_robot_file

MODULES = Path("/usr/lib/linuxcnc/modules")
GENHEXKINS = MODULES / "genhexkins.so"
STOCK = {"linuxcnc_hexapod": "genhexkins", "linear_delta": "lineardeltakins", "rotary_delta": "rotarydeltakins"}
POSES = {
    "hexapod": ([12.5, -7.25, 470.0, 3.5, -2.25, 6.0], [-31.0, 22.0, 452.5, -6.0, 4.5, -9.0]),
    "flexapod": ([9.5, -14.0, 505.0, -2.5, 3.0, 7.5], [-21.0, 17.5, 488.0, 5.0, -4.0, -6.5]),
    "stewart_gough_example": ([6.0, -11.0, 262.0, 2.0, -3.5, 4.0], [-14.5, 9.0, 238.0, -4.0, 2.5, -3.0]),
    "linuxcnc_hexapod": ([0.6, -0.35, 20.8, 4.0, -3.0, 5.0], [-1.1, 0.9, 19.2, -6.0, 5.0, -7.5]),  # inch, deg
    "linear_delta": ([35.0, -20.0, 22.0, 0, 0, 0], [-50.0, 42.5, 5.0, 0, 0, 0]),  # mm
    "rotary_delta": ([1.5, -0.8, -13.2, 0, 0, 0], [-2.1, 1.7, -15.5, 0, 0, 0]),  # inch
}


def layout_points(layout):
    """Base and platform points of the Stewart-Gough layout, by its equation: point i at angle
    60 + 120 floor(i / 2) -/+ pair / 2 degrees (minus for even i), at z = base_height or
    platform_height (docs/explanation/conventions.md, Layouts)."""
    base, platform = [], []
    for i in range(6):
        sign = -1 if i % 2 == 0 else 1
        for radius, pair, height, out in ((layout["base_radius"], layout["base_pair_angle"],
                                           layout.get("base_height", 0.0), base),
                                          (layout["platform_radius"], layout["platform_pair_angle"],
                                           layout.get("platform_height", 0.0), platform)):
            angle = math.radians(60 + 120 * (i // 2) + sign * pair / 2)
            out.append((radius * math.cos(angle), radius * math.sin(angle), height))
    return base, platform, [layout["reference_length"]] * 6


def geometry(name):
    data = read_robot_file(Path(__file__).resolve().parent.parent / "robots" / f"{name}.yaml")[0]
    if "layout" in data:
        return layout_points(data["layout"])
    limbs = data["limbs"]
    return ([limb["base_point"] for limb in limbs], [limb["platform_point"] for limb in limbs],
            [limb["reference_length"] for limb in limbs])


def genhexkins_lengths(name, poses):
    base, platform, reference = geometry(name)
    setp = {f"genhexkins.{kind}.{index}.{axis}": float(value)
            for kind, points in (("base", base), ("platform", platform))
            for index, point in enumerate(points) for axis, value in zip("xyz", point)}
    module = Module(GENHEXKINS, "genhexkins", load_robot(name), setp=setp)
    world = np.zeros((len(poses), 9))
    world[:, :6] = poses
    joints, returns, _ = module.inverse(world)
    assert np.all(returns == 0), returns
    return joints[:, :6], np.asarray(reference, dtype=float)


def stock_joints(name, poses):
    """The stock module's joints at ``poses`` (file units), as loaded with no pin set."""
    robot = load_robot(name)
    module = Module(MODULES / f"{STOCK[name]}.so", STOCK[name], robot)
    world = np.zeros((len(poses), 9))
    world[:, :6] = poses
    joints, returns, _ = module.inverse(world)
    assert np.all(returns == 0), returns
    return joints[:, :robot.dof], robot.working_posture


def stock_entries(name):
    joints, posture = stock_joints(name, np.array(POSES[name], dtype=float))
    tolerance = "0.000001"
    for pose, values in zip(POSES[name], joints):
        print(f"  - source: >\n      LinuxCNC 2.9 {STOCK[name]} as shipped (kinematicsInverse, Debian linuxcnc-uspace),\n"
              "      at a non-symmetric pose: its joints as they stand (tools/golden_linuxcnc.py).\n"
              f"    pose: {list(pose)}\n" + (f"    posture: {posture}\n" if posture else "")
              + f"    joints: [{', '.join(f'{value:.9f}' for value in values)}]\n    tolerance: {tolerance}")


def main(names):
    for name in names:
        if name in STOCK:
            print(f"# {name}")
            stock_entries(name)
            continue
        poses = POSES[name]
        lengths, reference = genhexkins_lengths(name, np.array(poses, dtype=float))
        print(f"# {name}")
        for pose, strut in zip(poses, lengths):
            joints = ", ".join(f"{value:.6f}" for value in strut - reference)
            print("  - source: >\n      LinuxCNC 2.9 genhexkins (kinematicsInverse, Debian linuxcnc-uspace) with this\n"
                  "      file's base and platform points, at a non-symmetric pose: its absolute strut\n"
                  f"      lengths {', '.join(f'{value:.6f}' for value in strut)} mm minus L0\n"
                  "      (tools/golden_linuxcnc.py).\n"
                  f"    pose: {list(pose)}\n    joints: [{joints}]\n    tolerance: 0.000005")


if __name__ == "__main__":
    main(sys.argv[1:] or list(POSES))
