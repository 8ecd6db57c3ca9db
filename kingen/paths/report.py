"""What a check reports: the verdict, the checks it judged (and those it could not), the
problems by line, the JSON document, the CSV of every sample and the HTML page.

Units: poses mm and degrees; joints, speeds and accelerations in the robot file's joint
units (mm or degrees, per s, per s^2); radicands unitless; the direct index and the force
lines' determinant in mm and mm^3; clearances in mm.
"""

import numpy as np

from ..runtime.text import counted, one_line
from ..units import number_text
from .manifold import OFF_MANIFOLD
from .power import power_limited
from .program import POSE_COLUMNS, is_gcode

BLENDING = ("G-code timed as LinuxCNC's trajectory planner moves it (G61, G61.1, G64 blend arcs, look-ahead, the "
            ".ini's axis limits; parabolic blends rest to rest at half acceleration); a CSV's rows from rest to rest")
SPEED_KINDS = ("joint speed", "joint acceleration")


def checks(outcome):
    """{kind: 'passed' | 'failed' | 'not exercised: why'} of every check, in report order."""
    evaluator, limits, findings = outcome.evaluator, outcome.limits, outcome.findings
    failed = {place.kind for place in findings.worst.values()}
    verdicts = {}
    reasons = {
        "unreachable": "no limb of this robot can be out of reach (legs)",
        "travel": "no joint has travel limits (robot file travel, .ini MIN_LIMIT/MAX_LIMIT)",
        "limb singular": "no limb of this robot has a singular band (legs)",
        "direct index": "the robot file gives no singularity.direct_index_min" if evaluator.six_lines
        else "the robot has no six force lines",
        "assembly change": "the robot has no six force lines",
        "collision": "the robot file gives no collision: radii (rod_radius, leg_radius, crank_radius)"
        if outcome.robot.collision is None else "the robot has fewer than two limbs",
        "joint angle": "the robot file gives no limb joint_limits",
        "actuator load": "the robot file gives no limb max_force or max_torque",
    }
    if findings.samples == 0:
        return {kind: "not exercised: the program has no move" for kind in list(reasons) + list(SPEED_KINDS)
                + ["actuator power"]}
    kinds = evaluator.kinds()
    for kind in reasons:
        verdicts[kind] = ("failed" if kind in failed else "passed") if kind in kinds else f"not exercised: {reasons[kind]}"
    for kind, bounds, timed in (("joint speed", limits.speed, findings.timed_moves > 0),
                                ("joint acceleration", limits.acceleration, findings.accelerated_moves > 0)):
        if not np.any(np.isfinite(bounds)):
            verdicts[kind] = (f"not exercised: no joint {kind.split()[1]} limit (robot file max_"
                              f"{kind.split()[1]}, .ini MAX_{'VELOCITY' if kind == 'joint speed' else 'ACCELERATION'})")
        elif not timed:
            verdicts[kind] = ("not exercised: no move is timed (feeds and rapids need a feed or t, or an .ini)"
                              if kind == "joint speed" else "not exercised: no move's accelerations are known (a path "
                              "acceleration, .ini [TRAJ], or CSV times)")
        else:
            verdicts[kind] = "failed" if kind in failed else "passed"
    verdicts["actuator power"] = (
        "not exercised: the robot file gives no limb max_power" if not power_limited(outcome.robot)
        else "not exercised: no move is timed (feeds and rapids need a feed or t, or an .ini)"
        if findings.timed_moves == 0 else "failed" if "actuator power" in failed else "passed")
    if outcome.manifold is not None:
        verdicts[OFF_MANIFOLD] = outcome.manifold.verdict()
    return verdicts


def runs(outcome):
    """Whether the program runs within every limit that was judged: something was judged (a
    sample), and nothing beyond a limit."""
    return outcome.findings.samples > 0 and not outcome.findings.worst


def verdict(outcome):
    """The verdict in words: "runs", "does not run", or "judged nothing" (no sample: the program
    has no move, or only moves of length 0)."""
    if outcome.findings.samples == 0:
        return "judged nothing"
    return "runs" if runs(outcome) else "does not run"


