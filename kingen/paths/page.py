"""The HTML page of a check: the verdict, the checks, the problems by line, and figures of the
joints' positions, speeds and accelerations along the program against their limits, the
singularity indices, with the problems' lines marked."""

import base64

import numpy as np
from markupsafe import Markup
from matplotlib.figure import Figure

from ..design.figures import png
from ..runtime.templates import template
from .report import checks, problem_rows, verdict_line

PANELS = (("joints", "position", "travel_limits", ""), ("speeds", "|speed|", "speed_limit", "/s"),
          ("accelerations", "|acceleration|", "acceleration_limit", "/s^2"))


def _marks(trace, lines):
    """The trace's sample numbers at which each problem line starts."""
    marks = []
    for line in lines:
        where = np.flatnonzero(trace["line"] == line)
        if len(where):
            marks.append(trace["sample"][where[0]])
    return marks


def _label(name, robot, per):
    """A joint panel's axis label with its units: mm for prismatic joints, deg for revolute
    ones, both when the robot has both (``per``: "", "/s" or "/s^2")."""
    units = [unit for unit, present in (("mm", not all(robot.revolute)), ("deg", any(robot.revolute))) if present]
    return f"{name} ({', '.join(unit + per for unit in units)})"


def _singularity_panel(axis, trace, threshold):
    """The least limb radicand D (no unit, 0 at a limb singularity) on ``axis`` and the direct
    index (mm) with its threshold on a second axis at the right, each on its own scale."""
    index_axis = axis.twinx()
    if len(trace["sample"]):
        axis.plot(trace["sample"], trace["radicand"], color="#555555", lw=0.8, label="least limb radicand D (left)")
        index_axis.plot(trace["sample"], trace["direct_index"], color="#1f77b4", lw=0.8, label="direct index (right)")
    if threshold is not None:
        index_axis.axhline(threshold, color="#1f77b4", ls="--", lw=0.7, label="direct_index_min (right)")
    axis.set_ylabel("least limb radicand D (0: limb singular)")
    index_axis.set_ylabel("direct index (mm)", color="#1f77b4")
    axis.set_xlabel("sample along the program (red: the start of a line with a problem)")
    handles = [handle for side in (axis, index_axis) for handle in side.get_legend_handles_labels()[0]]
    if handles:
        axis.legend(handles=handles, fontsize=7, ncol=3, loc="lower left", bbox_to_anchor=(0.0, 1.02),
                    borderaxespad=0.0, frameon=False)
    axis.grid(alpha=0.3)


def figure(outcome, document):
    """The figure (a matplotlib Figure): one panel per joint quantity (positions, |speeds|, |accelerations|
    in the joints' units, mm or deg, against their limits, dashed) and one of the singularity
    indices; red lines mark where each problem line starts. The legends stand above the panels,
    so no curve or crossing is under them."""
    trace = outcome.findings.trace_arrays()
    marks = _marks(trace, sorted({place.line for place in outcome.findings.problems.values()}))
    panels = Figure(figsize=(10, 11.5), layout="constrained")
    axes = panels.subplots(4, 1, sharex=True)
    for axis, (series, name, limit_key, per) in zip(axes, PANELS):
        for index, peak in enumerate(document["peaks"]):
            colour = f"C{index % 10}"
            if len(trace["sample"]):
                axis.plot(trace["sample"], trace[series][:, index], color=colour, lw=0.8, label=peak["joint"])
            limits = peak[limit_key] if isinstance(peak[limit_key], list) else [peak[limit_key]]
            for limit in limits:
                if limit is not None and np.isfinite(limit):
                    axis.axhline(limit, color=colour, ls="--", lw=0.7)
        axis.set_ylabel(_label(name, outcome.robot, per))
        axis.grid(alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    axes[0].legend(handles, labels, fontsize=7, ncol=min(len(labels), 8) or 1, loc="lower left",
                   bbox_to_anchor=(0.0, 1.02), borderaxespad=0.0, title="joints (dashed: their limits)",
                   title_fontsize=7, frameon=False)
    _singularity_panel(axes[3], trace, outcome.evaluator.threshold)
    for axis in axes:
        for mark in marks:
            axis.axvline(mark, color="red", lw=0.8, alpha=0.6)
    return panels


def page_html(outcome, document, view=""):
    """The self-contained HTML page of ``outcome`` (its JSON ``document`` beside it), with the
    3D ``view`` (HTML, kingen.view's fragment; "" for none) after the problems."""
    image = base64.b64encode(png(figure(outcome, document))).decode("ascii")
    return template("path_report.html.j2").render(
        verdict=verdict_line(outcome), document=document, checks=checks(outcome), rows=problem_rows(outcome),
        image=image, view=Markup(view))
