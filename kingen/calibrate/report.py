"""What a calibration reports: calibration.json (plain data, mm and degrees) and report.html
(the residuals per pose before and after, the parameters' changes with their standard
deviations as error bars)."""

import base64
from dataclasses import asdict

import numpy as np
from markupsafe import Markup
from matplotlib.figure import Figure

from ..design.figures import png
from ..runtime.templates import template
from ..units import length_text, number_text


def summary(position, angle):
    """{rms_mm, max_mm, rms_deg, max_deg} of per-pose errors (degrees None for positions)."""
    def rms(values):
        return float(np.sqrt(np.mean(np.square(values))))

    return {"rms_mm": rms(position), "max_mm": float(np.max(position)),
            "rms_deg": None if angle is None else rms(angle), "max_deg": None if angle is None else float(np.max(angle))}


def result(parameters, fit, before, after, validation, seconds):
    """calibration.json's content: ``before`` and ``after`` are (position, angle) per-pose
    errors, ``validation`` a pair: the same on held-out measurements after, and of the nominal
    robot (frame and target fitted) there (each None without them). A parameter's ``std`` is
    null unless it was identified with redundancy (kingen.calibrate.noise)."""
    values = fit.values
    inference = fit.inference
    reported = bool(np.any(np.isfinite(fit.std)))
    return {
        "parameters": [{"name": entry.name, "nominal": entry.nominal, "identified": float(value),
                        "std": None if not np.isfinite(std) else float(std), "identifiable": bool(chosen)}
                       for entry, value, std, chosen in zip(parameters.entries, values, fit.std, fit.chosen)],
        "measuring_frame": [float(v) for v in values[parameters.groups == "frame"]],
        "target": [float(v) for v in values[parameters.groups == "target"]],
        "unidentifiable": list(fit.unidentifiable),
        "condition_number": fit.indices["condition_number"],
        "min_singular_value": fit.indices["min_singular_value"],
        "noise_amplification": fit.indices["noise_amplification"],
        "residuals_before": summary(*before),
        "residuals_after": summary(*after),
        "validation": None if validation[0] is None else summary(*validation[0]),
        "validation_nominal": None if validation[1] is None else summary(*validation[1]),
        "noise": asdict(fit.stated),
        "equations": int(inference.redundancy + np.count_nonzero(fit.chosen)),
        "redundancy": int(inference.redundancy),
        "variance_factor": float(inference.variance_factor) if inference.redundancy > 0 else None,
        "std_reported": reported,
        "outliers": list(fit.outliers),
        "poses": int(len(before[0])),
        "seconds": float(seconds),
    }


def residual_figure(before, after):
    """PNG: each pose's position error (and orientation error) before and after, as bars on a
    log scale. Each series is one PolyCollection of numpy rectangles (some 100 bytes a pose)
    rather than one matplotlib patch per bar (some 20 kB a pose), so memory stays small for
    the most measurements a file may hold."""
    panels = 1 if before[1] is None else 2
    figure = Figure(figsize=(8.0, 2.6 * panels + 0.6), layout="constrained")
    for panel, unit in zip(range(panels), ("mm", "deg")):
        axes = figure.add_subplot(panels, 1, panel + 1)
        poses = np.arange(1, len(before[0]) + 1)
        heights = np.concatenate([before[panel], after[panel]])
        positive = heights[heights > 0]
        floor = positive.min() / 2.0 if positive.size else 1e-12
        _bars(axes, poses - 0.4, before[panel], floor, "#999999", "before (frame and target fitted)")
        _bars(axes, poses, after[panel], floor, "#1f77b4", "after calibration")
        axes.set_yscale("log")
        axes.autoscale_view()
        axes.set_xlabel("pose (row of the measurement file)")
        axes.set_ylabel(f"{'position' if panel == 0 else 'orientation'} error ({unit})")
        axes.grid(alpha=0.3)
    figure.legend(*figure.axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=2, fontsize=8,
                  frameon=False)
    return png(figure)


