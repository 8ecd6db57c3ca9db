"""The HTML page of a check: the verdict, the checks, the problems by line, and figures of the
joints' positions, speeds and accelerations along the program against their limits, the
singularity indices, with the problems' lines marked."""

import base64

import numpy as np
from matplotlib.figure import Figure

from ..design.figures import png
from ..runtime.templates import template
from .report import checks, problem_rows, verdict_line

PANELS = (("joints", "position", "travel_limits"), ("speeds", "|speed| (per s)", "speed_limit"),
          ("accelerations", "|acceleration| (per s^2)", "acceleration_limit"))


def _marks(trace, lines):
    """The trace's sample numbers at which each problem line starts."""
    marks = []
    for line in lines:
        where = np.flatnonzero(trace["line"] == line)
        if len(where):
            marks.append(trace["sample"][where[0]])
    return marks


def figure(outcome, document):
    """The figure (PNG bytes): one panel per joint quantity and one of the singularity indices."""
    trace = outcome.findings.trace_arrays()
    marks = _marks(trace, sorted({place.line for place in outcome.findings.problems.values()}))
    panels = Figure(figsize=(10, 11), layout="constrained")
    axes = panels.subplots(4, 1, sharex=True)
    for axis, (series, label, limit_key) in zip(axes, PANELS):
        for index, peak in enumerate(document["peaks"]):
            colour = f"C{index % 10}"
            if len(trace["sample"]):
                axis.plot(trace["sample"], trace[series][:, index], color=colour, lw=0.8, label=peak["joint"])
            limits = peak[limit_key] if isinstance(peak[limit_key], list) else [peak[limit_key]]
            for limit in limits:
                if limit is not None and np.isfinite(limit):
                    axis.axhline(limit, color=colour, ls="--", lw=0.7)
        axis.set_ylabel(label)
        axis.grid(alpha=0.3)
    axes[0].legend(fontsize=7, ncol=6, loc="upper right")
    if len(trace["sample"]):
        axes[3].plot(trace["sample"], trace["radicand"], color="#555555", lw=0.8, label="least limb radicand D")
        axes[3].plot(trace["sample"], trace["direct_index"], color="#1f77b4", lw=0.8, label="direct index (mm)")
    if outcome.evaluator.threshold is not None:
        axes[3].axhline(outcome.evaluator.threshold, color="#1f77b4", ls="--", lw=0.7, label="direct_index_min")
    axes[3].set_ylabel("singularity indices")
    axes[3].set_xlabel("sample along the program")
    axes[3].legend(fontsize=7, loc="upper right")
    axes[3].grid(alpha=0.3)
    for axis in axes:
        for mark in marks:
            axis.axvline(mark, color="red", lw=0.8, alpha=0.6)
    return png(panels)


def page_html(outcome, document):
    """The self-contained HTML page of ``outcome`` (its JSON ``document`` beside it)."""
    image = base64.b64encode(figure(outcome, document)).decode("ascii")
    return template("path_report.html.j2").render(
        verdict=verdict_line(outcome), document=document, checks=checks(outcome), rows=problem_rows(outcome),
        image=image)
