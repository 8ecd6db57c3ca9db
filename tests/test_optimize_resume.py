"""kingen optimize stopped the ways a user stops it (Ctrl-C to its process group, SIGTERM to
kingen alone or to its whole group, as a service manager stops it) resumes to exactly the result an uninterrupted run with the same seed gets; so
does a search resumed from the checkpoint of any iteration boundary."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time

import pytest

from kingen.cli import main
from kingen.design import search
from kingen.design.problem import Problem
from kingen.robot.reading import read_robot_file
from test_optimize import SMALL, small_robot_file

pytestmark = pytest.mark.xdist_group("optimize")
ITERATIONS = 40
"""Long enough that a signal sent once the first checkpoint is written lands mid-search, and
that the resumed search runs the 30 iterations without improvement after which pymoo's own
termination criteria would end it."""
SAME = ("objective_deg", "swarm_objective_deg", "history", "variables", "tilt_table", "evaluations", "poses",
        "iterations", "stopped_by", "start_kept")


@pytest.fixture(scope="module")
def small_file(tmp_path_factory):
    """rus_optimized with a small swarm, coarse azimuth and tilt steps and no patience limit:
    milliseconds an iteration."""
    return small_robot_file(tmp_path_factory.mktemp("resume"), {
        **SMALL, "search": {**SMALL["search"], "iterations": ITERATIONS, "patience": 100000},
        "objective": {**SMALL["objective"], "azimuth_step": 45, "tilt_step": 5}})


@pytest.fixture(scope="module")
def uninterrupted(small_file, tmp_path_factory):
    """optimization.json of the run never stopped (seed 5)."""
    folder = tmp_path_factory.mktemp("uninterrupted")
    assert main(["optimize", str(small_file), "-o", str(folder), "--seed", "5", "--workers", "1"]) == 0
    return json.loads((folder / "optimization.json").read_text())


def _stopped(small_file, folder, send):
    """Start ``kingen optimize`` as a process (two workers, seed 5), wait until it has written
    its first checkpoint, ``send(process)`` a signal, and return (exit status, stderr, the
    checkpoint's iteration)."""
    process = subprocess.Popen([sys.executable, "-m", "kingen.cli", "optimize", str(small_file), "-o", str(folder),
                                "--seed", "5", "--workers", "2"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while not (folder / search.CHECKPOINT).exists() and process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        send(process)
        _, error = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    return process.returncode, error, json.loads((folder / search.CHECKPOINT).read_text())["iteration"]


STOPS = {
    "Ctrl-C": (lambda process: os.killpg(process.pid, signal.SIGINT), 130),
    "SIGTERM": (lambda process: process.send_signal(signal.SIGTERM), 143),
    "SIGTERM to the group": (lambda process: os.killpg(process.pid, signal.SIGTERM), 143),
}


@pytest.mark.parametrize("how", STOPS)
def test_a_run_stopped_by_a_signal_resumes_to_the_uninterrupted_result(small_file, uninterrupted, tmp_path, capsys,
                                                                      how):
    send, status = STOPS[how]
    code, error, stopped_at = _stopped(small_file, tmp_path, send)
    assert code == status, error
    assert "Traceback" not in error and error.count("\n") <= 2, error
    assert 1 <= stopped_at < ITERATIONS, "the signal did not land mid-search"
    assert sorted(path.name for path in tmp_path.iterdir()) == [search.CHECKPOINT]
    assert f"kingen: stopped at iteration {stopped_at} " in error and "--resume" in error
    assert main(["optimize", str(small_file), "-o", str(tmp_path), "--workers", "1", "--resume"]) == 0
    assert f"resuming at iteration {stopped_at} " in capsys.readouterr().out
    resumed = json.loads((tmp_path / "optimization.json").read_text())
    assert {key: resumed[key] for key in SAME} == {key: uninterrupted[key] for key in SAME}


class _Here:
    """An executor evaluating in this process."""

    map = staticmethod(map)


def test_a_search_resumed_at_any_iteration_boundary_continues_as_the_uninterrupted_one(small_file, tmp_path):
    """The checkpoint of every iteration, resumed for one iteration, is the uninterrupted
    search's next checkpoint (swarm, velocities, random generator, counters, history), but for
    the time; so, step by step, a search resumed anywhere ends where the uninterrupted one
    ends, which the search resumed at iteration 1 and run to the end shows directly."""
    problem = Problem(read_robot_file(small_file)[0], small_file)
    fingerprint = search.fingerprint(problem)
    folder = tmp_path / "whole"

    def keep(state):
        shutil.copytree(folder, tmp_path / str(state.iteration))

    search.run_swarm(problem, search.new_state(problem, 5, fingerprint), _Here, folder, keep)
    for iteration in range(1, ITERATIONS):
        boundary = tmp_path / f"from{iteration}"
        shutil.copytree(tmp_path / str(iteration), boundary)
        state = search.load(boundary, problem, fingerprint)
        assert state.iteration == iteration
        search.run_swarm(problem, state, _Here, boundary, stop=lambda: state.iteration > iteration)
        assert _without_time(boundary) == _without_time(tmp_path / str(iteration + 1)), f"resumed at {iteration}"
    state = search.load(tmp_path / "1", problem, fingerprint)
    search.run_swarm(problem, state, _Here, tmp_path / "1")
    assert _without_time(tmp_path / "1") == _without_time(folder)


def _without_time(folder):
    data = json.loads((folder / search.CHECKPOINT).read_text())
    data.pop("seconds")
    return data


def _signal_masks(pid):
    """(ignored, blocked) signal sets of process ``pid``, from /proc."""
    fields = dict(line.split(":\t", 1) for line in open(f"/proc/{pid}/status").read().splitlines() if ":\t" in line)
    return tuple({number for number in range(1, 65) if int(fields[key], 16) >> (number - 1) & 1}
                 for key in ("SigIgn", "SigBlk"))


def test_the_pool_is_up_with_ctrl_c_ignored_before_the_first_particle():
    """The executor starts its workers at once, SIGINT and SIGTERM blocked while they fork: each
    worker either ignores them (its initializer ran) or still blocks them (it has not yet: it
    ignores them before it unblocks them), never takes them, and kingen's own mask is as it was,
    so a Ctrl-C or a group's SIGTERM at any moment reaches kingen alone (never a worker: a broken pool)."""
    from kingen.runtime.executors import executor
    from test_hostile import _children

    before = signal.pthread_sigmask(signal.SIG_BLOCK, [])
    with executor(2) as opened:
        workers = sorted(set(_children(os.getpid())) & set(opened.pool._processes))
        assert len(workers) == 2
        for pid in workers:
            ignored, blocked = _signal_masks(pid)
            for number in (signal.SIGINT, signal.SIGTERM):
                assert (number in ignored) != (number in blocked), (pid, number, ignored, blocked)
        assert signal.pthread_sigmask(signal.SIG_BLOCK, []) == before
