"""The calibration's parameter vector: every limb's geometry, the measuring frame and the target.

Values are in mm and degrees (a robot file in inches is read in mm, as kingen holds every robot). Per
limb, what its model's ``calibration_parameters`` lists (kingen.robot.limbs): a leg's base point (3),
platform point (3) and reference length; a rail's rail point (3), its direction's tilt about two axes
across it (2, degrees, 0 nominal), platform point (3), link length and origin; a crank's pivot (3),
crank direction, crank and rod lengths, zero offset and platform point (3).

A machine with task coordinates adds its constraints' geometry (kingen.calibrate.constraints):
the revolute axes' turns and a passive leg's base point and axes. A machine with a serial wrist
adds its parallel part's and the wrist's (kingen.calibrate.wrist: each joint's zero offset and
axis, the tool's reach); its target is on the tool.

The measuring frame is the measuring device's frame in the base frame (x, y, z, roll, pitch,
yaw); the target is the measured frame in the platform frame (a pose, ``--measure pose``) or
the reflector's point (``--measure position``). A measured pose M (device frame) is then
F M = T Tg: the platform's pose T = F M Tg^-1.

The solver works on x, the deviation from nominal in mm-equivalents: an angle moves by
x / (robot size) radians, so that one unit of x moves the machine by about a millimetre
whatever the parameter (the parameters' scaling).
"""

import math
from dataclasses import dataclass, replace

import numpy as np

from ..conventions import matrix_from_pose
from ..errors import KingenError
from ..robot.limbs import MODELS
from . import constraints, wrist
from .constraints import AXIS_GROUP

GROUPS = dict(
    base="the limbs' base points (leg base points, rail points, crank pivots)", platform="the limbs' platform points",
    length="leg reference lengths, rail link lengths, crank and rod lengths, a tool's reach",
    direction="rail directions and crank directions", zero="crank zero offsets, rail origins, wrist joints' zero offsets",
    frame="the measuring frame (the device's pose in the base frame)",
    target="the target (the measured frame or reflector on the platform; on the tool with a wrist)",
    **dict([AXIS_GROUP]))
"""The groups --identify selects, in words."""

POSE_NAMES = ("x", "y", "z", "roll", "pitch", "yaw")


@dataclass(frozen=True)
class Parameter:
    """One identified number: ``name`` ('leg1.base_point.z', 'measuring_frame.yaw'), its
    ``group``, ``unit`` ('mm' or 'deg') and ``nominal`` value; where it lives (``limb`` index
    or None: the passive leg's, or the measuring frame's and target's (``field`` None); ``field``,
    ``component``: 0..2 of a vector, 'a'/'b' a direction's tilt, 'turn' a rail's revolute axis's
    turn (kingen.calibrate.constraints), or None); ``wrist`` a wrist joint's index or 'tool'
    for the wrist's (kingen.calibrate.wrist), else None."""

    name: str
    group: str
    unit: str
    nominal: float
    limb: int = None
    field: str = None
    component: object = None
    wrist: object = None