def verdict_line(outcome):
    """The one-line verdict with the counts and settings behind it."""
    findings, settings = outcome.findings, outcome.settings
    judged = [kind for kind, verdict in checks(outcome).items() if not verdict.startswith("not exercised")]
    where = (f"{counted(findings.moves, 'move')}, {counted(findings.samples, 'sample')} at chord {settings.chord:g} "
             f"mm/deg, posture {outcome.posture}, host {settings.host}")
    if findings.samples == 0:
        return (f"check-path {outcome.robot.name} {outcome.program}: judged nothing: the program has no move "
                f"that goes anywhere ({where})")
    if runs(outcome):
        return f"check-path {outcome.robot.name} {outcome.program}: runs within every limit judged ({where}; " \
               f"judged: {', '.join(judged) or 'nothing'})"
    problems = findings.sorted_problems()
    lines = {(place.file, place.line) for place in problems}
    first = place_line(problems[0]) if problems else "?"
    return (f"check-path {outcome.robot.name} {outcome.program}: does not run: "
            f"{counted(len(findings.problems) + findings.dropped, 'problem')} on {counted(len(lines), 'line')}, "
            f"first at line {first} ({where})")


def reading_line(outcome):
    """For G-code, what LinuxCNC's interpreter emitted and what was judged, and the work
    offset the program started with; None for a CSV."""
    reading = outcome.reading
    if reading is None:
        return None
    offset = reading.work_offset or {"system": "G54", "g5x": [0.0] * 6, "g92": [0.0] * 6}
    g92 = "" if not any(offset["g92"]) else f", G92 {' '.join(f'{value:g}' for value in offset['g92'])}"
    counts = "" if reading.rs274_motions is None else f", {reading.rs274_motions} as rs274 counts them"
    return (f"G-code: {counted(reading.motions, 'motion')} from LinuxCNC's interpreter{counts} "
            f"({reading.zero_length} of length 0), {counted(outcome.findings.moves, 'move')} judged; work offset "
            f"{offset['system']} {' '.join(f'{value:g}' for value in offset['g5x'])}{g92} ({reading.offset_from})")


def place_line(place):
    """A place's line as the report shows it: ``line``, or ``file:line`` in a subroutine's file."""
    return f"{place.file}:{place.line}" if place.file is not None else str(place.line)


def source_of(outcome, place):
    """The text of a place's line."""
    return outcome.sources.get((place.file, place.line), "")


def _joint_units(outcome, joint, kind, between=None):
    if kind == OFF_MANIFOLD:
        return "mm" if between in POSE_COLUMNS[:3] else "deg"
    if joint is None:
        return {"direct index": "mm", "assembly change": "mm^3", "collision": "mm"}.get(kind, "")
    index = outcome.robot.joint_names.index(joint)
    base = "deg" if outcome.robot.revolute[index] else "mm"
    if kind in ("unreachable", "limb singular"):
        return ""
    if kind == "joint angle":
        return "deg"
    if kind == "actuator load":
        return "N m" if outcome.robot.revolute[index] else "N"
    if kind == "actuator power":
        return "W"
    return {"joint speed": f"{base}/s", "joint acceleration": f"{base}/s^2"}.get(kind, base)


def problem_rows(outcome):
    """The table of problems by line: header and rows of text."""
    rows = [["line", "problem", "joint", "value", "limit", "source"]]
    for place in outcome.findings.sorted_problems():
        units = _joint_units(outcome, place.joint, place.kind, place.between)
        extra = f" (fits at {place.override * 100:.0f}% feed)" if place.override is not None else ""
        rows.append([place_line(place), place.kind, " ".join(filter(None, (place.joint, place.between))) or "-",
                     f"{number_text(place.value, 6)} {units}".strip() + extra,
                     f"{number_text(place.limit, 6)} {units}".strip(), one_line(source_of(outcome, place))[:60]])
    return rows


def _place_json(outcome, place):
    data = {"kind": place.kind, "line": place.line, "source": source_of(outcome, place),
            "joint": place.joint, "pose": place.pose, "joints": place.joints, "value": place.value,
            "limit": place.limit, "units": _joint_units(outcome, place.joint, place.kind, place.between)}
    if place.override is not None:
        data["override"] = place.override
    if place.between is not None:
        data["between"] = place.between
    if place.file is not None:
        data["file"] = place.file
    return data


