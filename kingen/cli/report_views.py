"""The 3D view each report holds (kingen.view, as an ``<iframe srcdoc>``): check-path's path
played on a timeline with its problems marked, calibrate's residual arrows and magnified ghost,
analyze's tilt-limit surface with the machine at each limit. The reports' own modules give the
overlays as plain data (kingen.paths.playback, kingen.calibrate.drawing, kingen.design.tilt_view);
here they are put into the view's scene, so the reports' layers never import the view.

Every report's view draws the poses kingen computed (no WebAssembly routine inside: the report
shows what was judged; ``kingen view`` has the sliders), with one copy of three.js per report.
"""

from pathlib import Path

VIEW_HEIGHT = 620
"""The view's height in a report (px)."""


def path_view(outcome):
    """check-path's view of ``outcome`` (paths.check.Outcome): the path's frames and the problems'
    markers (kingen.paths.playback), the machine shown at the first problem (without one, at the
    program's first checked pose)."""
    from ..paths.playback import playback
    from ..view import scene, view_fragment

    overlays = playback(outcome)
    frames, markers = overlays["frames"], overlays["markers"]
    start = markers[0]["frame"] if markers else 0
    program = Path(outcome.program).name
    marked = ("no problem to mark on the timeline" if not markers else
              f"{len(markers)} problem{'s' if len(markers) > 1 else ''} numbered on the timeline (click one to see "
              "the machine there)")
    shown = {**scene(outcome.robot, frames[start]["pose"] if frames else None, outcome.posture), **overlays,
             "description": f"{program} on {outcome.robot.name}, posture {outcome.posture}: {len(frames):,} frames "
                            f"along the program, {marked}"}
    if frames:
        shown["start_frame"] = start
    return view_fragment(outcome.robot, shown, title=f"{outcome.robot.name}: {program}", routine=False,
                         height=VIEW_HEIGHT)


def calibration_view(parameters, fit):
    """calibrate's view: the nominal machine at home, each pose's residual after calibration as an
    arrow at its measured point, and the calibrated machine as a ghost, its geometry changes
    magnified (kingen.calibrate.drawing; ``fit`` an identification.Fit of ``parameters``)."""
    from ..calibrate.drawing import magnified_robot, residual_arrows
    from ..view import machine_at, scene, view_fragment

    robot = parameters.robot
    shown = scene(robot)
    arrows, factor = residual_arrows(fit.problem, fit.values)
    words = [f"{len(arrows)} residuals after calibration (predicted - measured) as arrows at the measured points, "
             f"drawn {factor:,.0f} times longer"]
    ghost, scale = magnified_robot(parameters, fit.values)
    if ghost is not None:
        drawing, _, _ = machine_at(ghost, shown["t6"], shown["posture"])
        shown["ghost"] = {**drawing, "scale": scale, "label": "calibrated machine"}
        words.append(f"the calibrated machine as a ghost, its geometry changes drawn {scale:,.0f} times larger")
    else:
        words.append("no geometry changed (only the measuring frame and the target)")
    shown.update(arrows=arrows, description=f"{robot.name} at home: " + "; ".join(words))
    return view_fragment(robot, shown, title=f"{robot.name}: calibration", routine=False, height=VIEW_HEIGHT)


def analysis_view(robot, analysis, convention):
    """analyze's view of ``analysis`` (design.analysis.analyze's, tilts in ``convention``): the
    machine at home, the tilt limits as a surface, their tips labelled with the cause, and the
    machine at each azimuth's limit on the timeline (kingen.design.tilt_view)."""
    from ..design.tilt_view import tilt_overlays
    from ..view import scene, view_fragment

    overlays = tilt_overlays(robot, analysis, convention)
    about = (f"the largest tilt towards each of {len(overlays['frames'])} azimuths as a surface, the machine at each "
             "limit on the timeline" if overlays else "no tilt limits (the platform does not tilt)")
    shown = {**scene(robot, None, analysis["posture"]), **overlays,
             "description": f"{robot.name}, posture {analysis['posture']}, at home: {about}"}
    return view_fragment(robot, shown, title=f"{robot.name}: tilt limits", routine=False, height=VIEW_HEIGHT)
