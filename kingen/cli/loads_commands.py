"""``kingen loads``: what it takes to hold or move the machine's payload at a pose (actuator
forces and torques, what the constraints carry, passive-joint angles, deflection), each against
its limit (kingen.kinematics.loads)."""

import json
import math
from pathlib import Path

import click

from ..defaults import LOAD_RATE_MAX, LOAD_WRENCH_MAX
from .common import EXIT_FAILED, ROBOT, _output_file, _pose, cli, finite, load_model, print_table, say



def _bounded(limit, what):
    def check(context, parameter, values):
        if values is not None and not all(math.isfinite(v) and abs(v) <= limit for v in values):
            raise click.BadParameter(f"six finite numbers within +/-{limit:g} ({what}) expected")
        return values
    return check


@cli.command()
@ROBOT
@click.option("--pose", nargs=6, type=float, metavar="X Y Z ROLL PITCH YAW", callback=_pose, default=None,
              help="The platform's pose (mm, degrees) [default: the verification home]; a constrained machine "
                   "takes the pose its constraints give for its task coordinates.")
@click.option("--velocity", nargs=6, type=float, default=None, metavar="VX VY VZ WX WY WZ",
              callback=_bounded(LOAD_RATE_MAX, "mm/s and deg/s"),
              help="The platform frame origin's velocity (mm/s) and angular velocity (deg/s), base frame.")
@click.option("--acceleration", nargs=6, type=float, default=None, metavar="AX AY AZ ALPHAX ALPHAY ALPHAZ",
              callback=_bounded(LOAD_RATE_MAX, "mm/s^2 and deg/s^2"),
              help="The platform frame origin's acceleration (mm/s^2) and angular acceleration (deg/s^2), base frame.")
@click.option("--wrench", nargs=6, type=float, default=None, metavar="FX FY FZ MX MY MZ",
              callback=_bounded(LOAD_WRENCH_MAX, "N and N m"),
              help="An external wrench applied at the platform origin (N, N m), base frame.")
@click.option("--posture", type=click.IntRange(min=0), default=None,
              help="Only this posture [default: every posture that reaches the pose].")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write the loads as JSON.")
def loads(robot, pose, velocity, acceleration, wrench, posture, json_path):
    """Actuator forces and torques that hold or move the payload at a pose, what the constraints
    carry, each passive joint's angle and the platform's deflection, against the robot file's
    limits (max_force, max_torque, joint_limits). Positive: the force or torque an actuator exerts
    in the direction that increases its joint.

    Exit 0 when every load and angle shown is within its limit, 1 when one is beyond it (named)."""
    import numpy as np

    from .. import loads as compute
    from ..kinematics.loads import machine_pose
    from ..kinematics.routine import WARNING_NAMES, WARNINGS
    from ..runtime.files import write_atomic

    model = load_model(robot)
    if posture is not None and posture >= model.postures:
        raise click.BadParameter(f"{model.name} has postures 0 to {model.postures - 1}", param_hint="--posture")
    asked = np.array(pose if pose is not None else model.verification.home, dtype=float)
    chosen = list(range(model.postures)) if posture is None else [posture]
    result = compute(model, [asked], wrench=wrench, velocity=velocity, acceleration=acceleration, postures=chosen)
    postures = [_posture_loads(model, result, column, number, WARNING_NAMES) for column, number in enumerate(chosen)
                if result.warnings[0, column] != WARNINGS["WARN_UNREACHABLE"]]
    at = machine_pose(result)[0]
    document = {"robot": model.name, "pose": asked.tolist(), "machine_pose": at.tolist(),
                "payload": _payload_text(model), "gravity": list(model.gravity),
                "velocity": list(velocity) if velocity else None, "acceleration": list(acceleration) if acceleration
                else None, "wrench": list(wrench) if wrench else None, "postures": postures}
    if json_path is not None:
        write_atomic(json_path, json.dumps(finite(document), indent=2, allow_nan=False) + "\n")
    _print(model, asked, at, postures, velocity is not None or acceleration is not None, wrench)
    beyond = [f"posture {entry['posture']}: {text}" for entry in postures for text in entry["beyond"]]
    for line in beyond:
        say(f"BEYOND LIMIT {line}")
    if not postures:
        say("no posture reaches the pose")
        return EXIT_FAILED
    return EXIT_FAILED if beyond else 0


def _payload_text(model):
    payload = model.payload
    if payload is None:
        return None
    return {"mass": payload.mass, "centre": list(payload.centre), "inertia": [list(row) for row in payload.inertia]}


