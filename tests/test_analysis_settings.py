"""analyze's settings and verdicts: the 6-RUS thesis's published optimum under the thesis's
own rules, crossings of a direct singularity with and without a threshold, only the free
coordinates analysed, slices out to the workspace boundary."""

import json

import numpy as np
import pytest

from kingen.design import analysis
from kingen.design.analysis import CAUSES, Settings, home_values, slices, sweeps, tilt_limits
from kingen.cli import main
from kingen.kinematics.collision import line_distance
from kingen.robot.model import load_robot

THESIS = Settings(tilt_convention="euler", tilt_step_deg=1.0, azimuth_step_deg=1.0, tilt_max_deg=120.0,
                  collision="thesis")


def test_line_distances_written_out_by_hand():
    p1, q1 = np.array([[0.0, 0, 0]] * 3), np.array([[1.0, 0, 0]] * 3)
    p2 = np.array([[5.0, 3, -1], [12.0, 4, 0], [7.0, 0, 0]])
    q2 = np.array([[5.0, 3, 1], [20.0, 4, 0], [9.0, 0, 0]])
    np.testing.assert_allclose(line_distance(p1, q1, p2, q2), [3.0, 4.0, 0.0])


@pytest.fixture(scope="module")
def thesis_limits():
    robot = load_robot("rus_optimized")
    return tilt_limits(robot, 21, THESIS), home_values(robot, 21, THESIS)


def test_the_thesis_optimum_under_the_thesis_rules(thesis_limits):
    """optimisation.md's published values: T = 47 deg with 1-degree steps, ended by the rods
    near azimuth 51-57; about Y 57 deg by rod collision; direct index 137.2 mm at home."""
    limits, home = thesis_limits
    assert len(limits) == 360 and home.index_mm == pytest.approx(137.2, abs=0.05)
    least = min(row["max_tilt_deg"] for row in limits)
    assert least == 47.0
    first = min((row for row in limits if row["max_tilt_deg"] == least), key=lambda row: row["azimuth_deg"])
    assert first["cause"] == "collision" and 51 <= first["azimuth_deg"] <= 57
    about_y = limits[90]
    assert (about_y["azimuth_deg"], about_y["max_tilt_deg"], about_y["cause"]) == (90.0, 57.0, "collision")
    assert all(float(row["max_tilt_deg"]).is_integer() for row in limits)  # multiples of the step


def test_the_kingen_model_is_stricter_than_the_thesis():
    robot = load_robot("rus_optimized")
    ours = Settings(tilt_convention="euler", tilt_step_deg=1.0, azimuth_step_deg=45.0, tilt_max_deg=120.0)
    theirs = Settings(**{**ours.__dict__, "collision": "thesis"})
    for mine, thesis in zip(tilt_limits(robot, 21, ours), tilt_limits(robot, 21, theirs)):
        assert mine["max_tilt_deg"] <= thesis["max_tilt_deg"]


def test_a_crossing_stops_a_tilt_by_the_sign_of_det_j_alone(monkeypatch):
    """LinuxCNC's sample hexapod sets no threshold: the index's fall stops the tilt, and with
    that rule switched off the determinant's sign still does, one coarse step later at most."""
    robot = load_robot("linuxcnc_hexapod")
    settings = Settings(tilt_step_deg=2.0, azimuth_step_deg=90.0)
    both = tilt_limits(robot, robot.working_posture, settings)
    assert robot.direct_index_min is None
    stopped = [row for row in both if row["cause"] == "direct_singularity"]
    assert stopped, both
    monkeypatch.setattr(analysis, "CROSSING", 0.0)
    sign_only = tilt_limits(robot, robot.working_posture, settings)
    for with_index, without in zip(both, sign_only):
        if with_index["cause"] == "direct_singularity":
            assert without["cause"] == "direct_singularity"
            assert with_index["max_tilt_deg"] <= without["max_tilt_deg"] <= with_index["max_tilt_deg"] + 2.0


