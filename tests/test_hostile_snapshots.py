"""Hostile and oversized snapshots (issue 23): a snapshot verify cannot use is bad input
(exit 2, one line naming the file and the field), never an internal error; and kingen
never writes a snapshot it would refuse to read, nor holds a whole one in memory."""

import json
import subprocess
import sys

import pytest

import kingen.verify.snapshot
from kingen.cli import main
from kingen.robot.model import load_robot

from test_hostile import ROBOT, plugin_source


def run(capsys, *argv):
    code = main([str(arg) for arg in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """tau's snapshot of 5 poses, as kingen records it, parsed."""
    path = tmp_path_factory.mktemp("snapshot") / "tau.golden.json"
    assert main(["golden", "record", "tau", "-o", str(path), "--samples", "5"]) == 0
    return json.loads(path.read_text())


def _set(path, value):
    def change(data):
        *parents, last = path
        for part in parents:
            data = data[part]
        data[last] = value
    return change


BAD = [
    # (change, field and problem in the one line)
    (_set(["entries"], []), "entries: none recorded; record the snapshot again"),
    (_set(["joint_units"], ["mm"]), "joint_units: 1 units for 3 joints"),
    (_set(["joint_units"], ["mm"] * 5), "joint_units: 5 units for 3 joints"),
    (_set(["joint_names"], ["carriage1"]), "joint_names: 1 names for the robot's 3 joints (carriage1, carriage2, "
                                           "carriage3)"),
    (_set(["joint_names"], ["carriage3", "carriage2", "carriage1"]),
     "joint_names.0: 'carriage3', but the robot's joint 0 is carriage1"),
    (_set(["joint_units", 1], "m" * 300), "joint_units.1: String should have at most 255 characters"),
    (_set(["entries", 0, "warnings", 0], 2 ** 70),
     "entries.0.warnings.0: 1180591620717411303424 is not a warning code"),
    (_set(["entries", 1, "warnings", 3], 3), "entries.1.warnings.3: 3 is not a warning code (0, 1, 2, 5)"),
    (_set(["entries", 2, "warnings"], [0]), "entries.2: must hold 3 joints x 8 postures and 8 warnings"),
    (_set(["entries", 0, "joints", 1], [0.0] * 9), "entries.0: must hold 3 joints x 8 postures"),
    (_set(["entries", 0, "t6", 3, 0], float("inf")), "entries.0.t6.3.0: Input should be a finite number"),
    (_set(["entries", 0, "t6", 1, 1], float("nan")), "entries.0.t6.1.1: Input should be a finite number"),
    (_set(["entries", 0, "joints", 0, 0], float("-inf")), "entries.0.joints.0.0: Input should be a finite number"),
    (_set(["samples"], 6), "samples: 6, but the file holds 5 entries"),
    (_set(["seed"], -1), "seed: Input should be greater than or equal to 0"),
    (_set(["definition_sha256"], "x"), "definition_sha256: String should match pattern"),
    (_set(["tolerance", "mm"], 0), "tolerance.mm: Input should be greater than 0"),
]


@pytest.mark.parametrize("change, words", BAD, ids=[words.split(":")[0] for _, words in BAD])
def test_bad_snapshots_are_one_line_errors(tmp_path, capsys, recorded, change, words):
    data = json.loads(json.dumps(recorded))
    change(data)
    bad = tmp_path / "s.json"
    bad.write_text(json.dumps(data, allow_nan=True))
    code, _, err = run(capsys, "verify", "tau", "--golden", bad, "-o", tmp_path / "b", "--samples", "50")
    assert code == 2 and err.startswith(f"kingen: error: {bad}: ") and words in err, err
    assert err.count("\n") == 1
    assert not (tmp_path / "b").exists()  # refused before anything was built


def test_record_refuses_what_verify_would_refuse_before_computing(tmp_path, capsys, monkeypatch):
    def computing(*arguments, **keywords):
        raise AssertionError("the reference was called")

    monkeypatch.setattr("kingen.kinematics.reference.solve", computing)
    output = tmp_path / "ceart.golden.json"
    code, _, err = run(capsys, "golden", "record", "ceart", "-o", output, "--samples", "10000")
    robot = load_robot("ceart")
    per_entry = kingen.verify.snapshot.entry_bytes(robot)
    assert code == 2 and err.count("\n") == 1, err
    assert err.startswith(f"kingen: error: --samples 10000: a snapshot of ceart takes up to "
                          f"{per_entry / 1000:.1f} kB a pose and verify reads at most 64 MB: at most ")
    fitting = int(err.split("at most ")[-1].split()[0])
    assert 6000 < fitting <= (64 << 20) // per_entry
    assert list(tmp_path.iterdir()) == []


def test_the_largest_count_that_fits_is_recorded_and_read_back(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(kingen.verify.snapshot, "MAX_SNAPSHOT_BYTES", 100_000)
    output = tmp_path / "tau.golden.json"
    code, _, err = run(capsys, "golden", "record", "tau", "-o", output, "--samples", "1000")
    assert code == 2 and "and verify reads at most 100 kB: at most " in err, err
    fitting = int(err.split("at most ")[-1].split()[0])
    assert fitting > 50
    assert run(capsys, "golden", "record", "tau", "-o", output, "--samples", fitting + 1)[0] == 2
    assert not output.exists()
    assert run(capsys, "golden", "record", "tau", "-o", output, "--samples", fitting)[0] == 0
    assert output.stat().st_size <= 100_000
    assert len(kingen.verify.snapshot.load(output, load_robot("tau")).entries) == fitting


def test_record_writes_chunk_by_chunk_the_same_file(tmp_path, capsys, monkeypatch):
    whole = tmp_path / "whole.json"
    assert run(capsys, "golden", "record", "tau", "-o", whole, "--samples", "30")[0] == 0
    monkeypatch.setattr("kingen.verify.chunk_size", lambda robot: 7)
    chunked = tmp_path / "chunked.json"
    assert run(capsys, "golden", "record", "tau", "-o", chunked, "--samples", "30")[0] == 0
    assert chunked.read_bytes() == whole.read_bytes()
    assert len(kingen.verify.snapshot.load(chunked, load_robot("tau")).entries) == 30


def _peak_memory_mb(tmp_path, samples):
    output = str(tmp_path / "c.json")
    script = ("import resource; from kingen.cli import main; "
              f"code = main(['golden', 'record', 'ceart', '-o', {output!r}, '--samples', '{samples}']); "
              "print(code, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024)")
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    code, megabytes = result.stdout.split()[-2:]
    assert code == "0", result.stdout + result.stderr
    return int(megabytes)


def test_record_memory_does_not_grow_with_the_samples(tmp_path):
    # Before issue 23 the whole snapshot was built in memory: about 75 MB more per 1000 ceart poses.
    assert _peak_memory_mb(tmp_path, 3000) < _peak_memory_mb(tmp_path, 1000) + 60


def test_a_plugin_recording_streams_from_its_child_and_verifies(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("kingen.verify.chunk_size", lambda robot: 7)  # the forked child draws the same chunks
    assert run(capsys, "build", "tau", "-o", tmp_path / "b")[0] == 0
    output = tmp_path / "tau.golden.json"
    code, out, _ = run(capsys, "golden", "record", "tau", "--plugin", tmp_path / "b" / "libtau.so", "-o", output,
                       "--samples", "30")
    assert code == 0 and out == f"{output}: 30 poses x 8 postures recorded from plugin libtau.so (kin_tau)\n"
    code, out, _ = run(capsys, "verify", "tau", "--plugin", tmp_path / "b" / "libtau.so", "--golden", output,
                       "--samples", "100")
    assert code == 0 and "ok     snapshot: 30 recorded poses x 8 postures (plugin libtau.so (kin_tau)" in out


def test_a_plugin_answering_an_unknown_warning_records_nothing(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the source is compiled into build/probe/legacy
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    source = tmp_path / "kin_probe.c"
    source.write_text(plugin_source().replace("warnings[0] = WARN_GOOD_SOLUTION;", "warnings[0] = 7;"))
    output = tmp_path / "probe.golden.json"
    code, _, err = run(capsys, "golden", "record", robot, "--source", source, "-o", output, "--samples", "10")
    assert code == 1 and err == ("kingen: plugin failed: plugin libprobe.so (kin_probe) answered warning 7 "
                                 "(pose 0, posture 0), not one of kingen's warning codes; a snapshot records only "
                                 "those\n"), err
    assert sorted(path.name for path in tmp_path.iterdir()) == ["build", "kin_probe.c", "probe.yaml"]