def _bars(axes, lefts, heights, floor, color, label):
    """Bars 0.4 wide from ``lefts`` up to ``heights`` (from ``floor``, the log scale's bottom,
    which a bar below it reaches), one PolyCollection."""
    from matplotlib.collections import PolyCollection

    tops = np.maximum(np.asarray(heights, dtype=float), floor)
    corners = np.empty((len(lefts), 4, 2))
    corners[:, :, 0] = lefts[:, None] + np.array([0.0, 0.0, 0.4, 0.4])
    corners[:, :, 1] = np.column_stack([np.full(len(tops), floor), tops, tops, np.full(len(tops), floor)])
    axes.add_collection(PolyCollection(corners, facecolors=color, edgecolors="none", label=label))


PANELS = (("limbs", "mm"), ("limbs", "deg"), ("frames", "mm"), ("frames", "deg"))
"""The parameter chart's panels, in order: the limbs' geometry (and a wrist's), then the
measuring frame and the target, each in mm and in degrees."""

PANEL_TITLES = {"limbs": "limb geometry", "frames": "measuring frame and target"}


def _panel(entry):
    """The (part, unit) panel of PANELS that ``entry`` (a calibrate.parameters.Parameter) is drawn in."""
    return ("frames" if entry.group in ("frame", "target") else "limbs", entry.unit)


def parameter_figure(outcome, entries):
    """PNG of parameter_chart."""
    return png(parameter_chart(outcome, entries))


def parameter_chart(outcome, entries):
    """Figure: identified minus nominal per identified parameter, one standard deviation as error
    bars, in one panel per part and unit (PANELS: the limbs' geometry, then the measuring frame
    and the target, in mm and in degrees), each on its own scale, so a limb's 0.5 mm change is
    not drawn on the axis of a measuring frame 1,200 mm away. ``entries`` are the parameters
    (calibrate.parameters.Parameter) in the order of ``outcome["parameters"]``."""
    chosen = [(row, _panel(entry)) for row, entry in zip(outcome["parameters"], entries) if row["identifiable"]]
    panels = [(key, [row for row, panel in chosen if panel == key]) for key in PANELS]
    panels = [(key, rows) for key, rows in panels if rows] or [(PANELS[0], [])]
    heights = [0.16 * len(rows) + 0.9 for _, rows in panels]
    figure = Figure(figsize=(8.0, max(3.0, sum(heights) + 0.4)), layout="constrained")
    for axes, ((part, unit), rows) in zip(figure.subplots(len(panels), 1, squeeze=False,
                                                         gridspec_kw={"height_ratios": heights})[:, 0], panels):
        positions = np.arange(len(rows))
        axes.errorbar([row["identified"] - row["nominal"] for row in rows], positions,
                      xerr=[row["std"] or 0.0 for row in rows], fmt="o", markersize=3, color="#1f77b4",
                      ecolor="#555555")
        axes.set_yticks(positions, [row["name"] for row in rows], fontsize=6)
        axes.set_ylim(max(len(rows), 1) - 0.5, -0.5)
        axes.axvline(0.0, color="#222222", linewidth=0.8)
        axes.set_title(f"{PANEL_TITLES[part]} ({unit})", fontsize=9, loc="left")
        axes.set_xlabel(f"identified - nominal ({unit}); bars: one standard deviation", fontsize=8)
        axes.grid(alpha=0.3)
    return figure


def report_html(robot_name, outcome, pngs, settings, view=""):
    """The self-contained report; residuals written for people (kingen.units: a length in the
    unit that suits it, no exponent); the 3D ``view`` (HTML, kingen.view's fragment; "" for
    none) after the residuals."""
    images = {name: base64.b64encode(data).decode("ascii") for name, data in pngs.items()}
    return template("calibration_report.html.j2").render(robot=robot_name, result=outcome, images=images,
                                                         settings=settings, length=length_text, number=number_text,
                                                         view=Markup(view))
