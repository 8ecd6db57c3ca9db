"""Machines a user could write, drawn at random (tests/machines.py), and the regression files
their failing draws shrank to (tests/data/random_machines/): verify gives no false verdict.

For each machine: `kingen verify` passes on every host that accepts it (a real process per
host, as a user runs it), LinuxCNC's refusal of a far pose is the reference's (the pose is out
of every limb's reach in every posture), forward kinematics returns the pose the reference's
joints came from, and a machine singular everywhere fails the ``machine`` check. CI draws a
fixed, bounded set (hypothesis profile 'ci'); KINGEN_FULL_SWEEPS=1 draws many more."""

import contextlib
import io
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from hypothesis import HealthCheck, assume, given, settings, strategies as st

from conftest import require_linuxcnc_headers
from machines import coincident_tricept, in_units, machines
from kingen.cli import main
from kingen.hosts.linuxcnc.checks.refusal import far_pose
from kingen.kinematics.home import judged_posture
from kingen.kinematics.routine import WARNINGS
from kingen.robot.model import robot_from_data
from kingen.conventions import pose_from_t6, t6_from_pose
from kingen.hosts.linuxcnc.render import robot_problem
from kingen.kinematics.reference import solve as reference_solve
from kingen.robot.model import load_robot
from kingen.runtime.resources import robots_dir
from kingen.verify.checks.machine import machine_check

REGRESSIONS = sorted((Path(__file__).parent / "data" / "random_machines").glob("*.yaml"))
HOSTS = ("delmia", "c", "linuxcnc")
SAMPLES = 300
"""Poses verify draws per machine and host: enough to reach every warning's boundary rays."""
FULL = bool(os.environ.get("KINGEN_FULL_SWEEPS"))
DRAWS = int(os.environ.get("KINGEN_RANDOM_DRAWS", 1000 if FULL else 20))
"""Machines drawn: 20 in CI (3 to 5 s each: three hosts' builds and verify runs), 1,000 on demand."""
DRAWN = settings(max_examples=DRAWS, deadline=None, database=None if FULL else settings.default.database,
                 suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                        HealthCheck.filter_too_much, HealthCheck.data_too_large])
LOG = os.environ.get("KINGEN_DRAWS_LOG")
"""A file each draw's family and verdict is appended to (the sweep's count per family), when set."""


def accepting_hosts(robot):
    """The hosts that take ``robot`` (LinuxCNC refuses robots it cannot drive, with exit 2)."""
    return [host for host in HOSTS if host != "linuxcnc" or robot_problem(robot) is None]


def run_verify(path, host, tmp_path, samples=SAMPLES):
    """`kingen verify PATH --host HOST` in a new process (in this one, through kingen.cli.main,
    when KINGEN_RANDOM_IN_PROCESS is set: a long sweep saves the start): (exit code, stdout, stderr)."""
    arguments = ["verify", str(path), "--host", host, "--samples", str(samples), "--out-dir", str(tmp_path / host)]
    if os.environ.get("KINGEN_RANDOM_IN_PROCESS"):
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(arguments)
        return code, out.getvalue(), err.getvalue()
    done = subprocess.run([sys.executable, "-m", "kingen.cli", *arguments], capture_output=True, text=True, timeout=300)
    return done.returncode, done.stdout, done.stderr


def expectation(path):
    """A regression file's ``# expect:`` line: 'pass', 'fail CHECK' (the one check that fails), or
    'xfail CHECK': a false verdict found and not yet fixed (the test is expected to fail until it is)."""
    found = re.search(r"^# expect: (.+)$", path.read_text(), re.MULTILINE)
    assert found, f"{path.name}: a regression file says what verify must answer ('# expect: pass')"
    return found.group(1).strip()


@pytest.mark.parametrize("path", [pytest.param(path, marks=pytest.mark.xfail(
    reason=expectation(path), strict=True)) if expectation(path).startswith("xfail") else path for path in REGRESSIONS],
    ids=[path.stem for path in REGRESSIONS])
