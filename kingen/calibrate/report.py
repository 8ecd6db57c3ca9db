"""What a calibration reports: calibration.json (plain data, mm and degrees) and report.html
(the residuals per pose before and after, the parameters' changes with their standard
deviations as error bars)."""

import base64

import numpy as np
from matplotlib.figure import Figure

from ..design.figures import png
from ..runtime.templates import template


def summary(position, angle):
    """{rms_mm, max_mm, rms_deg, max_deg} of per-pose errors (degrees None for positions)."""
    def rms(values):
        return float(np.sqrt(np.mean(np.square(values))))

    return {"rms_mm": rms(position), "max_mm": float(np.max(position)),
            "rms_deg": None if angle is None else rms(angle), "max_deg": None if angle is None else float(np.max(angle))}


def result(parameters, fit, before, after, validation, seconds):
    """calibration.json's content: ``before`` and ``after`` are (position, angle) per-pose
    errors, ``validation`` the same on held-out measurements after (or None)."""
    values = fit.values
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
        "validation": None if validation is None else summary(*validation),
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


def parameter_figure(outcome):
    """PNG: identified minus nominal per identified parameter, one standard deviation as error bars."""
    rows = [row for row in outcome["parameters"] if row["identifiable"]]
    figure = Figure(figsize=(8.0, max(3.0, 0.16 * len(rows) + 1.2)), layout="constrained")
    axes = figure.add_subplot()
    positions = np.arange(len(rows))
    axes.errorbar([row["identified"] - row["nominal"] for row in rows], positions,
                  xerr=[row["std"] or 0.0 for row in rows], fmt="o", markersize=3, color="#1f77b4", ecolor="#555555")
    axes.set_yticks(positions, [row["name"] for row in rows], fontsize=6)
    axes.invert_yaxis()
    axes.axvline(0.0, color="#222222", linewidth=0.8)
    axes.set_xlabel("identified - nominal (mm or deg); bars: one standard deviation")
    axes.grid(alpha=0.3)
    return png(figure)


def report_html(robot_name, outcome, pngs, settings):
    """The self-contained report."""
    images = {name: base64.b64encode(data).decode("ascii") for name, data in pngs.items()}
    return template("calibration_report.html.j2").render(robot=robot_name, result=outcome, images=images,
                                                         settings=settings)
