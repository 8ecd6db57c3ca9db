"""Pictures of an analysis (:mod:`kingen.analysis`) with matplotlib, and the self-contained
HTML report that shows them: the polar graph of tilt limits, the sweeps' index curves with
their thresholds, and the workspace slices coloured by what limits each cell."""

import base64
import io

import numpy as np

from .analysis import CAUSES
from .render import template

COLOURS = {"unreachable": "#d62728", "joint_limits": "#ff7f0e", "direct_singularity": "#9467bd",
           "collision": "#8c564b", "none": "#2ca02c"}
LABELS = {"unreachable": "unreachable", "joint_limits": "joint limits", "direct_singularity": "direct singularity",
          "collision": "collision", "none": "no limit"}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as pyplot

    return pyplot


def _png(figure):
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110, bbox_inches="tight")
    _pyplot().close(figure)
    return buffer.getvalue()


def polar_graph(analysis):
    """PNG: the largest tilt about each horizontal axis, coloured by what stops it."""
    pyplot = _pyplot()
    figure = pyplot.figure(figsize=(6.2, 6.2))
    axes = figure.add_subplot(projection="polar")
    limits = analysis["tilt_limits"]
    azimuths = np.radians([row["azimuth_deg"] for row in limits] + [limits[0]["azimuth_deg"]])
    tilts = [row["max_tilt_deg"] for row in limits] + [limits[0]["max_tilt_deg"]]
    axes.plot(azimuths, tilts, color="#444444", linewidth=1.2, label="largest tilt")
    for cause in CAUSES:
        chosen = [row for row in limits if row["cause"] == cause]
        if chosen:
            axes.scatter(np.radians([row["azimuth_deg"] for row in chosen]), [row["max_tilt_deg"] for row in chosen],
                         color=COLOURS[cause], s=36, zorder=3, label=f"stopped by {LABELS[cause]}")
    axes.set_rlabel_position(100)
    axes.set_xlabel("azimuth of the tilt axis (deg)")
    axes.set_ylabel("largest tilt (deg)", labelpad=28)
    axes.set_title(f"{analysis['robot']}, posture {analysis['posture']}: tilt limits about horizontal axes", pad=18)
    axes.legend(loc="upper left", bbox_to_anchor=(0.85, 1.12), fontsize=8)
    return _png(figure)


def sweep_graphs(analysis):
    """PNG: along each single-axis sweep, the direct index, the clearances and the smallest
    inverse index, with the direct-index threshold."""
    pyplot = _pyplot()
    figure, grid = pyplot.subplots(2, 3, figsize=(13, 7.5))
    threshold = analysis.get("direct_index_min_mm")
    for axes, (name, entries) in zip(grid.ravel(), analysis["sweeps"].items()):
        values = [entry["value"] for entry in entries]
        unit = "deg" if name in ("roll", "pitch", "yaw") else "mm"
        for key, label, style in (("direct_index_mm", "direct index (mm)", "-"),
                                  ("min_rod_distance_mm", "rod clearance (mm)", "--"),
                                  ("min_crank_distance_mm", "crank clearance (mm)", ":")):
            series = [np.nan if entry[key] is None else entry[key] for entry in entries]
            if np.any(np.isfinite(series)):
                axes.plot(values, series, style, label=label)
        if threshold is not None:
            axes.axhline(threshold, color=COLOURS["direct_singularity"], linewidth=0.8,
                         label=f"threshold {threshold:g} mm")
        inverse = axes.twinx()
        inverse.plot(values, [np.nan if entry["min_inverse_index"] is None else entry["min_inverse_index"]
                              for entry in entries], color="#7f7f7f", linewidth=0.8, label="min inverse index D")
        inverse.set_ylabel("min inverse index D (1)")
        stopped = [entry["value"] for entry in entries if entry["cause"] != "none"]
        if stopped:
            axes.scatter(stopped, [0.0] * len(stopped), color=COLOURS["unreachable"], s=6, label="limited pose")
        axes.set_xlabel(f"{name} ({unit})")
        axes.set_ylabel("mm")
        axes.set_title(f"sweep of {name}")
        handles, labels = axes.get_legend_handles_labels()
        more_handles, more_labels = inverse.get_legend_handles_labels()
        axes.legend(handles + more_handles, labels + more_labels, fontsize=7, loc="upper right")
    figure.suptitle(f"{analysis['robot']}, posture {analysis['posture']}: single-axis sweeps from home")
    figure.tight_layout()
    return _png(figure)


def slice_graph(analysis):
    """PNG: the x-y and x-z workspace slices, each cell coloured by what limits it."""
    pyplot = _pyplot()
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    figure, grid = pyplot.subplots(1, 2, figsize=(12, 5.6))
    colours = ListedColormap([COLOURS[cause] for cause in CAUSES])
    for axes, (name, data) in zip(grid, analysis["slices"].items()):
        causes = np.array(data["causes"]).T
        extent = [data["first"][0], data["first"][-1], data["second"][0], data["second"][-1]]
        axes.imshow(causes, origin="lower", extent=extent, cmap=colours, vmin=-0.5, vmax=len(CAUSES) - 0.5,
                    aspect="auto", interpolation="nearest")
        axes.set_xlabel(f"{data['axes'][0]} (mm)")
        axes.set_ylabel(f"{data['axes'][1]} (mm)")
        axes.set_title(f"{data['axes'][0]}-{data['axes'][1]} slice at home orientation")
    figure.legend(handles=[Patch(color=COLOURS[cause], label=LABELS[cause]) for cause in CAUSES],
                  loc="lower center", ncol=len(CAUSES))
    figure.suptitle(f"{analysis['robot']}, posture {analysis['posture']}: what limits the workspace")
    figure.tight_layout(rect=(0, 0.07, 1, 1))
    return _png(figure)


def figures(analysis):
    """{file name: PNG bytes} of every figure."""
    return {"tilt_limits.png": polar_graph(analysis), "sweeps.png": sweep_graphs(analysis),
            "slices.png": slice_graph(analysis)}


def report_html(robot, analysis, pngs, seconds):
    """The self-contained HTML report: summary, tables, figures embedded as data URIs."""
    images = {name: "data:image/png;base64," + base64.b64encode(data).decode("ascii") for name, data in pngs.items()}
    counts = {cause: sum(1 for row in analysis["tilt_limits"] if row["cause"] == cause) for cause in CAUSES}
    return template("analysis_report.html.j2").render(
        robot=robot, analysis=analysis, images=images, labels=LABELS, colours=COLOURS, counts=counts,
        seconds=f"{seconds:.1f}")