class Parameters:
    """The parameter vector of ``robot`` (a Robot, limbs expanded, mm) for measurements of
    kind ``measure`` ('pose' or 'position'), with the measuring frame's nominal pose ``frame``
    (6,) and the target's ``target`` (6,) or (3,) (mm, degrees)."""

    def __init__(self, robot, measure, frame=(0.0,) * 6, target=None):
        self.robot, self.measure = robot, measure
        self.lever = robot.size_mm
        entries = []
        for index, limb in enumerate(robot.limbs):
            fields = type(limb).calibration_parameters
            if not fields:
                known = (name for name, model in MODELS.items() if model.calibration_parameters)
                raise KingenError(f"{robot.path}: limbs: calibrate does not know the parameters of the "
                                  f"'{limb.model}' limb model (it knows {', '.join(known)})")
            name = robot.joint_names[index]
            for field, group, kind in fields:
                entries.extend(_limb_entries(name, index, limb, field, group, kind))
        entries += [Parameter(*spec) for spec in constraints.entries(robot.parallel)]
        entries += [Parameter(*spec, wrist=place[0], field=place[1], component=place[2])
                    for spec, place in wrist.entries(robot)]
        target = (0.0,) * (6 if measure == "pose" else 3) if target is None else target
        entries += [Parameter(f"measuring_frame.{axis}", "frame", "mm" if i < 3 else "deg", float(frame[i]))
                    for i, axis in enumerate(POSE_NAMES)]
        entries += [Parameter(f"target.{axis}", "target", "mm" if i < 3 else "deg", float(target[i]))
                    for i, axis in enumerate(POSE_NAMES[:len(target)])]
        self.entries = tuple(entries)
        self.names = [entry.name for entry in entries]
        self.nominal = np.array([entry.nominal for entry in entries])
        self.step = np.array([1.0 if entry.unit == "mm" else math.degrees(1.0 / self.lever) for entry in entries])
        """Value per unit of x: 1 for mm, the degrees one mm-equivalent turns for angles."""
        self.groups = np.array([entry.group for entry in entries])
        self._partners = constraints.partners(robot.parallel)

    def __len__(self):
        return len(self.entries)

    def values(self, x):
        """Values (mm, degrees) of the deviations ``x`` (mm-equivalents) from nominal."""
        return self.nominal + np.asarray(x, dtype=float) * self.step

    def deviations(self, values):
        """The x of ``values``: values() inverted."""
        return (np.asarray(values, dtype=float) - self.nominal) / self.step

    def robot_of(self, values):
        """The Robot with the limb, constraint and wrist parameters ``values`` (mm, degrees) put in."""
        parallel = self._parallel_of(values)
        if self.robot.wrist is None:
            return parallel
        placed = [((entry.wrist, entry.field, entry.component), value)
                  for entry, value in zip(self.entries, values) if entry.wrist is not None]
        return replace(self.robot, limbs=parallel.limbs, passive_leg=parallel.passive_leg, parallel_part=parallel,
                       wrist=wrist.calibrated_wrist(self.robot.wrist, placed))

    def _parallel_of(self, values):
        """The parallel part (the robot itself without a wrist) with its parameters ``values`` put in."""
        base = self.robot.parallel
        updates = [{} for _ in base.limbs]
        turns, passive = {}, {}
        for entry, value in zip(self.entries, values):
            if entry.field is None or entry.wrist is not None:
                continue
            if isinstance(entry.component, str):
                turns.setdefault((entry.limb, entry.field), {})[entry.component] = math.radians(value)
            elif entry.limb is None:
                passive.setdefault(entry.field, list(getattr(base.passive_leg, entry.field)))[
                    entry.component] = float(value)
            elif entry.component is None:
                updates[entry.limb][entry.field] = float(value)
            else:
                limb = base.limbs[entry.limb]
                updates[entry.limb].setdefault(entry.field, list(getattr(limb, entry.field)))[entry.component] = \
                    float(value)
        limbs = []
        for index, (limb, update) in enumerate(zip(base.limbs, updates)):
            for field, _, kind in type(limb).calibration_parameters:
                if kind == "tilt":
                    update[field] = [float(v) for v in constraints.tilted(getattr(limb, field),
                                                                          turns.get((index, field), {}))]
            about = type(limb).revolute_axis_turns_about
            direction = None if about is None else update.get(about, getattr(limb, about))
            for field in ("revolute_axis", "platform_revolute_axis"):
                owner = self._partners.get(index, index)
                if getattr(limb, field, None) is not None:
                    update[field] = [float(v) for v in constraints.limb_axis(limb, field, turns.get((owner, field), {}),
                                                                               direction)]
            limbs.append(limb.model_copy(update=update))
        robot = replace(base, limbs=tuple(limbs))
        if base.passive_leg is None:
            return robot
        leg = base.passive_leg
        angles = {field: angles for (limb, field), angles in turns.items() if limb is None}
        return replace(robot, passive_leg=constraints.passive_leg_of(leg, passive.get("base_point", leg.base_point),
                                                                     angles))

    def frame(self, values):
        """The measuring frame's homogeneous matrix (4, 4) in the base frame."""
        return matrix_from_pose(self._slice(values, "frame"))

    def target(self, values):
        """The target: its matrix (4, 4) in the platform frame (the tool frame with a wrist) (pose),
        or its point (3,) (position)."""
        target = self._slice(values, "target")
        return matrix_from_pose(target) if self.measure == "pose" else target

    def _slice(self, values, group):
        return np.asarray(values, dtype=float)[self.groups == group]

    def selected(self, spec):
        """(len,) bool: the parameters --identify ``spec`` selects: comma-separated 'all', a group
        or '-group' (fix it); a spec that starts with '-group' starts from all."""
        items = [item.strip() for item in spec.split(",") if item.strip()]
        if not items:
            raise KingenError("--identify: empty; give 'all', groups or -groups")
        chosen = np.ones(len(self), dtype=bool) if items[0].startswith("-") else np.zeros(len(self), dtype=bool)
        for item in items:
            group = item.lstrip("-")
            if group != "all" and group not in GROUPS:
                raise KingenError(f"--identify: unknown group '{group}' (choose from all, {', '.join(GROUPS)})")
            chosen[np.ones(len(self), dtype=bool) if group == "all" else self.groups == group] = \
                not item.startswith("-")
        if not chosen.any():
            raise KingenError(f"--identify: '{spec}' selects none of {self.robot.name}'s parameters (its groups: "
                              f"{', '.join(dict.fromkeys(self.groups))})")
        return chosen


def _limb_entries(name, index, limb, field, group, kind):
    """The Parameters of one limb field of ``kind``: 'vector' (3 components, mm), 'tilt' (a unit
    direction's two tilts, degrees, 0 nominal), 'mm' or 'deg' (one number)
    (kingen.robot.limbs.LimbModel.calibration_parameters)."""
    if kind == "vector":
        return [Parameter(f"{name}.{field}.{axis}", group, "mm", float(getattr(limb, field)[axis_index]),
                          index, field, axis_index) for axis_index, axis in enumerate("xyz")]
    if kind == "tilt":
        return [Parameter(f"{name}.{field}.tilt_{part}", group, "deg", 0.0, index, field, part) for part in "ab"]
    return [Parameter(f"{name}.{field}", group, kind, float(getattr(limb, field)), index, field)]
