"""What every limb model is: its schema, its numpy solver, its C partial and its words.

A limb model is one class (a pydantic schema) in one module of :mod:`kingen.robot.limbs`, plus
one template partial ``templates/limbs/<model>.c.j2``. Everything else in kingen iterates
over the registry and asks the class; nothing names a model but the registry and the layouts.
docs/explanation/conventions.md has the equations; docs/developer/extending.md the checklist.
"""

import math
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar, Optional

import numpy as np
from pydantic import field_validator, model_validator

from ...conventions import PRISMATIC, JointType
from ...runtime.resources import templates_dir
from ..loads_schema import ForceLimit, JointLimits, LimbParts, refuse_wrong_limit
from ..schema import CalibrationField, Identifier, PositiveRate, Strict, Travel, UnitVec3, Vec3


@dataclass(frozen=True)
class LimbSolution:
    """One limb over n poses: ``values`` (n, 2), the joint of branch 0 and branch 1 (the
    same twice for one-branch models), mm or rad; ``radicand`` (n,) the normalised radicand D
    whose sign decides reachability (None for models that are always reachable)."""

    values: np.ndarray
    radicand: Optional[np.ndarray] = None


def components_last(components):
    """(..., 3) from three (...) arrays: a view of memory with the components first, so that
    numpy's loops over the result (and over what is computed from it) run along the poses."""
    return np.moveaxis(np.stack(components), 0, -1)


def c_double(value):
    """A C double literal that reads back as exactly ``value``."""
    text = repr(float(value))
    if not math.isfinite(float(value)):
        raise ValueError(f"cannot write {text} as a C constant")
    return text if ("." in text or "e" in text) else text + ".0"


def c_vector(values):
    """Three numbers as the inside of a C initializer: '1.0, 2.5, -3.0'."""
    return ", ".join(c_double(value) for value in values)


