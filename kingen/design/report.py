"""What an optimisation shows: the polar graph of the best design's tilt limits against the
starting design's, the convergence of the swarm's best, and the self-contained HTML report
that holds them (:mod:`kingen.design.search` runs the search)."""

import base64

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from .figures import COLOURS, LABELS, label_rings, png
from ..runtime.templates import template


def polar_comparison(result):
    """PNG: the tilt limit towards each azimuth (degrees, radius from 0 to the cap) of the
    starting design (grey) and the best (black, markers coloured by what stops it)."""
    figure = Figure(figsize=(6.6, 7.2), layout="constrained")
    axes = figure.add_subplot(projection="polar")
    cap = result["settings"]["objective"]["tilt_max"]
    for key, colour, label in (("start_tilt_table", "#999999", "starting design"),
                               ("tilt_table", "#222222", "best design")):
        rows = result[key]
        angles = np.radians([row["azimuth_deg"] for row in rows] + [rows[0]["azimuth_deg"]])
        tilts = [row["max_tilt_deg"] for row in rows] + [rows[0]["max_tilt_deg"]]
        axes.plot(angles, tilts, color=colour, linewidth=1.3,
                  label=f"{label}: least {min(row['max_tilt_deg'] for row in rows):g} deg")
    rows = result["tilt_table"]
    for cause in sorted({row["cause"] for row in rows}):
        chosen = [row for row in rows if row["cause"] == cause]
        axes.scatter(np.radians([row["azimuth_deg"] for row in chosen]), [row["max_tilt_deg"] for row in chosen],
                     s=6, zorder=3, color=COLOURS.get(cause, "#000000"),
                     label=f"best design stopped by {LABELS.get(cause, cause)}")
    axes.set_ylim(0.0, cap)
    axes.set_title(f"{result['robot']}: largest tilt towards each azimuth\n"
                   f"radius: tilt (deg), outer circle {cap:g} deg, the largest searched", fontsize=10)
    figure.legend(loc="outside lower center", ncol=1, fontsize=8, frameon=False)
    label_rings(axes, [[(row["azimuth_deg"], row["max_tilt_deg"]) for row in result[key]]
                       for key in ("start_tilt_table", "tilt_table")])
    return png(figure)


def convergence(result):
    """PNG of convergence_figure(result)."""
    return png(convergence_figure(result))


def convergence_figure(result):
    """The swarm's best objective after each iteration (whole iterations on the x axis),
    from 0, with the refinement's."""
    figure = Figure(figsize=(7.5, 3.6), layout="constrained")
    axes = figure.add_subplot()
    history = result["history"]
    axes.plot(np.arange(1, len(history) + 1), history, color="#1f77b4", label="swarm's best")
    axes.axhline(result["objective_deg"], color="#222222", linestyle="--", linewidth=1,
                 label=f"the file's own design: {result['objective_deg']:g} deg" if result["start_kept"]
                 else f"after refinement: {result['objective_deg']:g} deg")
    axes.set_xlabel("iteration")
    axes.xaxis.set_major_locator(MaxNLocator(integer=True))
    axes.set_ylabel("least tilt over the azimuths (deg)")
    axes.set_ylim(0.0, max(max(history, default=0.0), result["objective_deg"]) * 1.1 + 1.0)
    axes.grid(alpha=0.3)
    figure.legend(loc="outside lower center", ncol=2, fontsize=8, frameon=False)
    return figure


def report_html(result, pngs):
    """The self-contained report: the problem, the settings, the best design, the figures."""
    images = {name: base64.b64encode(data).decode("ascii") for name, data in pngs.items()}
    return template("optimization_report.html.j2").render(result=result, images=images)
