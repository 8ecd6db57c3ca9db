"""analyze's loads in pictures and numbers: the workspace slices coloured by the largest actuator
load over its limit and by the platform's least stiffness, and where over the sweeps and slices
each is at its worst (kingen.design.load_analysis computes them per pose)."""

import numpy as np
from matplotlib.colors import LogNorm, Normalize
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from .analysis import CAUSES
from .load_analysis import LOAD_KEYS

TITLES = {"load_fraction": "largest actuator load / its limit (1: at the limit)",
          "min_stiffness_n_per_mm": "least stiffness of the platform origin (N/mm)"}
"""Each quantity's name and unit, as the figure's colour bars and the report say them."""
WORST = {"load_fraction": np.nanargmax, "min_stiffness_n_per_mm": np.nanargmin}
"""Which end of a quantity is its worst: the largest load fraction, the least stiffness."""
ANGLES = ("roll", "pitch", "yaw")
"""The sweeps whose values are degrees (the others' are mm)."""
COLOUR_MAPS = {"load_fraction": "magma_r", "min_stiffness_n_per_mm": "viridis"}
LOADED = ("none", "actuator_load", "joint_angle")
"""The causes of poses whose loads count: within every limit, or stopped by loads alone (a pose
beyond the workspace's geometry, near a singularity say, would swamp the rest)."""


def _grid(data, key):
    """(first, second) float array of a slice's ``key``, NaN where null or where the cell's cause
    is not one of LOADED."""
    values = np.array([[np.nan if value is None else value for value in row] for row in data[key]], dtype=float)
    return np.where(np.isin(data["causes"], [CAUSES.index(cause) for cause in LOADED]), values, np.nan)


def load_extremes(analysis):
    """[{key, title, value, where}] for each of LOAD_KEYS with data: its worst value (the largest
    load fraction, the least stiffness in N/mm) over the sweeps' and slices' poses of a LOADED
    cause, and that pose
    in words ('x sweep at 12.5 mm', 'xy slice at x 10 mm, y -4 mm')."""
    extremes = []
    for key in LOAD_KEYS:
        candidates = [(entry[key], f"{name} sweep at {entry['value']:g} {'deg' if name in ANGLES else 'mm'}")
                      for name, entries in analysis["sweeps"].items() for entry in entries
                      if entry.get(key) is not None and entry["cause"] in LOADED]
        for name, data in analysis["slices"].items():
            if key in data:
                grid = _grid(data, key)
                for i, j in zip(*np.nonzero(np.isfinite(grid))):
                    first, second = data["axes"]
                    candidates.append((grid[i, j], f"{name} slice at {first} {data['first'][i]:g} mm, "
                                                   f"{second} {data['second'][j]:g} mm"))
        if candidates:
            best = int(WORST[key]([value for value, _ in candidates]))
            extremes.append({"key": key, "title": TITLES[key], "value": float(candidates[best][0]),
                             "where": candidates[best][1]})
    return extremes


def _scale(key, low, high):
    """The colour scale of ``key`` from ``low`` to ``high``: a stiffness's logarithmic where it spans
    a decade or more (it soars where the legs line up with a force, and would flatten the rest)."""
    if key == "min_stiffness_n_per_mm" and low > 0.0 and high >= 10.0 * low:
        return LogNorm(low, high)
    return Normalize(low, max(high, low + 1e-12))


def loads_figure(analysis):
    """The slices coloured by each of LOAD_KEYS that has data (one row per quantity, one column
    per slice, equal-aspect, a colour bar with the unit per row; the worst cell ringed; blank
    where the cell's cause is not LOADED); None without slices that carry loads."""
    slices = analysis["slices"]
    keys = [key for key in LOAD_KEYS if any(key in data and np.any(np.isfinite(_grid(data, key)))
                                            for data in slices.values())]
    if not keys:
        return None
    figure = Figure(figsize=(12, 0.8 + 4.6 * len(keys)), layout="constrained")
    shapes = [(data["first"][-1] - data["first"][0] + 1e-9) / (data["second"][-1] - data["second"][0] + 1e-9)
              for data in slices.values()]  # each slice's width over its height: equal-aspect panels share the width
    grid = figure.subplots(len(keys), len(slices), squeeze=False, width_ratios=[max(shape, 0.3) for shape in shapes])
    for row, key in enumerate(keys):
        values = [_grid(data, key) for data in slices.values() if key in data]
        low = min(float(np.nanmin(v)) for v in values if np.any(np.isfinite(v)))
        high = max(float(np.nanmax(v)) for v in values if np.any(np.isfinite(v)))
        image = None
        for axes, data in zip(grid[row], slices.values()):
            first, second = data["axes"]
            axes.set_xlabel(f"{first} (mm)")
            axes.set_ylabel(f"{second} (mm)")
            axes.set_aspect("equal")
            if key not in data or not np.any(np.isfinite(_grid(data, key))):
                axes.set_title(f"{first}-{second} slice: no data", fontsize=10)
                continue
            cells = _grid(data, key)
            spacing = [(c[1] - c[0]) / 2 if len(c) > 1 else 0.5 for c in (data["first"], data["second"])]
            extent = [data["first"][0] - spacing[0], data["first"][-1] + spacing[0],
                      data["second"][0] - spacing[1], data["second"][-1] + spacing[1]]
            image = axes.imshow(cells.T, origin="lower", extent=extent, cmap=COLOUR_MAPS[key],
                                norm=_scale(key, low, high), interpolation="nearest")
            if np.any(np.isfinite(cells)):
                i, j = np.unravel_index(int(WORST[key](cells)), cells.shape)
                axes.add_patch(Rectangle((data["first"][i] - spacing[0], data["second"][j] - spacing[1]),
                                         2 * spacing[0], 2 * spacing[1], fill=False, edgecolor="#d62728",
                                         linewidth=1.5))
            axes.set_title(f"{first}-{second} slice at home orientation", fontsize=10)
        if image is not None:
            figure.colorbar(image, ax=list(grid[row]), label=TITLES[key], shrink=0.9)
    figure.suptitle(f"{analysis['robot']}, posture {analysis['posture']}: loads over the workspace slices "
                    "(the payload at rest; blank: a limit other than loads; ringed: the worst cell)", fontsize=11)
    return figure
