"""Golden crank angles for the 6-RUS robots, computed independently of kingen's code:

    python tools/golden_cranks.py iwf rus_optimized ceart

The robot file is read as plain YAML (no kingen); the pivots A_i and platform points c_i
come from the 6-RUS thesis's layout equations as docs/explanation/conventions.md restates them; the
pose is R = Rz(yaw) Ry(pitch) Rx(roll) (the thesis's and LinuxCNC's fixed-axis order). Each
crank angle is a root of the closure |B(theta) - N|^2 - L^2 with
B(theta) = A + r (cos theta cos beta, cos theta sin beta, -sin theta), found by scanning
theta over a turn in 0.1-degree steps and refining each sign change with scipy's brentq to
1e-13 rad: no closed form, no acos, nothing shared with kingen/robot/limbs/crank.py. Branch 0 is
the root that turns past the direction from the pivot to N (in the crank's plane), branch 1
the other (docs/explanation/conventions.md, Postures). Checked against the CEART simulator's CAE crank
angles at its home (robots/ceart.yaml): -43.394 and 32.345 degrees.
"""

import math
import sys
from pathlib import Path

import numpy as np
from ruamel.yaml import YAML
from scipy.optimize import brentq

ROBOTS = Path(__file__).resolve().parent.parent / "robots"
POSES = {
    "iwf": ([12.0, -8.0, -495.0, 2.0, -1.5, 3.0], [-15.0, 10.0, -520.0, -3.0, 2.5, -4.0]),
    "rus_optimized": ([20.0, -15.0, -395.0, 3.0, -4.0, 5.0], [-25.0, 18.0, -420.0, -5.0, 3.5, -6.0]),
    "ceart": ([25.0, -30.0, -430.0, 4.0, -3.0, 6.0],),
}


def layout(name):
    data = YAML(typ="safe").load((ROBOTS / f"{name}.yaml").read_text())
    return data["layout"], data["working_posture"]


def pivots_and_points(geometry):
    """A_i and c_i, i = 1..6: m = (-1)^(i-1) e_b, n = (-1)^(i-1) e_p,
    A_i = (rb cos chi - m sin chi, rb sin chi + m cos chi, 0), c_i likewise with rp, n."""
    pivots, points = [], []
    for i in range(1, 7):
        chi = math.radians(geometry["pair_angles"][i - 1])
        sign = (-1) ** (i - 1)
        m, n = sign * geometry["base_half_distance"], sign * geometry["platform_half_distance"]
        rb, rp = geometry["base_radius"], geometry["platform_radius"]
        pivots.append([rb * math.cos(chi) - m * math.sin(chi), rb * math.sin(chi) + m * math.cos(chi), 0.0])
        points.append([rp * math.cos(chi) - n * math.sin(chi), rp * math.sin(chi) + n * math.cos(chi), 0.0])
    return np.array(pivots), np.array(points)


def rotation(roll, pitch, yaw):
    a, b, c = (math.radians(v) for v in (roll, pitch, yaw))
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    rz = np.array([[math.cos(c), -math.sin(c), 0], [math.sin(c), math.cos(c), 0], [0, 0, 1]])
    return rz @ ry @ rx


def crank_roots(pivot, beta, r, rod, target):
    def closure(theta):
        tip = pivot + r * np.array([math.cos(theta) * math.cos(beta), math.cos(theta) * math.sin(beta), -math.sin(theta)])
        return float(np.sum((tip - target) ** 2) - rod * rod)

    grid = np.radians(np.arange(-180.0, 180.0001, 0.1))
    values = [closure(theta) for theta in grid]
    roots = [brentq(closure, a, b, xtol=1e-13) for a, b, fa, fb in zip(grid, grid[1:], values, values[1:])
             if fa == 0.0 or fa * fb < 0.0]
    toward = math.atan2(-(target - pivot)[2], (target - pivot)[0] * math.cos(beta) + (target - pivot)[1] * math.sin(beta))
    assert len(roots) == 2, roots
    ahead = [math.remainder(root - toward, 2 * math.pi) > 0 for root in roots]
    assert ahead[0] != ahead[1]
    return (roots[0], roots[1]) if ahead[0] else (roots[1], roots[0])  # (branch 0, branch 1)


def crank_angles(name, pose, posture):
    geometry, _ = layout(name)
    pivots, points = pivots_and_points(geometry)
    placed = points @ rotation(*pose[3:]).T + np.asarray(pose[:3])
    angles = []
    for i in range(6):
        branches = crank_roots(pivots[i], math.radians(geometry["crank_directions"][i]), geometry["crank_length"],
                               geometry["rod_length"], placed[i])
        angles.append(math.degrees(branches[(posture >> (5 - i)) & 1]))  # crank 1 is the most significant digit
    return angles


def main(names):
    home = crank_angles("ceart", [0, 0, -450, 0, 0, 0], 63)
    assert np.allclose(home, [-43.394, 32.345] * 3, atol=5e-4), home  # the CAE model's angles
    for name in names:
        _, posture = layout(name)
        print(f"# {name}")
        for pose in POSES[name]:
            angles = ", ".join(f"{value:.6f}" for value in crank_angles(name, pose, posture))
            print("  - source: >\n      Independent 6-RUS inverse (tools/golden_cranks.py): the thesis's layout\n"
                  "      equations, each crank angle a brentq root of its closure |B - N| = L, checked\n"
                  "      against the CEART simulator's CAE angles at its home.\n"
                  f"    pose: {list(pose)}\n    posture: {posture}\n    joints: [{angles}]\n    tolerance: 0.00001")


if __name__ == "__main__":
    main(sys.argv[1:] or list(POSES))
