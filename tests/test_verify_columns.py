"""verify compares by limb branch when the routine's postures repeat each branch's values:
the report must be the one comparing every posture gives, entry for entry."""

import dataclasses

import numpy as np
import pytest

from kingen.verify import tally as verify
from kingen.kinematics.routine import WARNINGS
from kingen.kinematics.routine import Calls
from kingen.hosts import get_host
from kingen.robot.model import load_robot
from kingen.kinematics.reference import solve
from kingen.verify.report import Report
from kingen.kinematics.singularity import branch_table
from kingen.kinematics.poses import sample_poses
from kingen.verify.tally import Tally as _Tally
from kingen.verify.tally import accumulate as _accumulate
from kingen.verify.tally import compared_columns as _compared_columns
from kingen.conventions import t6_from_pose

UNREACHABLE = WARNINGS["WARN_UNREACHABLE"]


def routine_like(expected, joints):
    return Calls(returned=np.zeros(len(joints), dtype=np.intc), solutions=joints,
                 warnings=expected.warnings.astype(np.intc).copy(), faults=np.zeros(len(joints), dtype=np.intc))


def shifted_branch(robot, expected, limb, branch, shift):
    """The reference's joints with ``shift`` added to one limb's branch in every posture taking it."""
    joints = expected.joints.copy()
    joints[:, limb, branch_table(robot)[:, limb] == branch] += shift
    return joints


def report_and_tally(robot, t6, calls, expected):
    report = Report(robot=robot.name, routine=get_host("delmia").routine_name(robot), samples=len(t6), seed=0,
                    postures=robot.postures)
    tally = _Tally.start(robot)
    _accumulate(robot, report, tally, robot.revolute, t6, calls, expected)
    return report, tally


def summary(report, tally):
    return (dataclasses.asdict(report), tally.posture_counts.tolist(), [w.tolist() for w in tally.posture_worst],
            tally.closure_worst, tally.closure_checked)


@pytest.mark.parametrize("name", ["ceart", "tau", "exechon", "hexapod", "iwf"])
@pytest.mark.parametrize("case", ["exact", "one branch off", "one entry off", "unreached posture"])
def test_comparing_by_branch_reports_what_comparing_every_posture_does(name, case, monkeypatch):
    robot = load_robot(name)
    t6 = t6_from_pose(sample_poses(robot, 300, 4))
    expected = solve(robot, t6)
    limb = robot.dof - 1
    joints = expected.joints.copy()
    if case == "one branch off":
        joints = shifted_branch(robot, expected, limb, robot.limbs[limb].branches - 1, 1e-6)
    elif case == "one entry off":
        joints[7, limb, -1] += 1e-6
    calls = routine_like(expected, joints)
    if case == "unreached posture":
        calls.warnings[11, -1] = UNREACHABLE
    by_branch = _compared_columns(robot, calls, expected).weights.max() > 1
    assert by_branch == (case in ("exact", "one branch off") and robot.postures > 2)
    fast = report_and_tally(robot, t6, calls, expected)
    monkeypatch.setattr(verify, "_repeats_branches", lambda robot, solutions: False)
    every_posture = report_and_tally(robot, t6, calls, expected)
    assert summary(*fast) == summary(*every_posture)
    worst = max(fast[0].max_abs_error_mm, fast[0].max_abs_error_rad)
    assert worst == (pytest.approx(1e-6, rel=1e-3) if "off" in case else 0.0)
    wrongly_unreached = int(fast[1].posture_counts[2].sum())
    assert wrongly_unreached == (1 if case == "unreached posture" else 0)


@pytest.mark.parametrize("name", ["ceart", "tau", "iwf"])
def test_the_branch_repeat_check_finds_every_single_entry_that_breaks_it(name):
    """_repeats_branches (shifted views) against its definition, each posture's joint equal to
    the one in the first posture taking the same branch: for every (limb, posture) entry
    changed alone, and for a NaN there (robots with more than two postures)."""
    robot = load_robot(name)
    table = branch_table(robot)
    first = [[int(np.argmax(table[:, limb] == branch)) for branch in range(2)] for limb in range(robot.dof)]
    branch_joints = np.random.default_rng(5).normal(size=(3, robot.dof, 2))
    joints = np.stack([branch_joints[:, limb, table[:, limb]] for limb in range(robot.dof)], axis=1)
    assert verify._repeats_branches(robot, joints)
    for limb in range(robot.dof):
        for posture in range(robot.postures):
            for value in (1e-12, np.nan):
                changed = joints.copy()
                changed[1, limb, posture] = value if np.isnan(value) else changed[1, limb, posture] + value
                representative = changed[:, limb, first[limb][table[posture, limb]]]
                by_definition = all(np.array_equal(changed[:, limb, k], representative)
                                    for k in range(robot.postures) if table[k, limb] == table[posture, limb])
                assert verify._repeats_branches(robot, changed) == by_definition, (limb, posture, value)


