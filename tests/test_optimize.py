"""kingen optimize: reproducible for a seed on any number of workers and on a Dask cluster,
resumable to the same result, its outputs complete (a robot file that builds and verifies,
the JSON contract, a report a browser shows), bad input refused in one line."""

import copy
import io
import json
import os
import pickle
import re
import signal
import subprocess
import sys
import time

import pytest
from ruamel.yaml import YAML

from conftest import require_tool, skip_or_fail
from kingen.design import search
from kingen.cli import main
from kingen.design.problem import Problem
from kingen.robot.model import load_robot, resolve_robot_path
from kingen.robot.reading import read_robot_file

# One worker under -n N: the module's optimisation runs are then made once.
pytestmark = pytest.mark.xdist_group("optimize")
SMALL = {"search": {"swarm": 6, "iterations": 4, "c1": 2.8, "c2": 1.3},
         "refine": {"iterations": 2}, "objective": {"posture": 21, "tilt_convention": "euler", "tilt_step": 1,
                                                      "azimuth_step": 8, "tilt_max": 120, "collision": "thesis"}}


def small_robot_file(folder, optimize=SMALL):
    """rus_optimized as ``folder``/rus_small.yaml with its optimize section's entries replaced by
    ``optimize``'s (SMALL: a small swarm and a coarse azimuth step) and no golden values."""
    data = read_robot_file(resolve_robot_path("rus_optimized"))[0]
    data["optimize"] = {**data["optimize"], **optimize}
    data.pop("golden", None)
    path = folder / "rus_small.yaml"
    buffer = io.StringIO()
    YAML().dump({**data, "name": "rus_small"}, buffer)
    path.write_text(buffer.getvalue())
    return path


@pytest.fixture(scope="module")
def small_file(tmp_path_factory):
    """rus_optimized with a small swarm and a coarse azimuth step: seconds, not minutes."""
    return small_robot_file(tmp_path_factory.mktemp("design"))


def _run(small_file, folder, *extra):
    assert main(["optimize", str(small_file), "-o", str(folder), "--seed", "5", *extra]) == 0
    return json.loads((folder / "optimization.json").read_text())


@pytest.fixture(scope="module")
def two_workers(small_file, tmp_path_factory):
    folder = tmp_path_factory.mktemp("two")
    return _run(small_file, folder, "--workers", "2"), folder


def test_outputs_and_json_contract(two_workers, small_file):
    result, folder = two_workers
    assert {"objective_deg", "evaluations", "seconds", "variables", "tilt_table", "history", "settings",
            "seed"} <= set(result)
    assert result["objective_deg"] >= result["swarm_objective_deg"] >= max(result["history"][:1])
    assert result["objective_deg"] >= result["start_objective_deg"]
    assert result["evaluations"] >= 6 * 4 and len(result["history"]) == 4 and len(result["tilt_table"]) == 45
    assert min(row["max_tilt_deg"] for row in result["tilt_table"]) == result["objective_deg"]
    assert result["settings"]["search"]["constriction"] == pytest.approx(0.7298, abs=1e-4)
    design = folder / "rus_small_optimized.yaml"
    assert main(["verify", str(design), "--samples", "500", "-o", str(folder / "build")]) == 0
    data = read_robot_file(design)[0]
    problem = Problem(data, design)
    assert list(problem.start()) == pytest.approx([variable["value"] for variable in result["variables"]], abs=1e-6)


def test_the_written_design_is_never_worse_than_the_start(small_file, tmp_path, capsys):
    """One iteration of a small swarm finds nothing better than rus_optimized's own 47 deg: the
    summary says so and the written design is the file's own."""
    result = _run(small_file, tmp_path, "--iterations", "1", "--workers", "1")
    out = capsys.readouterr().out
    assert result["objective_deg"] >= result["start_objective_deg"] == 47.0
    assert result["start_kept"] is True and result["swarm_objective_deg"] < 47.0
    assert "optimize rus_small: no design beat the file's own (47 deg): the written design is the file's; " \
           "1 iteration (iterations)" in out
    assert [variable["value"] for variable in result["variables"]] == [variable["start"] for variable in
                                                                      result["variables"]]
    design = tmp_path / "rus_small_optimized.yaml"
    written = Problem(read_robot_file(design)[0], design).start()
    original = Problem(read_robot_file(small_file)[0], small_file).start()
    assert list(written) == pytest.approx(list(original), abs=1e-9)
    assert "no design beat the file's own" in design.read_text().splitlines()[0]


