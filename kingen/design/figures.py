"""Pictures of an analysis (:mod:`kingen.design.analysis`) with matplotlib, and the self-contained
HTML report that shows them: the polar graph of tilt limits, the sweeps' curves with their
limits, and the workspace slices coloured by what limits each cell.

What the figures promise a reader: an axis carries one quantity and is drawn only when that
quantity has finite data; a legend entry names something drawn; index axes start at 0 (no
zoom turns a small change into a fall); poses something limits are shaded along the x axis;
legends sit outside the data; slices are equal-aspect, and outside the analysed window is
hatched grey, never the green of "within limits"."""

import base64
import io

import numpy as np
from markupsafe import Markup
from matplotlib.figure import Figure
from matplotlib.patches import Patch, Rectangle

from .analysis import CAUSES
from .load_figures import TITLES, load_extremes, loads_figure
from ..runtime.templates import template

COLOURS = {"unreachable": "#d62728", "joint_limits": "#ff7f0e", "direct_singularity": "#9467bd",
           "collision": "#8c564b", "none": "#2ca02c", "actuator_load": "#e377c2", "joint_angle": "#7f7f7f"}
LABELS = {"unreachable": "unreachable", "joint_limits": "joint limits", "direct_singularity": "direct singularity",
          "collision": "collision", "none": "within limits", "actuator_load": "actuator load",
          "joint_angle": "passive joint angle"}
OUTSIDE = {"facecolor": "#eeeeee", "edgecolor": "#b0b0b0", "hatch": "///", "linewidth": 0.0}
"""How the part of a slice's axes outside the analysed window looks (and its legend swatch)."""
OUTSIDE_LABEL = "not analysed (outside the window)"
ANGLES = ("roll", "pitch", "yaw")
QUANTITIES = (
    ("direct index (mm)", (("direct_index_mm", "direct index", "-", "#1f77b4"),)),
    ("clearance (mm)", (("min_rod_distance_mm", "rod clearance", "-", "#17becf"),
                        ("min_crank_distance_mm", "crank clearance", "--", "#bcbd22"))),
    ("least inverse index D\n(0: limb singularity)", (("min_inverse_index", "least inverse index D", "-", "#555555"),)),
    ("actuator load / limit", (("load_fraction", TITLES["load_fraction"], "-", "#e377c2"),)),
    ("least stiffness (N/mm)", (("min_stiffness_n_per_mm", TITLES["min_stiffness_n_per_mm"], "-", "#2ca02c"),)),
)
"""Rows of the sweep figure: an axis label (one quantity) and its curves (key, label, style, colour)."""