def host_summary(robot, joints):
    """kingen_host_summarise_branches (the DELMIA host emulator's C) on each pose of ``joints``
    (n, dof, postures): (repeats (n,), branch values (n, dof, 2))."""
    from kingen.hosts.delmia.loader import _pointer, host
    from kingen.kinematics.singularity import representative_postures

    first_postures = np.array(representative_postures(robot), dtype=np.intc)
    branch_of = np.array(branch_table(robot), dtype=np.intc)
    values = np.empty(joints.shape[:2] + (2,))
    repeats = [host().kingen_host_summarise_branches(
        _pointer("double *", np.ascontiguousarray(pose)), robot.dof, robot.postures, _pointer("int *", first_postures),
        _pointer("int *", branch_of), _pointer("double *", values[number])) for number, pose in enumerate(joints)]
    return np.array(repeats, dtype=bool), values


@pytest.mark.parametrize("name", ["ceart", "tau", "iwf"])
def test_the_hosts_summary_by_branch_is_the_repeat_check_and_the_branch_values(name):
    """The C summary the DELMIA host makes as it calls (Calls.repeats, Calls.branch_values)
    against _repeats_branches and kingen.kinematics.singularity.branch_values, pose by pose: for every
    (limb, posture) entry changed alone, by a little or to NaN, and unchanged."""
    from kingen.kinematics.singularity import branch_values

    robot = load_robot(name)
    table = branch_table(robot)
    branch_joints = np.random.default_rng(6).normal(size=(1, robot.dof, 2))
    joints = np.stack([branch_joints[:, limb, table[:, limb]] for limb in range(robot.dof)], axis=1)
    changed = []
    for limb in range(robot.dof):
        for posture in range(robot.postures):
            for value in (1e-12, np.nan):
                pose = joints[0].copy()
                pose[limb, posture] = value if np.isnan(value) else pose[limb, posture] + value
                changed.append(pose)
    poses = np.concatenate([joints, np.array(changed)])
    repeats, values = host_summary(robot, poses)
    assert repeats.tolist() == [verify._repeats_branches(robot, pose[None]) for pose in poses]
    assert repeats[0] and not np.all(repeats)
    np.testing.assert_array_equal(values, branch_values(robot, poses))


@pytest.mark.parametrize("name", ["ceart", "tau"])
def test_a_call_summarised_by_branch_returns_what_a_plain_call_does(name, plugin):
    """plugin.call(..., branches_of=robot): the same outputs as without, read-only solutions,
    and the summary of exactly those (the comparison then takes its columns from it)."""
    robot, routine = plugin(name)
    t6 = t6_from_pose(sample_poses(robot, 200, 9))
    routine.reset_host()  # as verify does before each chunk: another test may have left it refusing
    plain, summarised = routine.call(t6), routine.call(t6, branches_of=robot)
    for field in ("returned", "solutions", "warnings", "faults"):
        np.testing.assert_array_equal(getattr(summarised, field), getattr(plain, field))
    assert plain.repeats is None and not summarised.solutions.flags.writeable
    repeats, values = host_summary(robot, plain.solutions)
    np.testing.assert_array_equal(summarised.repeats, repeats)
    np.testing.assert_array_equal(summarised.branch_values, values)
    assert np.all(summarised.repeats)
    expected = solve(robot, t6)
    by_summary, by_numpy = (_compared_columns(robot, calls, expected) for calls in (summarised, plain))
    assert by_summary.weights.max() > 1
    np.testing.assert_array_equal(by_summary.plugin, by_numpy.plugin)


def test_a_summary_by_another_robots_branches_is_refused(plugin):
    """The C summary indexes the routine's buffers by the robot's tables: a robot of other
    counts is a programming error, refused before any call."""
    _, routine = plugin("ceart")
    with pytest.raises(ValueError, match="branches_of: tau has 3 joints and 8 postures, the routine 6 and 64"):
        routine.call(t6_from_pose(sample_poses(load_robot("ceart"), 2, 1)), branches_of=load_robot("tau"))