def test_the_same_seed_gives_the_same_search_on_one_worker(two_workers, small_file, tmp_path):
    result, _ = two_workers
    other = _run(small_file, tmp_path, "--workers", "1")
    for key in ("objective_deg", "history", "variables", "tilt_table", "evaluations"):
        assert other[key] == result[key]


def test_a_dask_cluster_gives_the_same_result(two_workers, small_file, tmp_path):
    distributed = pytest.importorskip("distributed")
    result, _ = two_workers
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        other = _run(small_file, tmp_path, "--scheduler", cluster.scheduler_address)
    assert other["workers"].startswith("a Dask cluster")
    for key in ("objective_deg", "history", "variables"):
        assert other[key] == result[key]


def test_pool_workers_die_with_kingen_killed_by_sigkill(small_file, tmp_path):
    """SIGKILL gives kingen no chance to stop its pool: its workers die with it all the same
    (PR_SET_PDEATHSIG), within a few seconds."""
    from test_hostile import _children, _state

    process = subprocess.Popen([sys.executable, "-m", "kingen.cli", "optimize", str(small_file), "-o", str(tmp_path),
                                "--workers", "2", "--iterations", "100000"],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    workers = []
    while len(workers) < 2 and time.monotonic() < deadline and process.poll() is None:
        time.sleep(0.2)
        workers = _children(process.pid)
    assert len(workers) >= 2, "the pool never started"
    os.kill(process.pid, signal.SIGKILL)
    process.wait(timeout=10)
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline and [pid for pid in workers if _state(pid) not in ("gone", "Z")]:
        time.sleep(0.1)
    survivors = [pid for pid in workers if _state(pid) not in ("gone", "Z")]
    for pid in survivors:  # a failing run leaves nothing spinning either
        os.kill(pid, signal.SIGKILL)
    assert survivors == []


def test_bad_input_is_one_line(small_file, tmp_path, capsys):
    assert main(["optimize", "hexapod", "-o", str(tmp_path / "a")]) == 2
    assert "optimize: no design problem in this robot file" in capsys.readouterr().err
    assert main(["optimize", str(small_file), "-o", str(tmp_path / "b"), "--resume"]) == 2
    assert "no checkpoint to resume from" in capsys.readouterr().err
    data = read_robot_file(small_file)[0]
    data["optimize"]["variables"][0]["field"] = "layout.crank_directoins"
    bad = _dump(data, tmp_path / "bad.yaml")
    assert main(["optimize", str(bad), "-o", str(tmp_path / "c")]) == 2
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1 and "optimize.variables[0].field" in error
    assert not (tmp_path / "c").exists()


def test_an_angles_bounds_are_refused_beyond_two_turns_before_the_search(small_file, tmp_path, capsys):
    data = read_robot_file(small_file)[0]
    data["optimize"]["variables"][0]["bounds"] = [0, 1000]  # layout.crank_directions, degrees
    bad = _dump(data, tmp_path / "bad.yaml")
    assert main(["optimize", str(bad), "-o", str(tmp_path / "c")]) == 2
    error = capsys.readouterr().err.strip()
    found = re.fullmatch(rf"kingen: error: {re.escape(str(bad))}:(\d+): optimize\.variables\[0\]\.bounds: "
                         r"an angle's bounds must be within \+/-720 degrees", error)
    assert found and bad.read_text().splitlines()[int(found[1]) - 1].strip() == "bounds:"
    assert not (tmp_path / "c").exists()


def test_a_long_robot_name_gives_a_design_kingen_reads(small_file, tmp_path):
    data = read_robot_file(small_file)[0]
    path = _dump({**data, "name": "r" * 60, "optimize": {**data["optimize"], "refine": {"method": "none"}}},
                 tmp_path / "long.yaml")
    assert main(["optimize", str(path), "-o", str(tmp_path / "o"), "--swarm", "2", "--iterations", "1",
                 "--workers", "1"]) == 0
    design = load_robot(tmp_path / "o" / f"{'r' * 53}_optimized.yaml")
    assert design.name == f"{'r' * 53}_optimized" and len(design.name) == 63


def _dump(data, path):
    """Write ``data`` as YAML to ``path``; returns the path."""
    buffer = io.StringIO()
    YAML().dump(data, buffer)
    path.write_text(buffer.getvalue())
    return path


def test_the_report_in_a_real_browser(two_workers):
    require_tool("chromium", "chromium")
    _, folder = two_workers
    page = (folder / "report.html").read_text()
    assert "<script" not in page and page.count('src="data:image/png;base64,') == 2
    shot = folder / "report.png"
    subprocess.run(["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--window-size=1200,2400",
                    f"--screenshot={shot}", (folder / "report.html").as_uri()], check=True, capture_output=True,
                   timeout=120)
    assert shot.stat().st_size > 20000


@pytest.fixture(scope="module")
def checkpointed(small_file, tmp_path_factory):
    """The checkpoint of a one-iteration search of small_file (as data), to be tampered with."""
    folder = tmp_path_factory.mktemp("checkpointed")
    _run(small_file, folder, "--workers", "1", "--iterations", "1")
    return json.loads((folder / search.CHECKPOINT).read_text())


def _resume(small_file, folder, capsys):
    """optimize --resume from ``folder``: (exit code, stderr)."""
    code = main(["optimize", str(small_file), "-o", str(folder), "--workers", "1", "--iterations", "2", "--resume"])
    return code, capsys.readouterr().err.strip()


def test_a_checkpoint_is_plain_private_data_and_resumes(checkpointed, small_file, tmp_path, capsys):
    (tmp_path / search.CHECKPOINT).write_text(json.dumps(checkpointed))
    os.chmod(tmp_path / search.CHECKPOINT, 0o600)
    assert _resume(small_file, tmp_path, capsys) == (0, "")
    assert os.stat(tmp_path / search.CHECKPOINT).st_mode & 0o777 == 0o600
    data = json.loads((tmp_path / search.CHECKPOINT).read_text())
    assert (data["format"], data["version"], data["iteration"]) == ("kingen optimize checkpoint", 1, 2)
    assert len(data["swarm"]["x"]) == SMALL["search"]["swarm"]


class _Payload:
    """Unpickling this runs code: it touches the file ``marker``."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return (open, (str(self.marker), "w"))


@pytest.mark.parametrize("name", ["checkpoint.pkl", "checkpoint.json"])
def test_a_pickled_checkpoint_runs_nothing(small_file, tmp_path, capsys, name):
    marker = tmp_path / "payload-ran"
    (tmp_path / name).write_bytes(pickle.dumps(_Payload(marker)))
    os.chmod(tmp_path / name, 0o600)
    code, error = _resume(small_file, tmp_path, capsys)
    assert code == 2 and not marker.exists() and len(error.splitlines()) == 1
    assert (f"{tmp_path / 'checkpoint.json'}: " + ("no checkpoint to resume from (kingen does not read the old "
            "pickled checkpoint.pkl)" if name == "checkpoint.pkl" else "not a kingen checkpoint (")) in error


def _tampered(checkpointed, change):
    data = copy.deepcopy(checkpointed)
    change(data)
    return json.dumps(data)


TAMPERED = {
    "an old version": (lambda data: data.update(version=0), "version: Input should be 1"),
    "a NaN": (lambda data: data["swarm"]["v"][0].__setitem__(0, float("nan")), "swarm.v.0.0: Input should be a finite"),
    "code as text": (lambda data: data.update(seed="__import__('os')"), "seed: Input should be a valid integer"),
    "a field more": (lambda data: data.update(extra=1), "extra: Extra inputs are not permitted"),
    "a particle less": (lambda data: data["swarm"]["x"].pop(), "swarm.x: not 6 particles of "),
    "a ragged swarm": (lambda data: data["swarm"]["v"][2].pop(), "swarm.v: not 6 particles of "),
    "another problem": (lambda data: data.update(fingerprint="0" * 64), "the checkpoint is of another design problem"),
    "a random state beyond PCG64's": (lambda data: data["swarm"].update(random_state=2 ** 200),
                                      "swarm.random_state: not within 0 to 340282366920938463463374607431768211455"),
    "a position beyond the bounds": (lambda data: data["swarm"]["x"][0].__setitem__(0, 1e308),
                                     "swarm.x: a value outside the variables' bounds, which no search of this problem"),
    "a velocity beyond the cap": (lambda data: data["swarm"]["v"][1].__setitem__(2, -1e6),
                                  "swarm.v: a value outside +/- the variables' widths"),
    "an objective beyond the cap": (lambda data: data["swarm"]["f"].__setitem__(0, -1e308),
                                    "swarm.f: a value outside -120 to 0"),
    "a history of another length": (lambda data: data["history"].append(3.0), "history: 2 entries for 1 iterations"),
    "a cause analyze never names": (lambda data: data["best_table"][0].__setitem__(1, "<script>"),
                                    "best_table: not 45 rows of a tilt from 0 to 120 degrees and a cause"),
    "a negative count": (lambda data: data.update(evaluations=-6), "evaluations: -6 below 0"),
}


@pytest.mark.parametrize("case", TAMPERED)
def test_a_tampered_checkpoint_is_refused_in_one_line(checkpointed, small_file, tmp_path, capsys, case):
    change, expected = TAMPERED[case]
    (tmp_path / search.CHECKPOINT).write_text(_tampered(checkpointed, change))
    os.chmod(tmp_path / search.CHECKPOINT, 0o600)
    code, error = _resume(small_file, tmp_path, capsys)
    assert code == 2 and len(error.splitlines()) == 1 and f"{tmp_path / search.CHECKPOINT}: " in error
    assert expected in error


def _other_users(path):
    os.chown(path, 12345, 12345)


PLACED = {
    "owned by another user": (_other_users, "is owned by another user (uid 12345)"),
    "writable by its group": (lambda path: os.chmod(path, 0o620), "is writable by its group"),
    "a symbolic link": (lambda path: (path.rename(path.with_suffix(".real")),
                                      path.symlink_to(path.with_suffix(".real"))), "is a symbolic link"),
    "a FIFO": (lambda path: (path.unlink(), os.mkfifo(path, 0o600)), "is not a regular file"),
    "8 GB": (lambda path: os.truncate(path, 8 << 30), "larger than 16 MB, which no checkpoint is"),
}


@pytest.mark.parametrize("case", PLACED)
def test_a_checkpoint_another_user_could_have_written_is_refused(checkpointed, small_file, tmp_path, capsys, case):
    place, expected = PLACED[case]
    path = tmp_path / search.CHECKPOINT
    path.write_text(json.dumps(checkpointed))
    os.chmod(path, 0o600)
    if case == "owned by another user" and os.getuid() != 0:
        skip_or_fail("only root can give a file to another user")
    place(path)
    code, error = _resume(small_file, tmp_path, capsys)
    assert code == 2 and len(error.splitlines()) == 1
    assert f"{path}: {expected}" in error


@pytest.mark.parametrize("field, value, problem", [
    ("c1", 1e308, "Input should be less than or equal to 100 (got 1e+308)"),
    ("c2", 1e155, "Input should be less than or equal to 100 (got 1e+155)"),
    ("c1", 0.0, "Input should be greater than 0 (got 0.0)")] + [
    (f"refine.{name}", value, f"Input should be greater than or equal to 0.000001 (got {value!r})")
    for name, value in (("angle_step", 5e-324), ("length_step", 1e-9))])
def test_swarm_coefficients_that_would_make_the_search_non_finite_are_refused(small_file, tmp_path, capsys, field,
                                                                              value, problem):
    data = read_robot_file(small_file)[0]
    section, key = field.split(".") if "." in field else ("search", field)
    data["optimize"][section][key] = value
    bad = _dump(data, tmp_path / "bad.yaml")
    assert main(["optimize", str(bad), "-o", str(tmp_path / "c")]) == 2
    error = capsys.readouterr().err.strip()
    found = re.fullmatch(rf"kingen: error: {re.escape(str(bad))}:(\d+): optimize\.{section}\.{key}: "
                         rf"{re.escape(problem)}", error)
    assert found and bad.read_text().splitlines()[int(found[1]) - 1].strip().startswith(f"{key}:")
    assert not (tmp_path / "c").exists()


@pytest.mark.parametrize("c1, c2, step", [(100.0, 100.0, 1e-6), (1e-300, 4.000000001, 720.0), (100.0, 1e-300, 1.0)])
def test_the_extreme_coefficients_allowed_keep_the_swarm_finite(small_file, tmp_path, c1, c2, step):
    """At the coefficients' and steps' bounds the constriction factor is finite and positive,
    every position and velocity of a few iterations is finite (the checkpoint refuses anything
    else), and the refinement ends in a finite design within the bounds."""
    data = read_robot_file(small_file)[0]
    data["optimize"]["search"].update(c1=c1, c2=c2, iterations=3)
    data["optimize"]["refine"].update(angle_step=step, length_step=step, iterations=1)
    problem = Problem(data, small_file)
    k = problem.section.search.constriction
    phi = c1 + c2
    assert k == pytest.approx(2.0 / (phi - 2.0 + (phi * phi - 4.0 * phi) ** 0.5), rel=1e-12) and k > 0
    state = search.run_swarm(problem, search.new_state(problem, 5, "x"), _Here, tmp_path)
    assert state.iteration == 3
    swarm = json.loads((tmp_path / search.CHECKPOINT).read_text())["swarm"]
    assert all(abs(value) < 1e7 for name in ("x", "v") for row in swarm[name] for value in row)
    design, objective, _, _ = search.refine(problem, state, _Here)
    assert all(problem.lower <= design) and all(design <= problem.upper) and objective >= state.best_objective


class _Here:
    """An executor evaluating in this process."""

    map = staticmethod(map)
