"""The figures have no overlaps: the slice titles clear the figure's title, the polar graph's
ring labels sit between azimuth markers and on none, the convergence plot counts whole
iterations."""

import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from kingen.design.analysis import Settings, analyze
from kingen.design.figures import figure_objects, ring_label_angle
from kingen.design.report import convergence_figure
from kingen.robot.model import load_robot

SETTINGS = Settings(tilt_convention="axis", tilt_step_deg=1.0, azimuth_step_deg=15.0, tilt_max_deg=90.0)


@pytest.fixture(scope="module", params=["ceart", "hexapod"])
def drawn(request):
    """The robot's analysis figures, drawn at the PNGs' resolution."""
    made = figure_objects(analyze(load_robot(request.param), None, SETTINGS))
    for figure in made.values():
        FigureCanvasAgg(figure)
        figure.set_dpi(110)
        figure.canvas.draw()
    return made


def test_slice_titles_clear_the_figures_title(drawn):
    figure = drawn["slices.png"]
    title = figure._suptitle.get_window_extent()
    assert figure.axes
    for axes in figure.axes:
        assert not title.overlaps(axes.title.get_window_extent()), axes.get_title()


def test_ring_labels_sit_between_markers_and_on_none(drawn):
    axes = drawn["tilt_limits.png"].axes[0]
    angle = axes.get_rlabel_position()
    offsets = [point for collection in axes.collections for point in collection.get_offsets()]
    azimuths = {round(float(theta) * 180.0 / 3.141592653589793, 6) % 360.0 for theta, _ in offsets}
    assert len(azimuths) == 24 and angle % 360.0 not in azimuths
    labels = [label for label in axes.yaxis.get_ticklabels() if label.get_text()]
    assert len(labels) >= 5
    markers = axes.transData.transform(offsets)
    for label in labels:
        box = label.get_window_extent()
        assert not any(box.x0 - 5 < x < box.x1 + 5 and box.y0 - 5 < y < box.y1 + 5 for x, y in markers), \
            label.get_text()


def test_ring_label_angle_avoids_the_rings_at_the_curve():
    curve = [(0.0, 23.0), (90.0, 23.0), (180.0, 25.0), (270.0, 25.0)]
    assert ring_label_angle([curve], [10.0, 20.0, 30.0, 40.0]) == 225.0  # radius 25 there: 5 deg from every ring
    assert ring_label_angle([[(0.0, 30.0), (120.0, 30.0), (240.0, 30.0)]], [10.0, 20.0]) == 60.0  # ties: nearest 67.5
    assert ring_label_angle([], [10.0]) == 67.5


def test_convergence_counts_whole_iterations():
    figure = convergence_figure({"history": [0.0, 11.0, 11.0], "objective_deg": 47.0, "start_kept": True})
    FigureCanvasAgg(figure)
    figure.canvas.draw()
    axes = figure.axes[0]
    shown = [tick for tick in axes.get_xticks() if axes.get_xlim()[0] <= tick <= axes.get_xlim()[1]]
    assert shown == [1.0, 2.0, 3.0]
    assert all(label.get_text().lstrip("−-").isdigit() for label in axes.get_xticklabels() if label.get_text())