def test_regression_file_verdict(path, tmp_path):
    robot = load_robot(str(path))
    expected = "pass" if expectation(path).startswith("xfail") else expectation(path)
    hosts = accepting_hosts(robot)
    if "linuxcnc" in hosts:
        require_linuxcnc_headers()
    for host in hosts:
        code, out, err = run_verify(path, host, tmp_path)
        failed = re.findall(r"^  FAILED (.+?):", out, re.MULTILINE)
        if expected == "pass":
            assert code == 0 and not failed, f"{path.name} on {host}: {failed}\n{out}{err}"
        else:
            assert code == 1 and failed == [expected.removeprefix("fail ")], f"{path.name} on {host}:\n{out}{err}"


def metres_hexapod(folder, units):
    """The shipped thesis hexapod with every length divided by 1000 (its file in metres), with a
    ``units:`` line when ``units`` is given: (path, its joints in the file's units at the pose
    (12.5, -7.25, 470) mm, (3.5, -2.25, 6) degrees, from the mm robot's reference)."""
    document = yaml.safe_load((robots_dir() / "hexapod.yaml").read_text())
    document.pop("golden")
    for limb in document["limbs"]:
        limb["base_point"] = [value / 1000 for value in limb["base_point"]]
        limb["platform_point"] = [value / 1000 for value in limb["platform_point"]]
        limb["reference_length"] /= 1000
    document["singularity"]["direct_index_min"] /= 1000
    region = document["verification"]
    for key in ("home", "range"):
        region[key] = [value / 1000 for value in region[key][:3]] + region[key][3:]
    if units:
        document["units"] = units
    path = folder / f"hexapod_{units or 'unitless'}.yaml"
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    pose = np.array([[12.5, -7.25, 470.0, 3.5, -2.25, 6.0]])
    return path, reference_solve(load_robot("hexapod"), t6_from_pose(pose)).joints[0, :, 0] / 1000


def test_a_hexapod_in_metres_fails_without_units_m_and_passes_with_it(tmp_path):
    require_linuxcnc_headers()
    unitless, _ = metres_hexapod(tmp_path, None)
    stated, joints = metres_hexapod(tmp_path, "m")
    for host in HOSTS:
        code, out, err = run_verify(unitless, host, tmp_path)
        assert code == 1 and re.findall(r"^  FAILED (.+?):", out, re.MULTILINE) == ["machine"], out + err
        assert "less than 10 mm: the file states no units" in out and "add the line 'units: m'" in out
        code, out, err = run_verify(stated, host, tmp_path)
        assert code == 0, out + err
    refused = subprocess.run([sys.executable, "-m", "kingen.cli", "package", str(unitless), "--host", "linuxcnc",
                              "-o", str(tmp_path / "refused")], capture_output=True, text=True)
    assert refused.returncode == 2 and len(refused.stderr.splitlines()) == 1 and not (tmp_path / "refused").exists()
    robot = load_robot(str(stated))
    assert robot.length_unit == "m" and robot.size_mm == pytest.approx(load_robot("hexapod").size_mm)
    pose = np.array([[12.5, -7.25, 470.0, 3.5, -2.25, 6.0]])
    assert np.allclose(reference_solve(robot, t6_from_pose(pose)).joints[0, :, 0] / 1000, joints, rtol=0, atol=1e-12)