class LimbModel(Strict):
    """The fields every limb has, and what a model class must declare.

    Subclasses declare ``model: Literal["<name>"]`` (the YAML tag) and their geometry
    fields, and set the class variables below; they implement :meth:`solve`,
    :meth:`c_row` and :meth:`explain_offset`.
    """

    name: Optional[Identifier] = None
    platform_point: Vec3
    """Where the limb's passive link meets the platform (mm, platform frame): every model has one."""
    travel: Optional[Travel] = None
    """[lower, upper] in mm (prismatic) or degrees (revolute); absent: no limits."""
    max_speed: Optional[PositiveRate] = None
    """The joint's drive's top speed, mm/s (prismatic) or degrees/s (revolute); absent: not limited
    (``kingen check-path`` judges the speeds a program needs against it)."""
    max_acceleration: Optional[PositiveRate] = None
    """The joint's drive's top acceleration, mm/s^2 or degrees/s^2; absent: not limited."""
    max_force: Optional[ForceLimit] = None
    """N: a prismatic actuator's largest force either way; absent: not limited (``kingen loads``)."""
    max_torque: Optional[ForceLimit] = None
    """N m: a revolute actuator's largest torque either way; absent: not limited."""
    max_power: Optional[ForceLimit] = None
    """W: the actuator's largest power (load times joint speed) either way; absent: not limited
    (``kingen check-path`` judges the power a program needs against it)."""
    stiffness: Optional[ForceLimit] = None
    """The actuator's stiffness along its joint: N/mm (prismatic) or N m/rad (revolute); absent: rigid
    is not assumed, and no deflection is computed."""
    joint_limits: Optional[JointLimits] = None
    """The passive joints' largest angles (degrees) between the passive link and each joint's neutral axis."""
    base_axis: Optional[UnitVec3] = None
    """The base-side passive joint's neutral axis (base frame); absent: the link's direction at the
    verification home in the working posture."""
    platform_axis: Optional[UnitVec3] = None
    """The platform joint's neutral axis (platform frame); absent: the link's direction at the
    verification home in the working posture."""
    parts: Optional[LimbParts] = None
    """The limb's moving masses (its actuator's part and its passive link), point masses; absent:
    massless (``kingen loads``)."""
    calibrate: dict[str, CalibrationField] = {}
    """Parameter -> calibration field read at run time; a zero field keeps the built-in value."""

    joint_type: ClassVar[JointType] = PRISMATIC
    branches: ClassVar[int] = 1
    has_radicand: ClassVar[bool] = False
    """Whether :meth:`solve` gives a normalised radicand (and the limb can be unreachable or
    singular); the C partial then classifies it with kingen_classify."""
    calibratable: ClassVar[dict] = {}
    """Parameter -> the unit its calibration field is read in ('mm' or 'degrees')."""
    closed_form_forward: ClassVar[bool] = False
    """Whether a translating platform on three limbs of this model has its forward in closed form in
    the generated C (the C library's and LinuxCNC's): the partial's "sphere" part then sets
    ``centre[limb][k]`` (k = 0..2) and ``radius[limb]``, the sphere the platform origin lies on, from
    its ``row`` and ``measured[row->joint]`` (every row's ``platform_point`` already turned by the
    platform's rotation), with ``int k`` declared; False: Newton's method."""
    calibration_parameters: ClassVar[tuple] = ()
    """What ``kingen calibrate`` identifies on a limb of this model: (field, group, kind) per field,
    ``kind`` 'vector' (its 3 components, mm), 'tilt' (a unit direction's two tilts across itself,
    degrees, 0 nominal), 'mm' or 'deg' (the number itself); ``group`` one of
    kingen.calibrate.parameters.GROUPS. Empty: calibrate refuses a robot with limbs of this model."""
    revolute_axis_turns_about: ClassVar[Optional[str]] = None
    """The field (a unit direction) a constraining ``revolute_axis`` stays perpendicular to (a rail's
    direction): calibration turns the axis about it, one parameter; None: two tilts across the axis."""
    length_fields: ClassVar[tuple] = ()
    """Fields in mm (numbers or 3-vectors): the robot's size is the largest of them."""
    c_columns: ClassVar[str] = ""
    """The table columns of the C partial, in order, in words (shown above the table)."""
    partial: ClassVar[Optional[Path]] = None
    """The template partial; None: ``templates/limbs/<model>.c.j2``."""
    joint_words: ClassVar[str] = ""
    """What the joint's value measures, in words, for the setup sheet's joints table: its zero
    and the direction of positive values."""

    @model_validator(mode="after")
    def _check_actuator_limit(self):
        refuse_wrong_limit(self.joint_type, self.max_force, self.max_torque)
        return self

    @property
    def actuator_limit(self):
        """The actuator's load limit: max_torque (N m) for a revolute joint, max_force (N) for a
        prismatic one; None where the file gives none."""
        return self.max_torque if self.joint_type.wraps else self.max_force

    def cone(self, side):
        """The passive joint's limit on ``side`` ('base' or 'platform'), degrees, or None."""
        return None if self.joint_limits is None else getattr(self.joint_limits, side)

    @field_validator("calibrate")
    @classmethod
    def _check_calibratable(cls, calibrate):
        for parameter in calibrate:
            if parameter not in cls.calibratable:
                raise ValueError(f"'{parameter}' cannot be calibrated on a {model_name(cls)} "
                                 f"(choose from {', '.join(cls.calibratable) or 'nothing'})")
        return calibrate

    def solve(self, platform_point):
        """The joint of both branches for platform points ``platform_point`` (n, 3) in the
        base frame, mm: a :class:`LimbSolution`."""
        raise NotImplementedError

    def base_side_point(self, platform_point, joint):
        """Where the passive link starts on the base side (n, 3), mm, base frame, for joint
        values ``joint`` (n,) (mm or rad, as reported) and platform points (n, 3): the force
        line of the limb runs from here through the platform point."""
        raise NotImplementedError

    def passive_length(self, joint):
        """The passive link's length (mm) at joint values ``joint`` (n,)."""
        raise NotImplementedError

    def base_joint(self):
        """Where the limb's actuated joint sits on the base (3,), mm, base frame, for the setup
        sheet's frames: by default the base side of the passive link at joint 0 (for a
        platform point at the base origin)."""
        return self.base_side_point(np.zeros((1, 3)), np.zeros(1))[0]

    def joint_axis(self):
        """The unit axis (3,) the joint moves along (prismatic) or turns about (revolute,
        right-handed, positive joint values), base frame; None: no fixed axis (a leg)."""
        return None

    def branch_labels(self, platform_point, centre):
        """For two-branch models: (branch 0, branch 1) in machine words for the setup sheet,
        true for the platform point ``platform_point`` (3,), mm, base frame; ``centre`` (3,) is
        the centre of the base joints. One-branch models: ()."""
        return ()

    def base_side_velocity(self, joint):
        """d(base-side point)/d(joint) (n, 3), base frame: mm per mm, or mm per rad."""
        return np.zeros(np.shape(joint) + (3,))

    def base_side_acceleration(self, joint):
        """d^2(base-side point)/d(joint)^2 (n, 3), base frame: mm per mm^2, or mm per rad^2."""
        return np.zeros(np.shape(joint) + (3,))

    def actuator_part_gain(self, distance):
        """How the centre of the actuator's moving part, ``distance`` mm from the actuator's joint
        (LimbParts.actuator), moves: as the base-side point times this factor (a carriage: 1), or
        None: it turns with the passive link about the base-side point (a leg's cylinder)."""
        return 1.0

    link_length_rate: ClassVar[float] = 0.0
    """d(link length)/d(joint): 1 for a prismatic leg whose joint is its length, else 0."""

    passive_radius: ClassVar[str] = "rod_radius"
    """Which ``collision`` radius the passive link is modelled with."""

    def actuator_segment(self, joint):
        """(start, end) (n, 3) of a moving actuator arm to keep clear of others, or None."""
        return None

    def closure_residual(self, platform_point, joint):
        """How far the passive link is from its length (mm) when the joint is at ``joint`` (n,)
        and the platform point at ``platform_point`` (n, 3), base frame: the geometry put back
        together forward, independent of :meth:`solve`'s formula."""
        return np.linalg.norm(platform_point - self.base_side_point(platform_point, joint), axis=-1) \
            - self.passive_length(joint)

    def force_direction(self, platform_point, joint):
        """The unit direction f (n, 3) of the force the limb transmits to the platform: along
        its passive link, from the base side to the platform point (docs/explanation/conventions.md,
        'Force lines and the direct index')."""
        line = platform_point - self.base_side_point(platform_point, joint)
        return line / np.linalg.norm(line, axis=-1, keepdims=True)

    def transmission(self, direction, joint):
        """f . dP/dq + dl/dq (n,): a platform point velocity v moves the joint at
        (f . v) / transmission. Zero at the limb's own (inverse) singularity."""
        return np.sum(direction * self.base_side_velocity(joint), axis=-1) + self.link_length_rate

    def constraint_plane(self):
        """(axis a (3,), point c (3,)), base frame, mm: the plane a.(x - c) = 0 a revolute joint
        whose axis is fixed in the base keeps the platform point in (kingen.robot.constraints),
        or None: the limb does not constrain the platform."""
        return None

    def platform_constraint(self):
        """(axis e (3,) unit, platform frame; base point b (3,), base frame, mm; platform point n
        (3,), platform frame, mm): a revolute joint at the platform point whose axis is fixed in
        the platform keeps (R e).(b - p) = e.n (kingen.robot.constraints), or None."""
        return None

    def c_row(self):
        """This limb's table row for the partial: {column: C text} (numbers via c_double)."""
        raise NotImplementedError

    def tilt_judge_row(self):
        """This limb's geometry as the design optimiser's compiled judge reads it
        (kingen.design.tilt_judge: {member of its design struct: number or 3 numbers}, mm, base
        frame, the platform point in the platform frame), or None: the judge does not decide a
        robot with limbs of this model, the numpy analysis does."""
        return None

    def singular_scale(self):
        """The scale of the joint's ill-conditioning in its singular band (mm or rad per
        unit of 1/sqrt(D)): verify's conditioning bound is relative to it."""
        return 1.0

    def explain_offset(self, offset):
        """Why a routine's joint could be off by a constant ``offset`` (mm or rad): the
        likely wrong parameter, in words, for diagnoses."""
        raise NotImplementedError

    def calibration_scale(self, parameter):
        """Factor from the unit of ``parameter``'s calibration field to the routine's unit."""
        return math.pi / 180.0 if self.calibratable[parameter] == "degrees" else 1.0


def axis_words(vector):
    """A direction in words: '+X', '-Z', ... within 0.1 degree of an axis, else its unit
    components, '(0.6, 0, -0.8)'."""
    unit = np.asarray(vector, dtype=float) / np.linalg.norm(vector)
    axis = int(np.argmax(np.abs(unit)))
    if abs(unit[axis]) >= math.cos(math.radians(0.1)):
        return f"{'+' if unit[axis] > 0 else '-'}{'XYZ'[axis]}"
    return "(" + ", ".join(f"{value + 0.0:.4g}" for value in unit) + ")"


def model_name(cls):
    """The YAML tag of a limb model class (its ``model`` literal)."""
    return cls.model_fields["model"].annotation.__args__[0]


def partial_path(cls):
    """The template partial of a limb model class."""
    return cls.partial or templates_dir() / "limbs" / f"{model_name(cls)}.c.j2"


class TwoBranchModel(LimbModel):
    """A model with two branches (one binary digit of the posture number) and a normalised
    radicand: it can be unreachable or singular."""

    branches: ClassVar[int] = 2
    has_radicand: ClassVar[bool] = True
