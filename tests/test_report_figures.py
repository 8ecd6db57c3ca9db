"""The reports' figures show what they are about: calibration's parameter chart draws each part
and unit on its own scale (a limb's 0.5 mm change is not lost beside a measuring frame 1,200 mm
away); check-path's figure keeps its legends off the data (a travel crossing stays visible) and
labels every axis with its unit; analyze's report says how it finds what it reports and why it
skips what it skips."""

import re

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg

from kingen.calibrate.parameters import Parameter
from kingen.calibrate.report import parameter_chart
from kingen.design.analysis import Settings as AnalysisSettings
from kingen.design.analysis import analyze
from kingen.design.figures import figures, report_html
from kingen.paths.check import Settings, check_program
from kingen.paths.page import figure
from kingen.paths.report import report_json
from kingen.robot.model import load_robot
from test_check_path import HOME, INCH, ini_text, strut_lengths


def drawn(made):
    FigureCanvasAgg(made)
    made.canvas.draw()
    return made


def test_the_parameter_chart_draws_each_part_and_unit_on_its_own_scale():
    changes = [  # (name, group, unit, identified - nominal, std)
        ("leg1.base_point.x", "base", "mm", 0.5, 0.02), ("leg2.reference_length", "length", "mm", -0.3, 0.01),
        ("leg3.platform_point.z", "platform", "mm", 0.2, 0.05), ("crank1.zero_offset", "zero", "deg", 0.05, 0.001),
        ("measuring_frame.x", "frame", "mm", 1200.0, 0.1), ("measuring_frame.y", "frame", "mm", -300.0, 0.1),
        ("target.z", "target", "mm", 40.0, 0.1), ("measuring_frame.yaw", "frame", "deg", 20.0, 0.01),
        ("leg4.base_point.y", "base", "mm", 9.0, None),  # not identifiable: not drawn
    ]
    entries = [Parameter(name, group, unit, 10.0) for name, group, unit, _, _ in changes]
    outcome = {"parameters": [{"name": name, "nominal": 10.0, "identified": 10.0 + change, "std": std,
                               "identifiable": std is not None} for name, _, _, change, std in changes]}
    chart = drawn(parameter_chart(outcome, entries))
    panels = {axes.get_title(loc="left"): axes for axes in chart.axes}
    expected = {"limb geometry (mm)": ["leg1.base_point.x", "leg2.reference_length", "leg3.platform_point.z"],
                "limb geometry (deg)": ["crank1.zero_offset"],
                "measuring frame and target (mm)": ["measuring_frame.x", "measuring_frame.y", "target.z"],
                "measuring frame and target (deg)": ["measuring_frame.yaw"]}
    assert list(panels) == list(expected)
    for title, names in expected.items():
        axes = panels[title]
        assert [label.get_text() for label in axes.get_yticklabels()] == names
        drawn_changes = [change + (std or 0.0) * side for name, _, _, change, std in changes if name in names
                         for side in (-1, 1)]
        low, high = axes.get_xlim()
        assert low <= min(drawn_changes) and max(drawn_changes) <= high
        # Its own scale: the axis spans at most a few times what its parameters need, with 0 on it.
        assert high - low <= 3.0 * (max(max(drawn_changes), 0.0) - min(min(drawn_changes), 0.0)), title
        assert title.endswith(")") and title.split("(")[-1][:-1] in axes.get_xlabel()


def test_the_check_path_figure_keeps_its_legends_off_the_data_and_labels_its_units(tmp_path):
    robot = load_robot("linuxcnc_hexapod")
    top = float(strut_lengths([HOME[:2] + [HOME[2] + 10.0] + HOME[3:]]).max()) / INCH
    ini = tmp_path / "machine.ini"
    ini.write_text(ini_text(maximum=top))
    program = tmp_path / "up.csv"
    up = HOME[:2] + [HOME[2] + 25.0] + HOME[3:]
    program.write_text("x,y,z,roll,pitch,yaw,feed\n" + "\n".join(
        ",".join(repr(value) for value in row) for row in (HOME + [600.0], up + [600.0], HOME + [600.0])) + "\n")
    outcome = check_program(robot, program, Settings(ini=ini))
    document = report_json(outcome)
    assert any(problem["kind"] == "travel" for problem in document["problems"])
    made = drawn(figure(outcome, document))
    renderer = made.canvas.get_renderer()
    panels = made.axes
    data_boxes = [axes.get_window_extent(renderer) for axes in panels]
    legends = [axes.get_legend() for axes in panels if axes.get_legend() is not None]
    assert legends
    for legend in legends:
        box = legend.get_window_extent(renderer)
        assert not any(box.overlaps(data) for data in data_boxes), "a legend covers a panel's data"
    labels = [axes.get_ylabel() for axes in panels]
    assert labels[:3] == ["position (mm)", "|speed| (mm/s)", "|acceleration| (mm/s^2)"]
    assert "direct index (mm)" in labels
    # The crossing is drawn: the struts' curves rise through the dashed travel limit, both on the panel.
    position = panels[0]
    limit = top * INCH
    low, high = position.get_ylim()
    highest = max(float(np.nanmax(line.get_ydata())) for line in position.get_lines() if len(line.get_ydata()) > 2)
    assert low < limit < highest <= high


def test_analyze_says_how_it_finds_the_direct_singularities_it_reports_and_why_it_skips_a_part():
    robot = load_robot("prs_head")
    analysis = analyze(robot, None, AnalysisSettings(azimuth_step_deg=90.0, tilt_step_deg=1.0))
    page = report_html(robot, analysis, figures(analysis), 1.0)
    # No direct index, yet tilts stopped by a direct singularity: the page says what finds them.
    assert analysis["available"]["direct_index"].startswith("not available: 3 limbs")
    assert "direct_singularity" in {row["cause"] for row in analysis["tilt_limits"]}
    index_row = re.search(r"<th>direct index</th><td>(.*?)</td>", page).group(1)
    assert "found from the closure Jacobian instead" in index_row
    singular_row = re.search(r"<th>direct singularity</th><td>(.*?)</td>", page).group(1)
    assert "closure Jacobian over the free coordinates (z, roll, pitch) is singular" in singular_row
    # Every part not analysed says why: here the slices, which need two free positions.
    assert re.findall(r"<p>Not analysed: (.*?)</p>", page) == [
        "fewer than two free position coordinates (free: z, roll, pitch)."]
    assert "<th>slice</th>" not in page  # no empty table under it