def test_a_home_off_the_manifold_by_more_than_the_tolerance_is_named_with_its_deviation(tmp_path):
    """vertical_prs with its rail points rounded to one decimal: its home (0, 0, -500) is off the
    manifold in y by what Newton on the constraint planes gives (test_hybrid.independent_pose),
    about ten times the tolerance (1e-5 of the machine's size); the machine check says so."""
    from test_hybrid import independent_pose

    text = (REGRESSIONS[0].parent / "vertical_prs.yaml").read_text().replace("458.9934640057092", "458.9")
    path = tmp_path / "coarse_prs.yaml"
    path.write_text(text)
    robot = load_robot(str(path))
    pose = independent_pose(robot, -500.0, 0.0, 0.0)
    x, y, yaw = pose[0], pose[1], pose[5]
    tolerance = 1e-5 * robot.size_mm
    assert abs(y) > 5 * tolerance and abs(x) < tolerance and abs(yaw) < 1e-7
    detail = machine_check(robot).detail
    assert detail.startswith(f"the verification home is off the machine's manifold by {abs(y):.3g} mm in y "
                             f"(tolerance {tolerance:.3g} mm, 1e-05 of its {robot.size_mm:g} mm size): the machine's "
                             f"pose for its z, roll, pitch there is x y z roll pitch yaw = "), detail
    shown = [float(value) for value in detail.split("yaw = ")[1].split(" (mm")[0].split()]
    assert np.allclose(shown, pose, rtol=0, atol=1e-8)


def write_machine(folder, document):
    """The drawn robot file, in ``folder`` (a name of its own per draw)."""
    path = folder / f"{document['name']}.yaml"
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


def failed_checks(out):
    return re.findall(r"^  FAILED (.+?):", out, re.MULTILINE)


def forward_poses(path, robot, tmp_path):
    """`kingen fk` for the reference's joints at the verification home in the judged posture:
    (the home's T6 (4, 4), the modes' T6 (k, 4, 4), the method line)."""
    home = np.array(robot.verification.home, dtype=float)
    joints = reference_solve(robot, t6_from_pose(home[None])).joints[0, :, judged_posture(robot).posture]
    given = joints / robot.joint_scale()
    report = tmp_path / "fk.json"
    assert main(["fk", str(path), "--joints", " ".join(f"{value:.17g}" for value in given),
                 "--json", str(report)]) == 0
    data = json.loads(report.read_text())
    poses = np.array([mode["pose"] for mode in data["solutions"]]).reshape(-1, 6)
    return t6_from_pose(home[None])[0], t6_from_pose(poses), data["method"]


def verdict_problems(family, document, folder):
    """What is wrong with kingen's verdicts on a drawn machine that must pass: each accepting
    host's verify (a real process) not passing, LinuxCNC not accepting it, a far pose LinuxCNC's
    refusal used that the reference reaches, fk finding no mode within 1e-6 (of the machine's size;
    of a unit axis) of the home its joints came from (a two-axis wrist: the tool tip and axis; the
    turn about it is free). Empty: no false verdict."""
    path = write_machine(folder, document)
    robot = robot_from_data(document, path)
    problems, hosts = [], accepting_hosts(robot)
    if "linuxcnc" not in hosts:
        problems.append(f"LinuxCNC refuses it: {robot_problem(robot)}")
    for host in hosts:
        code, out, err = run_verify(path, host, folder)
        if code != 0:
            problems.append(f"verify --host {host} exits {code}: {failed_checks(out)} {err.strip()}\n{out}")
        if re.search(r"out of every limb's reach", out):
            far, _ = far_pose(robot)
            if not np.all(reference_solve(robot, t6_from_pose(far[None])).warnings == WARNINGS["WARN_UNREACHABLE"]):
                problems.append(f"LinuxCNC's refusal used {far}, which the reference reaches")
    home, modes, method = forward_poses(path, robot, folder)
    columns = [2] if robot.wrist is not None and not robot.wrist.whole_pose else [0, 1, 2]
    apart = [max(np.max(np.abs(mode[3, :3] - home[3, :3])) / robot.size_mm,
                 np.max(np.abs(mode[columns, :3] - home[columns, :3]))) for mode in modes]  # T6 rows: the axes
    if not apart or min(apart) > 1e-6:  # Newton's answer, to what the pose's conditioning allows
        problems.append(f"fk finds no mode at the home its joints came from ({method})")
    return problems


@DRAWN
@given(drawn=machines())
def test_a_drawn_machine_gets_no_false_verdict(drawn, tmp_path_factory):
    family, document = drawn
    problems = verdict_problems(family, document, tmp_path_factory.mktemp("drawn"))
    if LOG:  # the sweep's count per family: one line per draw
        with open(LOG, "a") as log:
            log.write(f"{family}\t{'false verdict' if problems else 'ok'}\n")
    assert not problems, f"{family}:\n{yaml.safe_dump(document)}\n" + "\n".join(problems)