def png(figure):
    """The figure as PNG bytes (110 dpi)."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()


def ring_label_angle(curves, rings):
    """The angle (deg) at which to put a polar graph's ring labels (at radii ``rings``) so
    that they keep clear of the curves (each a list of (azimuth deg, radius) points, marked
    at every point): halfway between two neighbouring azimuths, where the curves' radii at
    both neighbours and halfway between are farthest from every labelled ring; ties go to the
    wider gap, then to the angle nearest 67.5 deg. Never a point's azimuth when there are two
    azimuths or more; 67.5 without points."""
    azimuths = sorted({azimuth % 360.0 for curve in curves for azimuth, _ in curve})
    if not azimuths:
        return 67.5
    radii = [{azimuth % 360.0: radius for azimuth, radius in curve} for curve in curves]
    best = None
    for first, second in zip(azimuths, azimuths[1:] + [azimuths[0] + 360.0]):
        near = []
        for curve in radii:
            ends = [curve[a % 360.0] for a in (first, second) if a % 360.0 in curve]
            near += ends + [sum(ends) / len(ends)] if ends else []
        clearance = min((abs(radius - ring) for radius in near for ring in rings), default=0.0)
        middle = (first + second) / 2.0 % 360.0
        key = (round(clearance, 9), second - first, -abs((middle - 67.5 + 180.0) % 360.0 - 180.0))
        best = max(best, (key, middle)) if best else (key, middle)
    return best[1]


def label_rings(axes, curves):
    """Put the ring (radius) labels of polar ``axes``, drawn last (its figure complete: the
    layout places the axes), at ring_label_angle of ``curves`` and the labelled rings,
    then leave blank each label whose text would still cover a marker (its ring stays drawn)."""
    top = axes.get_ylim()[1]
    rings = [float(ring) for ring in axes.get_yticks() if 0.0 < ring <= top]
    axes.set_rlabel_position(ring_label_angle(curves, rings))
    axes.set_rgrids(rings)
    axes.figure.draw_without_rendering()
    scale = axes.figure.dpi / 72.0
    markers = [(point, np.sqrt(size) / 2.0 * scale) for collection in axes.collections
               for point, size in zip(axes.transData.transform(collection.get_offsets()),
                                      np.broadcast_to(collection.get_sizes(), len(collection.get_offsets())))]
    labels = [label.get_text() for label in axes.yaxis.get_ticklabels()]
    for number, label in enumerate(axes.yaxis.get_ticklabels()):
        box = label.get_window_extent()
        if any(box.x0 - r < x < box.x1 + r and box.y0 - r < y < box.y1 + r for (x, y), r in markers):
            labels[number] = ""
    axes.set_rgrids(rings, labels)


def polar_figure(analysis):
    """The polar graph of the tilt limits (radius from 0 to the largest tilt searched, each
    azimuth's marker coloured by what stops it, legend below), or None when the analysis has
    no tilt limits (a platform that cannot tilt)."""
    limits = analysis["tilt_limits"]
    if not limits:
        return None
    searched = analysis["settings"].get("tilt_max_deg", max(row["max_tilt_deg"] for row in limits))
    figure = Figure(figsize=(6.6, 7.0), layout="constrained")
    axes = figure.add_subplot(projection="polar")
    azimuths = np.radians([row["azimuth_deg"] for row in limits] + [limits[0]["azimuth_deg"]])
    tilts = [row["max_tilt_deg"] for row in limits] + [limits[0]["max_tilt_deg"]]
    axes.plot(azimuths, tilts, color="#444444", linewidth=1.2, label="largest tilt before a limit")
    for cause in CAUSES:
        chosen = [row for row in limits if row["cause"] == cause]
        if chosen:
            style = {"facecolor": "white", "edgecolor": COLOURS[cause], "linewidth": 1.5,
                     "label": f"not stopped up to {searched:g} deg (searched no further)"} if cause == "none" else {
                     "color": COLOURS[cause], "label": f"stopped by {LABELS[cause]}"}
            axes.scatter(np.radians([row["azimuth_deg"] for row in chosen]), [row["max_tilt_deg"] for row in chosen],
                         s=36, zorder=3, clip_on=False, **style)
    axes.set_ylim(0.0, searched)
    axes.set_thetagrids(range(0, 360, 45), ["0°\nabout +X", "45°", "90°\nabout +Y", "135°", "180°\nabout -X",
                                            "225°", "270°\nabout -Y", "315°"])
    axes.tick_params(axis="x", pad=12, labelsize=9)
    axes.set_title(f"{analysis['robot']}, posture {analysis['posture']}: tilt limits about horizontal axes\n"
                   f"radius: largest tilt (deg), outer circle: {searched:g} deg, the largest searched;\n"
                   "angle: azimuth of the tilt axis", fontsize=10)
    figure.legend(loc="outside lower center", ncol=1, fontsize=8, frameon=False)
    label_rings(axes, [[(row["azimuth_deg"], row["max_tilt_deg"]) for row in limits]])
    return figure


def _series(entries, key):
    """The finite values of ``key`` along a sweep, NaN where missing or where the pose is
    unreachable (no assembled robot to measure there)."""
    return np.array([np.nan if entry[key] is None or entry["cause"] == "unreachable" else entry[key]
                     for entry in entries], dtype=float)


def _direct_limit(analysis):
    """(limit mm, label) of the direct index: the larger of the robot's threshold and the
    crossing fraction of the index at home; None when neither is known."""
    settings = analysis["settings"]
    candidates = []
    if analysis.get("direct_index_min_mm") is not None:
        candidates.append((analysis["direct_index_min_mm"], "robot's threshold"))
    if settings.get("crossing_fraction") is not None and settings.get("direct_index_at_home_mm") is not None:
        candidates.append((settings["crossing_fraction"] * settings["direct_index_at_home_mm"],
                           f"{settings['crossing_fraction']:.0%} of the index at home"))
    if not candidates:
        return None
    limit, source = max(candidates)
    return limit, f"direct-singularity limit {limit:.3g} mm ({source})"


def _limited_spans(entries):
    """[(start, end, cause)]: runs of consecutive poses one cause limits, each widened by half
    a step either side so a single pose shows."""
    values = [entry["value"] for entry in entries]
    half = abs(values[1] - values[0]) / 2 if len(values) > 1 else 0.5
    spans, previous = [], None
    for i, entry in enumerate(entries):
        cause = entry["cause"]
        if cause != "none" and cause == previous:
            spans[-1] = (spans[-1][0], values[i] + half, cause)
        elif cause != "none":
            spans.append((values[i] - half, values[i] + half, cause))
        previous = cause
    return spans


def _blocks(sweeps):
    """The sweep names in rows of at most three: rotations first, then positions."""
    rotations = [name for name in sweeps if name in ANGLES]
    positions = [name for name in sweeps if name not in ANGLES]
    return [block[i:i + 3] for block in (rotations, positions) for i in range(0, len(block), 3)]


def sweep_figure(analysis):
    """The sweep figure: under each row of up to three sweeps, one row per quantity with
    finite data (direct index, clearances, least inverse index D), on the same scale in every
    sweep and from 0 (a clearance below 0 extends it), with its limit as a line unless it
    would lie on the axis' edge; limited poses shaded along x and dotted on the curves in the
    colour of their cause; one legend below. None without a sweep or a quantity to draw."""
    sweeps = analysis["sweeps"]
    rows = [(label, curves, *_row_scale(analysis, sweeps, curves)) for label, curves in _quantities(sweeps)]
    blocks = _blocks(sweeps)
    if not rows or not blocks:
        return None
    figure = Figure(figsize=(12, 1.2 + 2.1 * len(rows) * len(blocks)), layout="constrained")
    grid = figure.subplots(len(rows) * len(blocks), 3, squeeze=False)
    for b, block in enumerate(blocks):
        for column in range(3):
            panels = grid[b * len(rows):(b + 1) * len(rows), column]
            if column >= len(block):
                for axes in panels:
                    axes.remove()
                continue
            name = block[column]
            for r, (label, curves, ylim, lines) in enumerate(rows):
                axes = panels[r]
                _sweep_panel(axes, sweeps[name], curves, lines)
                axes.set_ylim(*ylim)
                if r:
                    axes.sharex(panels[0])
                if column:
                    axes.tick_params(labelleft=False)
                else:
                    axes.set_ylabel(label, fontsize=9)
                if r == 0:
                    axes.set_title(f"{name} sweep", fontsize=10)
                if r == len(rows) - 1:
                    axes.set_xlabel(f"{name} ({'deg' if name in ANGLES else 'mm'})")
                else:
                    axes.tick_params(labelbottom=False)
    handles = _unique_handles(figure)
    figure.suptitle(f"{analysis['robot']}, posture {analysis['posture']}: single-axis sweeps from home "
                    "(shaded, and dotted on a curve: poses a limit stops)", fontsize=11)
    figure.legend(handles=handles, loc="outside lower center", ncol=min(4, len(handles)), fontsize=8, frameon=False)
    return figure


def _quantities(sweeps):
    """[(axis label, curves)] of the QUANTITIES some sweep has finite data for."""
    return [(label, curves) for label, curves in QUANTITIES
            if any(np.any(np.isfinite(_series(entries, key))) for entries in sweeps.values() for key, *_ in curves)]


def _row_scale(analysis, sweeps, curves):
    """((bottom, top), [(y, colour, label)]) of one quantity's row: from 0 (or the least value
    when below 0) to a little above the largest value or limit; its limit lines, leaving out
    a line at 0 while 0 is the bottom edge (it would hide in the axis)."""
    values = np.concatenate([_series(entries, key) for entries in sweeps.values() for key, *_ in curves])
    values = values[np.isfinite(values)]
    key = curves[0][0]
    lines = []
    limit = _direct_limit(analysis) if key == "direct_index_mm" else None
    if limit is not None:
        lines.append((*limit, "#333333"))
    bottom = min(0.0, float(values.min()) * 1.08) if len(values) else 0.0
    if key == "load_fraction":
        lines.append((1.0, "actuator load limit", "#333333"))
    if key == "min_rod_distance_mm" and bottom < 0.0:
        lines.append((0.0, "collision below 0 mm clearance", "#333333"))
    top = max([float(values.max()) if len(values) else 0.0, 1.0 if key == "min_inverse_index" else 1e-9]
              + [y for y, *_ in lines])
    return (bottom, top * 1.08), lines


def _sweep_panel(axes, entries, curves, lines):
    """One sweep's curves of one quantity, its limit lines, the shaded limited spans and the
    limited poses dotted on the curves; x from the first pose to the last, half a step beyond."""
    values = np.array([entry["value"] for entry in entries])
    limited = np.array([entry["cause"] != "none" for entry in entries])
    for start, end, cause in _limited_spans(entries):
        axes.axvspan(start, end, color=COLOURS[cause], alpha=0.25, linewidth=0, label=f"limited: {LABELS[cause]}")
    for key, name, style, colour in curves:
        series = _series(entries, key)
        if np.any(np.isfinite(series)):
            axes.plot(values, series, style, color=colour, linewidth=1.4, label=name)
            marked = limited & np.isfinite(series)
            if np.any(marked):
                axes.scatter(values[marked], series[marked], s=22, zorder=3, label="_limited pose", edgecolors="black",
                             linewidths=0.6, clip_on=False,
                             facecolors=[COLOURS[entries[i]["cause"]] for i in np.nonzero(marked)[0]])
    for y, label, colour in lines:
        axes.axhline(y, color=colour, linewidth=0.9, linestyle="-.", label=label)
    half = abs(values[1] - values[0]) / 2 if len(values) > 1 else 0.5
    axes.set_xlim(values[0] - half, values[-1] + half)
    axes.grid(True, linewidth=0.3)


def _unique_handles(figure):
    """The labelled artists drawn on the figure's axes, one per label: lines (curves and
    limits) first, then the shaded spans."""
    seen = {}
    for axes in figure.axes:
        for handle, label in zip(*axes.get_legend_handles_labels()):
            seen.setdefault(label, handle)
    return sorted(seen.values(), key=lambda handle: isinstance(handle, Patch))


def slice_figure(analysis):
    """The workspace slices side by side, equal-aspect, each cell coloured by what limits it,
    the axes reaching a margin beyond the analysed window, hatched grey there; a legend below
    naming only the causes that occur; None without slices."""
    slices = analysis["slices"]
    if not slices:
        return None
    from matplotlib.colors import ListedColormap

    figure = Figure(figsize=(12, 6), layout="constrained")
    # the default padding lets an equal-aspect axes' title run into the figure's title
    figure.get_layout_engine().set(h_pad=0.1)
    grid = figure.subplots(1, len(slices), squeeze=False)[0]
    colours = ListedColormap([COLOURS[cause] for cause in CAUSES])
    present = set()
    for axes, data in zip(grid, slices.values()):
        causes = np.array(data["causes"]).T
        present |= {CAUSES[int(index)] for index in np.unique(causes)}
        extent = [*_cell_edges(data["first"]), *_cell_edges(data["second"])]
        margin = 0.06 * max(extent[1] - extent[0], extent[3] - extent[2])
        axes.add_patch(Rectangle((0, 0), 1, 1, transform=axes.transAxes, zorder=0, label=OUTSIDE_LABEL, **OUTSIDE))
        axes.imshow(causes, origin="lower", extent=extent, cmap=colours, vmin=-0.5, vmax=len(CAUSES) - 0.5,
                    interpolation="nearest", zorder=1)
        axes.add_patch(Rectangle((extent[0], extent[2]), extent[1] - extent[0], extent[3] - extent[2], fill=False,
                                 edgecolor="#333333", linewidth=0.8, zorder=2))
        axes.set_xlim(extent[0] - margin, extent[1] + margin)
        axes.set_ylim(extent[2] - margin, extent[3] + margin)
        axes.set_aspect("equal")
        first, second = data["axes"]
        axes.set_xlabel(f"{first} (mm)")
        axes.set_ylabel(f"{second} (mm)")
        axes.set_title(f"{first}-{second} slice at home orientation, {len(data['first'])} x {len(data['second'])} "
                       "cells", fontsize=10)
    handles = [Patch(color=COLOURS[cause], label=LABELS[cause]) for cause in CAUSES if cause in present]
    handles.append(Patch(label=OUTSIDE_LABEL, **OUTSIDE))
    figure.suptitle(f"{analysis['robot']}, posture {analysis['posture']}: what limits the workspace", fontsize=11)
    figure.legend(handles=handles, loc="outside lower center", ncol=len(handles), fontsize=9, frameon=False)
    return figure


def _cell_edges(centres):
    """(low, high): the outer edges of a row of equally spaced cell centres."""
    half = (centres[-1] - centres[0]) / (len(centres) - 1) / 2 if len(centres) > 1 else 0.5
    return centres[0] - half, centres[-1] + half


def figure_objects(analysis):
    """{file name: matplotlib Figure} of every figure the analysis has data for: no tilt
    limits, no polar graph."""
    made = {"tilt_limits.png": polar_figure(analysis), "sweeps.png": sweep_figure(analysis),
            "slices.png": slice_figure(analysis), "loads.png": loads_figure(analysis)}
    return {name: figure for name, figure in made.items() if figure is not None}


def figures(analysis):
    """{file name: PNG bytes} of every figure the analysis has data for."""
    return {name: png(figure) for name, figure in figure_objects(analysis).items()}


def counts(analysis):
    """The numbers behind each figure: {tilt: {label: azimuths}, sweeps: [{name, unit, first,
    last, poses, causes}], slices: [{name, cells, window, causes, edge}]} with causes {label:
    count} listing only causes that occur, and edge saying how many of a slice's border cells
    are within limits (any: the workspace goes on past the window, unchecked)."""
    def tally(causes, labels=LABELS):
        return {labels[cause]: causes.count(cause) for cause in CAUSES if causes.count(cause)}

    searched = analysis["settings"].get("tilt_max_deg")
    tilt = tally([row["cause"] for row in analysis["tilt_limits"]],
                 {**LABELS, "none": f"not stopped up to {searched:g} deg" if searched else "not stopped"})
    sweeps = [{"name": name, "unit": "deg" if name in ANGLES else "mm", "first": entries[0]["value"],
               "last": entries[-1]["value"], "poses": len(entries),
               "causes": tally([entry["cause"] for entry in entries])}
              for name, entries in analysis["sweeps"].items() if entries]
    slices = []
    for data in analysis["slices"].values():
        causes = np.array(data["causes"])
        border = np.concatenate([causes[0], causes[-1], causes[1:-1, 0], causes[1:-1, -1]])
        inside = int(np.sum(border == CAUSES.index("none")))
        slices.append({
            "name": "-".join(data["axes"]), "cells": f"{causes.shape[0]} x {causes.shape[1]}",
            "window": f"{data['axes'][0]} {data['first'][0]:g} to {data['first'][-1]:g} mm, "
                      f"{data['axes'][1]} {data['second'][0]:g} to {data['second'][-1]:g} mm (cell centres)",
            "causes": tally([CAUSES[int(i)] for i in causes.ravel()]),
            "edge": f"{inside} of {len(border)} within limits" + (
                ": the workspace goes on past the window, unchecked" if inside else ": limited all round")})
    return {"tilt": tilt, "sweeps": sweeps, "slices": slices}


def _setting_text(value):
    if value is None:
        return "not available"
    if isinstance(value, (list, tuple)):
        return ", ".join(_setting_text(item) for item in value)
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _reason(note):
    """The reason of a ``not analysed: REASON`` note of analysis["available"] (else the note)."""
    return note.split(": ", 1)[1] if note.startswith("not analysed: ") else note


def report_html(robot, analysis, pngs, seconds, view=""):
    """The self-contained HTML report: summary, every setting, the counts behind each figure,
    the figures it is given embedded as data URIs (a missing one is said, not drawn empty), and
    the 3D ``view`` (HTML, kingen.view's fragment; "" for none) after the tilt limits."""
    images = {name: "data:image/png;base64," + base64.b64encode(data).decode("ascii") for name, data in pngs.items()}
    settings = {key: _setting_text(value) for key, value in analysis["settings"].items()}
    drawn = [" ".join(label.split()) for label, _ in _quantities(analysis["sweeps"])]
    missing = [" ".join(label.split()) for label, _ in QUANTITIES if " ".join(label.split()) not in drawn]
    return template("analysis_report.html.j2").render(
        robot=robot, analysis=analysis, images=images, labels=LABELS, colours=COLOURS, counts=counts(analysis),
        settings=settings, drawn=drawn, missing=missing, extremes=load_extremes(analysis), seconds=f"{seconds:.1f}",
        reason=_reason, view=Markup(view))