def _posture_loads(model, result, column, posture, warning_names):
    """The entry of the JSON's ``postures`` of ``posture`` (``result``'s posture ``column``), with
    ``beyond``: what leaves its limit, in words."""
    import numpy as np

    from ..kinematics.loads import beyond_limits

    forces = result.forces[0, column]
    units = ["N m" if t.wraps else "N" for t in model.joint_types]
    names = model.joint_names
    loaded, bent = beyond_limits(model, result, 0, column)
    beyond = [text for _, _, text in sorted(
        [(n, 0, f"{names[n]} {force:.6g} {units[n]} beyond its {limit:g} {units[n]}") for n, force, limit in loaded]
        + [(n, 1, f"{names[n]} {side} joint at {angle:.6g} deg beyond its {cone:g} deg") for n, side, angle, cone in bent])]
    deflection = None
    if result.deflection is not None:
        move = result.deflection[0, column]
        deflection = [*move[:3].tolist(), *np.degrees(move[3:]).tolist()]
    constraint = result.constraint[0, column]
    return {"posture": posture, "warning": warning_names.get(int(result.warnings[0, column]), "?"),
            "forces": forces.tolist(), "units": units,
            "limits": [limb.actuator_limit for limb in model.limbs] + [None] * (model.joint_count - model.dof),
            "joint_angles": {"base": np.degrees(result.base_angles[0, column]).tolist(),
                             "platform": np.degrees(result.platform_angles[0, column]).tolist()},
            "constraint": {"force": constraint[:3].tolist(), "moment": constraint[3:].tolist()},
            "deflection": deflection, "beyond": beyond}


def _print(model, asked, at, postures, moving, wrench):
    import numpy as np

    said = "moving" if moving else "at rest"
    payload = f"payload {model.payload.mass:g} kg" if model.payload is not None else "no payload"
    extra = ", external wrench at the platform origin" if wrench else ""
    where = " (on the tool; the pose, motion and wrench are the tool's)" if model.wrist is not None else ""
    say(f"loads {model.name}: {payload}{where}, {said}{extra}; gravity {', '.join(f'{g:g}' for g in model.gravity)} m/s^2")
    if model.wrist is not None:
        say("the platform's pose: " + " ".join(f"{v:.6f}" for v in at))
    elif np.max(np.abs(at - asked)) > 1e-9:
        say("the machine's pose for these task coordinates: " + " ".join(f"{v:.6f}" for v in at))
    from ..kinematics.loads import SIDES
    from ..kinematics.platform_loads import all_free

    for entry in postures:
        say(f"posture {entry['posture']} ({entry['warning']})")
        rows = [("joint", "load", "limit", "base joint (deg)", "platform joint (deg)")]
        for index, name in enumerate(model.joint_names):
            limit = entry["limits"][index]
            limb = model.limbs[index] if index < model.dof else None  # a wrist joint has no passive joints
            rows.append((name, f"{entry['forces'][index] + 0.0:.6g} {entry['units'][index]}",
                         f"{limit:g} {entry['units'][index]}" if limit is not None else "-",
                         *(_angle_text(entry["joint_angles"][side][index], limb.cone(side)) if limb else "-"
                           for side in SIDES)))
        print_table(rows)
        force, moment = entry["constraint"]["force"], entry["constraint"]["moment"]
        if all_free(model.parallel):
            say("  constraints: none (six actuated directions)")
        else:
            scale = ROUNDING * (1.0 + max(abs(value) for value in entry["forces"]))
            say(f"  constraints carry {_rounded(np.linalg.norm(force), scale):.6g} N and "
                f"{_rounded(np.linalg.norm(moment), scale):.6g} N m (about the platform origin)")
        if entry["deflection"] is not None:
            move = entry["deflection"]
            say(f"  deflection: {np.linalg.norm(move[:3]) * 1000:.4g} um ({', '.join(f'{v * 1000:.4g}' for v in move[:3])}), "
                f"{np.linalg.norm(move[3:]):.4g} deg")
        else:
            say("  deflection: not computed (a limb has no stiffness)")


ROUNDING = 1e-9
"""A constraint force or moment below this fraction of the largest actuator load (plus 1) is rounding: shown as 0."""


def _rounded(value, scale):
    return 0.0 if value <= scale else value


def _angle_text(angle, cone):
    return f"{angle + 0.0:.4f}" + (f" / {cone:g}" if cone is not None else "")