@settings(max_examples=3 if not FULL else 30, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(drawn=coincident_tricept())
def test_a_machine_singular_everywhere_fails_machine_and_fk_names_the_continuum(drawn, tmp_path_factory):
    family, document = drawn
    folder = tmp_path_factory.mktemp("coincident")
    path = write_machine(folder, document)
    robot = robot_from_data(document, path)
    code, out, err = run_verify(path, "c", folder)
    assert code == 1 and failed_checks(out) == ["machine"], out + err
    assert "the closure Jacobian at the verification home is singular" in out
    _, modes, method = forward_poses(path, robot, folder)
    assert method.startswith("not exhaustive: the geometry has a continuum of solutions") and len(modes) == 1, method


def test_solve_says_how_far_a_pose_is_off_the_manifold(capsys):
    """The Exechon thesis's pose (100, 50, -1250, 0, 0, 0) is off the constrained machine's
    manifold: the machine pitches by -4.57 degrees there (the tilt the thesis saw DELMIA take,
    docs/how-to/hybrid.md); solve names the coordinate, the deviation and the tolerance."""
    assert main(["solve", "exechon_constrained", "--pose", "100", "50", "-1250", "0", "0", "0"]) == 0  # solve prints; it judges nothing
    out = capsys.readouterr().out
    assert "the T6 is off its manifold by 4.57 degrees in pitch (tolerance 0.00172 degrees)" in out, out


@pytest.mark.parametrize("name", ["exechon_constrained", "tricept", "prs_head", "rps_table"])
def test_published_poses_rounded_as_a_drawing_gives_them_are_on_the_manifold(name):
    """Each golden pose of a shipped machine with task coordinates (an independent computation's,
    to 9 decimals) rounded to 4 decimals of a mm and 3 of a degree is on the machine's manifold:
    the reference answers it as the machine's pose, not WARN_UNREACHABLE."""
    from kingen.kinematics.hybrid.parasitic import solve_parasitic

    robot = load_robot(name)
    poses = np.array([entry.pose for entry in robot.golden])
    rounded = np.concatenate([np.round(poses[:, :3], 4), np.round(poses[:, 3:], 3)], axis=1)
    assert np.any(rounded != poses)
    assert not np.any(solve_parasitic(robot, t6_from_pose(rounded)).off)
    warnings = reference_solve(robot, t6_from_pose(rounded)).warnings
    assert not np.any(warnings[np.arange(len(poses)), [entry.posture for entry in robot.golden]] == WARNINGS["WARN_UNREACHABLE"])


@settings(max_examples=4 if not FULL else 50, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(drawn=machines(), units=st.sampled_from(["inch", "m"]))
def test_a_machine_in_inches_or_metres_and_the_same_in_mm_get_the_same_verdict(drawn, units, tmp_path_factory):
    """The same drawn machine written in mm and in ``units`` (every length divided by 25.4 or
    1000: tests/machines.in_units) is the same machine: the same joints at home (prismatic ones
    in mm) and the same verdict from verify."""
    family, document = drawn
    assume("units" not in document and "wrist" not in document)  # a wrist's parallel part is in mm
    folder = tmp_path_factory.mktemp("units")
    converted = dict(in_units(document, units), name=f"{document['name']}_{units}")
    paths = [write_machine(folder, document), write_machine(folder, converted)]
    robots = [robot_from_data(data, path) for data, path in zip((document, converted), paths)]
    home = np.array(robots[0].verification.home)
    joints = [reference_solve(robot, t6_from_pose(home[None])).joints for robot in robots]
    assert np.allclose(joints[0], joints[1], rtol=1e-9, atol=1e-9 * robots[0].size_mm), family
    verdicts = [run_verify(path, "c", folder)[:2] for path in paths]
    assert verdicts[0][0] == verdicts[1][0] == 0, (family, failed_checks(verdicts[0][1]), failed_checks(verdicts[1][1]))


def _plain_newton(robot, posture, joints, seed, steps=30):
    """z, roll, pitch (mm, radians) of a machine with task coordinates z, roll, pitch whose
    posture ``posture`` has ``joints``: undamped Newton from ``seed`` (6,; mm, radians) on the
    reference's inverse at the machine's pose (x, y, yaw following), derivative by central
    differences; (coordinates (3,), converged)."""
    from kingen.kinematics.hybrid.parasitic import on_manifold

    def joints_at(coordinates):
        pose = np.array([[0.0, 0.0, coordinates[0], *np.degrees(coordinates[1:]), 0.0]])
        return reference_solve(robot, t6_from_pose(on_manifold(robot, pose))).joints[0, :, posture]

    coordinates = np.array(seed)[[2, 3, 4]]
    for _ in range(steps):
        derivative = np.stack([(joints_at(coordinates + step) - joints_at(coordinates - step)) / (2 * np.sum(step))
                               for step in np.diag([1e-6, 1e-8, 1e-8])], axis=1)
        step = np.linalg.solve(derivative, joints_at(coordinates) - joints)
        coordinates = coordinates - step
        if np.max(np.abs(step)) < 1e-12:
            return coordinates, True
    return coordinates, False


def test_a_servo_seed_is_judged_only_where_newton_is_assured_to_return_the_pose():
    """inch_prs_newton's pose whose servo-cycle seed the C library's Newton refused (-4): from that
    seed Kantorovich's condition fails (kingen.verify.checks.round_trip.newton_assured), and an
    undamped Newton written here converges to another pose with the same joints; from a seed ten
    times nearer the condition holds and it returns the pose. Every servo seed of prs_head's
    forward check is assured: the check keeps judging shipped machines."""
    from kingen.hosts.c.checks import regular_pairs
    from kingen.kinematics.forward import free_mask
    from kingen.kinematics.poses import PoseStream
    from kingen.verify.checks.round_trip import forward_seeds, newton_assured, seed_offsets

    robot = load_robot(str(REGRESSIONS[0].parent / "inch_prs_newton.yaml"))
    pose = np.array([0.015981078531749040, 0.010542071304474255, -34.827707738734823,
                     0.075706956715337198, 0.032122863086801859, 0.0011365851711661965])
    offset = np.array([0.0, 0.0, 0.0072297361299589295, -2.7575815832992562e-06, -1.7446931011820687e-04, 0.0])
    joints = np.array([-32.801322166946143, -32.894630463550648, -27.591386477953314])
    assert np.allclose(reference_solve(robot, t6_from_pose(np.concatenate([pose[:3], np.degrees(pose[3:])])[None]))
                       .joints[0, :, 1], joints, rtol=0, atol=1e-9)
    free = free_mask(robot)
    for scale, expected in ((1.0, False), (0.1, True)):
        assert newton_assured(robot, (pose + scale * offset)[None], pose[None], joints[None], free)[0] == expected
        found, converged = _plain_newton(robot, 1, joints, pose + scale * offset)
        assert converged and (np.max(np.abs(found - pose[[2, 3, 4]])) < 1e-9) == expected, (scale, found)
    robot = load_robot("prs_head")
    t6 = t6_from_pose(PoseStream(robot, 0).draw(300))
    pose_index, _, joints, _, _, _ = regular_pairs(robot, t6)
    sampled = pose_from_t6(t6[pose_index])
    starts = np.concatenate([sampled[:, :3], np.radians(sampled[:, 3:])], axis=1)
    distance_mm, distance_deg = forward_seeds(robot)["a servo cycle away"]
    offsets = seed_offsets(np.random.default_rng(0), len(starts), distance_mm, distance_deg, free_mask(robot))
    offsets[:, 3:] = np.radians(offsets[:, 3:])
    assert np.all(newton_assured(robot, starts + offsets, starts, joints, free_mask(robot)))