def test_a_tilt_nothing_stops_reports_the_cap():
    robot = load_robot("hexapod")
    limits = tilt_limits(robot, 0, Settings(tilt_step_deg=0.5, azimuth_step_deg=90.0, tilt_max_deg=2.0))
    assert [(row["max_tilt_deg"], row["cause"]) for row in limits] == [(2.0, "none")] * 4


def test_tilt_limits_hold_a_bounded_number_of_poses_and_give_what_the_whole_grid_gives(monkeypatch):
    """12,004 poses (4 azimuths x 3,001 tilts; towards azimuth 0 a direct singularity stops the
    tilt at 58.8 degrees, the others reach the cap): judged at most TILT_CHUNK_POSES at a time,
    the limits are those of the whole grid judged at once, and of chunks of 50 poses."""
    robot = load_robot("hexapod")
    settings = Settings(tilt_step_deg=0.02, azimuth_step_deg=90.0, tilt_max_deg=60.0)
    judged = []
    evaluate = analysis.evaluate

    def counted(robot, t6, *args):
        judged.append(len(t6))
        return evaluate(robot, t6, *args)

    monkeypatch.setattr(analysis, "evaluate", counted)
    chunked = tilt_limits(robot, 0, settings)
    assert max(judged) <= analysis.TILT_CHUNK_POSES < 4 * len(settings.tilts)
    assert [row["cause"] for row in chunked] == ["direct_singularity", "none", "none", "none"]
    assert chunked[0]["max_tilt_deg"] == pytest.approx(58.76, abs=0.02)
    for size in (10 ** 9, 50):
        monkeypatch.setattr(analysis, "TILT_CHUNK_POSES", size)
        assert tilt_limits(robot, 0, settings) == chunked


def test_only_free_coordinates_are_analysed():
    delta = load_robot("linear_delta")
    assert tilt_limits(delta, 7) == []
    assert set(sweeps(delta, 7)) == {"x", "y", "z"}
    exechon = load_robot("exechon")
    assert set(sweeps(exechon, 0)) == {"z", "roll", "pitch"}
    assert slices(exechon, 0) == {}


def test_slices_reach_the_workspace_boundary_with_square_cells():
    robot = load_robot("rotary_delta")
    sliced = slices(robot, 7)
    assert set(sliced) == {"xy", "xz"}
    inside = {CAUSES.index("none")}
    for plane in sliced.values():
        causes = np.array(plane["causes"])
        border = np.concatenate([causes[0], causes[-1], causes[:, 0], causes[:, -1]])
        assert not set(border.tolist()) & inside  # the whole working region lies within the window
        assert np.count_nonzero(causes == CAUSES.index("none")) > 0.1 * causes.size
        steps = np.concatenate([np.diff(plane["first"]), np.diff(plane["second"])])
        np.testing.assert_allclose(steps, steps[0], rtol=1e-9)
        assert plane["capped"] is False


def test_every_setting_is_stated_and_bad_ones_are_one_line_errors(tmp_path, capsys):
    out = tmp_path / "a.json"
    assert main(["analyze", "hexapod", "-o", str(tmp_path / "x"), "--json", str(out), "--tilt-convention", "euler",
                 "--tilt-step", "1", "--azimuth-step", "90", "--tilt-max", "30"]) == 0
    said = capsys.readouterr()
    assert "4 azimuths every 90 deg, steps of 1 deg, euler convention, segments collisions" in said.out
    settings = json.loads(out.read_text())["settings"]
    assert settings["tilt_convention"].startswith("euler") and settings["collision"].startswith("segments")
    assert (settings["tilt_step_deg"], settings["azimuth_step_deg"], settings["tilt_max_deg"]) == (1.0, 90.0, 30.0)
    assert settings["free_coordinates"] == ["x", "y", "z", "roll", "pitch", "yaw"]
    assert main(["analyze", "tau", "--collision", "thesis", "-o", str(tmp_path / "y")]) == 2
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1 and "thesis's collision model pairs six limbs" in error
    assert not (tmp_path / "y").exists()
