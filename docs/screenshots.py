"""The how-tos' screenshots of the 3D view in each report and of kingen view's own page, made
from real runs, not by hand.

    python docs/screenshots.py [--only check-path|calibrate|analyze|view] [--keep DIR]

Runs kingen as a user does (``python -m kingen.cli``, a real process): check-path on LinuxCNC's
sample hexapod with a CSV program that leaves its struts' travel and speed (the .ini written
here), calibrate on the hexapod from measurements of a perturbed hexapod (made here with kingen's
own model, device noise 10 um and 0.001 deg, joints read to 1 um), and analyze on the CEART
6-RUS; then opens each report.html in headless Chromium (WebGL through SwiftShader) with every
part of the page but the view hidden, and writes the screenshots to docs/images/
(check_path_view.png, calibrate_view.png, analyze_view.png). ``kingen view exechon_wrist``'s page is
opened whole, at a pose given in its address (VIEW_POSE), its routine answering (view.png).
Chromium is /usr/bin/chromium or ``$CHROMIUM``.
"""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

IMAGES = Path(__file__).resolve().parent / "images"
SIZE = (1100, 640)
"""The screenshots' width and height (px): the view's frame in a report."""
ONLY_THE_VIEW = ("<style>body > *:not(.kingen-view-frame) { display: none !important; } "
                 "body { margin: 0; max-width: none; }</style></head>")
INI = """[TRAJ]
LINEAR_UNITS = inch
MAX_LINEAR_VELOCITY = 20
MAX_LINEAR_ACCELERATION = 1000
""" + "".join(f"\n[JOINT_{index}]\nMAX_VELOCITY = 0.5\nMAX_ACCELERATION = 100\nMIN_LIMIT = 26\nMAX_LIMIT = 31\n"
              for index in range(6))
PROGRAM = "x,y,z,roll,pitch,yaw,feed\n0,0,508,0,0,0,600\n20,10,520,2,0,0,600\n0,0,560,0,0,0,600\n-30,0,540,0,-4,0,600\n"


def kingen(*arguments, codes=(0,)):
    """Run ``python -m kingen.cli`` with ``arguments``; its exit code must be one of ``codes``."""
    done = subprocess.run([sys.executable, "-m", "kingen.cli", *map(str, arguments)], capture_output=True, text=True)
    if done.returncode not in codes:
        raise SystemExit(f"kingen {' '.join(map(str, arguments))}: exit {done.returncode}\n{done.stderr}")


def check_path(folder):
    """check-path's report of PROGRAM on linuxcnc_hexapod with INI's limits."""
    (folder / "part.csv").write_text(PROGRAM)
    (folder / "hexapod.ini").write_text(INI)
    kingen("check-path", "linuxcnc_hexapod", folder / "part.csv", "--ini", folder / "hexapod.ini",
           "--html", folder / "report.html", codes=(1,))
    return folder / "report.html"


def calibrate(folder):
    """calibrate's report of the hexapod from 30 noisy measurements of a perturbed hexapod."""
    from kingen.calibrate.identification import region_poses
    from kingen.calibrate.measurements import write_measurements
    from kingen.calibrate.parameters import Parameters
    from kingen.calibrate.prediction import synthesize
    from kingen.conventions import t6_from_pose
    from kingen.kinematics.reference import solve
    from kingen.robot.model import load_robot

    robot = load_robot("hexapod")
    parameters = Parameters(robot, "pose")
    rng = np.random.default_rng(5)
    truth = parameters.nominal.copy()
    limbs = np.array([entry.limb is not None for entry in parameters.entries])
    truth[limbs] += rng.uniform(-0.5, 0.5, limbs.sum())
    truth[parameters.groups == "frame"] = [150.0, -80.0, 40.0, 2.0, -3.0, 25.0]
    poses = region_poses(robot, 120, 3)
    poses = poses[solve(robot, t6_from_pose(poses)).warnings[:, robot.working_posture] == 0][:30]
    joints, measured = synthesize(parameters, truth, poses, robot.working_posture)
    joints = np.round(joints / 0.001) * 0.001
    measured[:, :3] += rng.normal(0.0, 0.01, measured[:, :3].shape)
    measured[:, 3:] += rng.normal(0.0, 0.001, measured[:, 3:].shape)
    (folder / "measured.csv").write_text(write_measurements(robot, "pose", joints, measured))
    kingen("calibrate", "hexapod", "--measurements", folder / "measured.csv", "-o", folder / "calibration")
    return folder / "calibration" / "report.html"


def analyze(folder):
    """analyze's report of ceart."""
    kingen("analyze", "ceart", "-o", folder / "analysis")
    return folder / "analysis" / "report.html"


VIEW_POSE = "#pose=50,-20,-1380,165,8,40&posture=1"
"""exechon_wrist's first golden pose: the tool tilted 15 degrees, the A/C head on its branch 1."""


def view(folder):
    """kingen view's page of exechon_wrist, opened at VIEW_POSE."""
    kingen("view", "exechon_wrist", "-o", folder)
    return folder / "exechon_wrist.html"


REPORTS = {"check-path": (check_path, "check_path_view.png"), "calibrate": (calibrate, "calibrate_view.png"),
           "analyze": (analyze, "analyze_view.png"), "view": (view, "view.png")}


def screenshot(report, shot, scratch):
    """``shot``: the view of ``report`` alone, SIZE, in headless Chromium."""
    probe = scratch / f"{shot.stem}.html"
    page = report.read_text()
    probe.write_text(page.replace("</head>", ONLY_THE_VIEW, 1) if "kingen-view-frame" in page else page)
    address = probe.as_uri() + (VIEW_POSE if "kingen-view-frame" not in page else "")
    chromium = os.environ.get("CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
    subprocess.run([chromium, "--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                    "--no-first-run", "--disable-background-networking", "--hide-scrollbars",
                    f"--user-data-dir={scratch / 'profile'}", f"--window-size={SIZE[0]},{SIZE[1]}",
                    "--virtual-time-budget=10000", f"--screenshot={shot}", address],
                   check=True, capture_output=True, timeout=180)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=sorted(REPORTS), action="append")
    parser.add_argument("--keep", type=Path, help="Keep the runs' outputs in this folder.")
    options = parser.parse_args()
    with tempfile.TemporaryDirectory() as temporary:
        scratch = options.keep or Path(temporary)
        for name in options.only or REPORTS:
            make, image = REPORTS[name]
            folder = scratch / name
            folder.mkdir(parents=True, exist_ok=True)
            screenshot(make(folder), IMAGES / image, scratch)
            print(IMAGES / image)


if __name__ == "__main__":
    main()