def report_json(outcome):
    """The JSON document (plain data): verdict, samples, moves, problems, first and worst place
    of each kind, peaks per joint, checks, limits and settings; for a machine with task
    coordinates also ``parasitic`` ({coordinate: [min, max]} over the reachable samples, mm and degrees)
    and ``manifold`` (what is read, the CSV rows' deviations: manifold.Manifold.summary); for one
    with a wrist ``five_axis`` (how the program's poses are read: five_axis.FiveAxis.summary)."""
    findings, limits = outcome.findings, outcome.limits
    peaks = []
    for index, (name, peak) in enumerate(zip(outcome.robot.joint_names, findings.peaks)):
        scale = findings.display_scale[index]
        peaks.append({"joint": name, "travel": [peak.low, peak.high], "speed": peak.speed,
                      "speed_line": peak.speed_line, "acceleration": peak.acceleration,
                      "acceleration_line": peak.acceleration_line,
                      "travel_limits": [limits.lower[index] * scale, limits.upper[index] * scale],
                      "speed_limit": limits.speed[index] * scale,
                      "acceleration_limit": limits.acceleration[index] * scale})
    document = {
        "verdict": verdict(outcome),
        "robot": outcome.robot.name, "program": outcome.program,
        "samples": findings.samples, "moves": findings.moves, "timed_moves": findings.timed_moves,
        "accelerated_moves": findings.accelerated_moves, "checks": checks(outcome),
        "problems": [_place_json(outcome, place) for place in findings.sorted_problems()],
        "problems_not_listed": findings.dropped,
        "first": [_place_json(outcome, place) for place in findings.first.values()],
        "worst": [_place_json(outcome, place) for place in findings.worst.values()],
        "peaks": peaks,
        "settings": {"host": outcome.settings.host, "posture": outcome.posture, "chord": outcome.settings.chord,
                     "ini": None if outcome.settings.ini is None else str(outcome.settings.ini),
                     "limits_from": list(limits.sources), "path_speed_mm_s": limits.path_speed,
                     "path_acceleration_mm_s2": limits.path_acceleration, "timing": BLENDING,
                     "solver": _solver(outcome)},
        "seconds": outcome.seconds,
    }
    if outcome.manifold is not None:
        document["parasitic"], document["manifold"] = outcome.manifold.summary()
        document["settings"]["task_only"] = outcome.settings.task_only
    if outcome.five_axis is not None:
        document["five_axis"] = outcome.five_axis.summary(is_gcode(outcome.program))
    if outcome.reading is not None:
        reading = outcome.reading
        document["gcode"] = {"motions": reading.motions, "rs274_motions": reading.rs274_motions,
                             "zero_length": reading.zero_length,
                             "judged_moves": findings.moves, "files": sorted(set(reading.files.values())),
                             "work_offset": reading.work_offset, "offset_from": reading.offset_from}
    return document


def _solver(outcome):
    """What solved the samples, and how the routine agreed with the reference where it was used."""
    if outcome.agreement is None:
        return "the numpy reference (kingen.kinematics.reference), in batches"
    agreement = outcome.agreement
    return (f"the robot's {outcome.settings.host} routine through the host's batch driver for the regular samples' "
            f"joints ({counted(agreement.samples, 'sample')}: largest difference from the reference "
            f"{agreement.joint_difference:.3g} mm or deg, {counted(agreement.warning_mismatches, 'warning')} differing); "
            "the numpy reference for the decision quantities and the refined samples")


def csv_header(robot):
    """The CSV's columns: the line, the move's parameter u, the pose, each joint's value, speed
    and acceleration (empty off the regular samples), the smallest limb radicand, the direct index."""
    names = robot.joint_names
    return ",".join(["line", "u", "x", "y", "z", "roll", "pitch", "yaw"] + list(names)
                    + [f"{name}_speed" for name in names] + [f"{name}_acceleration" for name in names]
                    + ["radicand", "direct_index"]) + "\n"


def csv_rows(lines, batch, rates, display_scale):
    """The CSV lines of a batch of samples on program ``lines`` (n,) (display units; NaN written empty)."""
    columns = np.column_stack([lines, batch.u, batch.poses, batch.joints * display_scale,
                               rates[:, 0] * display_scale, rates[:, 1] * display_scale, batch.radicand,
                               batch.direct_index])
    text = "\n".join(",".join("" if not np.isfinite(value) else f"{value:.15g}" for value in row) for row in columns)
    return text + "\n" if text else ""
