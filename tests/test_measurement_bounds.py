"""A measurement file holds its bounds: every value range-checked at its line and column (the
robot file's units), at most MAX_MEASUREMENTS rows, refused as soon as a row more is read; the
report's residual figure holds a fixed number of artists whatever the number of rows."""

import numpy as np
import pytest

from kingen.calibrate import report
from kingen.calibrate.measurements import MAX_MEASUREMENTS, read_measurements
from kingen.cli import main
from kingen.robot.model import load_robot


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    """The lines of a 30-pose measurement file of the nominal hexapod (calibrate plan)."""
    path = tmp_path_factory.mktemp("plan") / "poses.csv"
    assert main(["calibrate", "plan", "hexapod", "--poses", "30", "-o", str(path)]) == 0
    return path.read_text().splitlines()


def _with(lines, row, column, text):
    """``lines`` with data row ``row`` (1-based) holding ``text`` in ``column``."""
    header = lines[0].split(",")
    cells = lines[row].split(",")
    cells[header.index(column)] = text
    return [*lines[:row], ",".join(cells), *lines[row + 1:]]


@pytest.mark.parametrize("column, text, problem", [
    ("x", "1e308", "1e+308 mm is not within +/-1e+06 mm"),
    ("z", "-1000000.5", "-1e+06 mm is not within +/-1e+06 mm"),
    ("roll", "1e308", "1e+308 degrees is not within +/-720 degrees"),
    ("yaw", "-720.001", "-720.001 degrees is not within +/-720 degrees"),
    ("q4", "1e308", "1e+308 mm is not within +/-1e+06 mm"),
    ("pitch", "inf", "inf is not a finite number"),
])
def test_a_value_out_of_range_is_one_line_at_its_row_and_column(planned, tmp_path, capsys, column, text, problem):
    path = tmp_path / "bad.csv"
    path.write_text("\n".join(_with(planned, 3, column, text)) + "\n")
    assert main(["calibrate", "hexapod", "--measurements", str(path), "-o", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err.strip()
    assert error == f"kingen: error: {path}:4: {column}: {problem}"
    assert not (tmp_path / "out").exists()


def test_the_bounds_are_the_robot_files_units():
    """An inch robot's lengths are bounded in inches: 1,000,000 mm is 39,370.08 inches."""
    robot = load_robot("linuxcnc_hexapod")
    if robot.length_unit != "inch":
        pytest.skip("linuxcnc_hexapod is no longer in inches")
    from kingen.calibrate.measurements import _bounds

    header = ("q1", "x", "roll")
    assert _bounds(header, robot, "pose") == [(1e6 / 25.4, "inch"), (1e6 / 25.4, "inch"), (720.0, "degrees")]


def test_a_row_more_than_a_file_may_hold_is_refused_at_its_line(planned, tmp_path):
    path = tmp_path / "many.csv"
    rows = [planned[1 + index % 30] for index in range(MAX_MEASUREMENTS + 1)]
    path.write_text("\n".join([planned[0], "# a comment line is not a measurement", *rows]) + "\n")
    with pytest.raises(Exception, match=rf"{path}:{MAX_MEASUREMENTS + 3}: more than 10,000 measurements"):
        read_measurements(path, load_robot("hexapod"), "pose")
    path.write_text("\n".join([planned[0], *rows[:-1]]) + "\n")
    assert len(read_measurements(path, load_robot("hexapod"), "pose").joints) == MAX_MEASUREMENTS


def test_the_residual_figure_draws_each_series_as_one_collection(monkeypatch):
    """Two PolyCollections an axes, whatever the poses: each bar a rectangle of four corners
    from the floor (half the least positive error) up to its error; no patch per bar."""
    drawn = []
    monkeypatch.setattr(report, "png", lambda figure: drawn.append(figure) or b"")
    generator = np.random.default_rng(3)
    poses = 5000
    before = (generator.random(poses) * 1e-2, generator.random(poses) * 1e-3)
    after = (generator.random(poses) * 1e-3, np.zeros(poses))
    report.residual_figure(before, after)
    for axes, panel in zip(drawn[0].axes, range(2)):
        assert len(axes.patches) == 0 and len(axes.collections) == 2
        floor = np.concatenate([before[panel], after[panel]])
        floor = floor[floor > 0].min() / 2.0
        for collection, errors, left in zip(axes.collections, (before[panel], after[panel]), (-0.4, 0.0)):
            corners = np.array([path.vertices[:4] for path in collection.get_paths()])
            assert corners.shape == (poses, 4, 2)
            assert np.allclose(corners[:, 0, 0], np.arange(1, poses + 1) + left)
            assert np.allclose(corners[:, 1, 1], np.maximum(errors, floor)) and np.all(corners[:, 0, 1] == floor)
