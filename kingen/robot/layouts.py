"""Layouts: generators of limbs for parametric robots (``layout:`` in a robot file).

Each layout takes its parameters (mm, degrees) and returns the limbs of one model (six, or
three for the deltas, whose parameters are named as LinuxCNC's pins name them),
sharing travel limits and giving each limb its own calibration fields.
docs/explanation/conventions.md states the formulas.
"""

import math
from typing import Annotated, ClassVar, Literal, Optional, Union

from pydantic import Field, field_validator, model_validator

from .limbs import Crank, Leg, Rail, model_name
from .loads_schema import ForceLimit, JointLimits, LimbParts, refuse_wrong_limit
from .schema import MAX_MM, Coordinate, CalibrationField, Length, ReferenceLength, SixAngles, Strict, Travel

class _Layout(Strict):
    """A generator of six limbs of one model; ``calibrate`` maps a parameter to six fields."""

    travel: Optional[Travel] = None
    calibrate: dict[str, Annotated[list[CalibrationField], Field(min_length=6, max_length=6)]] = {}
    max_force: Optional[ForceLimit] = Field(None, description="N: every limb's actuator force limit (prismatic).")
    max_torque: Optional[ForceLimit] = Field(None, description="N m: every limb's actuator torque limit (revolute).")
    max_power: Optional[ForceLimit] = Field(None, description="W: every limb's actuator power limit.")
    stiffness: Optional[ForceLimit] = Field(None, description="Every limb's actuator stiffness: N/mm or N m/rad.")
    joint_limits: Optional[JointLimits] = Field(None, description="Every limb's passive joints' limits (degrees).")
    parts: Optional[LimbParts] = Field(None, description="Every limb's moving masses (kg, centres in the file's unit).")
    limb_class: ClassVar[type] = None

    @field_validator("calibrate")
    @classmethod
    def _check_calibratable(cls, calibrate):
        for parameter in calibrate:
            if parameter not in cls.limb_class.calibratable:
                raise ValueError(f"'{parameter}' cannot be calibrated "
                                 f"(choose from {', '.join(cls.limb_class.calibratable)})")
        return calibrate

    @model_validator(mode="after")
    def _limbs_take_their_limit(self):
        """Every limb of the layout takes the same limit: max_force (prismatic) or max_torque (revolute)."""
        refuse_wrong_limit(self.limb_class.joint_type, self.max_force, self.max_torque)
        return self

    def _shared(self, index):
        """The keys every generated limb takes from the layout: travel, its calibration fields and
        the load fields given."""
        loads = {name: getattr(self, name) for name in ("max_force", "max_torque", "max_power", "stiffness", "joint_limits", "parts")
                 if getattr(self, name) is not None}
        return {"travel": self.travel, **loads,
                "calibrate": {parameter: fields[index] for parameter, fields in self.calibrate.items()}}


class StewartGoughLayout(_Layout):
    """Six legs on the controller thesis's parametric layout (points at z = heights)."""

    type: Literal["stewart_gough"]
    base_radius: Length
    platform_radius: Length
    base_pair_angle: Annotated[float, Field(gt=0, lt=120)]
    platform_pair_angle: Annotated[float, Field(gt=0, lt=120)]
    base_height: Coordinate = 0.0
    platform_height: Coordinate = 0.0
    reference_length: ReferenceLength
    limb_class: ClassVar[type] = Leg

    def limbs(self):
        """The six legs; point angles lambda_1 = 60 - pair/2, lambda_2 = lambda_1 + pair, ... (degrees)."""
        legs = []
        for index in range(6):
            pair, second = divmod(index, 2)
            centre = 60.0 + 120.0 * pair
            base_angle = math.radians(centre + (second - 0.5) * self.base_pair_angle)
            platform_angle = math.radians(centre + (second - 0.5) * self.platform_pair_angle)
            legs.append(Leg(
                model=model_name(Leg),
                name=f"leg{index + 1}",
                base_point=[self.base_radius * math.cos(base_angle),
                            self.base_radius * math.sin(base_angle), self.base_height],
                platform_point=[self.platform_radius * math.cos(platform_angle),
                                self.platform_radius * math.sin(platform_angle), self.platform_height],
                reference_length=self.reference_length,
                **self._shared(index),
            ))
        return legs


class Rus6Layout(_Layout):
    """Six cranks on the 6-RUS flight-simulator layout (docs/explanation/conventions.md, '6-RUS layout')."""

    type: Literal["rus6"]
    base_radius: Length
    platform_radius: Length
    base_half_distance: Annotated[float, Field(ge=0, le=MAX_MM)]
    platform_half_distance: Annotated[float, Field(ge=0, le=MAX_MM)]
    crank_length: Length
    rod_length: Length
    pair_angles: SixAngles
    crank_directions: SixAngles
    limb_class: ClassVar[type] = Crank

    def limbs(self):
        """The six cranks: A_i and c_i from chi_i with m, n = (-1)^(i-1) times the half-distances."""
        cranks = []
        for index, (chi_deg, beta) in enumerate(zip(self.pair_angles, self.crank_directions)):
            chi = math.radians(chi_deg)
            sign = 1.0 if index % 2 == 0 else -1.0
            m, n = sign * self.base_half_distance, sign * self.platform_half_distance
            cranks.append(Crank(
                model=model_name(Crank),
                name=f"crank{index + 1}",
                pivot=[self.base_radius * math.cos(chi) - m * math.sin(chi),
                       self.base_radius * math.sin(chi) + m * math.cos(chi), 0.0],
                crank_direction=beta,
                crank_length=self.crank_length,
                rod_length=self.rod_length,
                platform_point=[self.platform_radius * math.cos(chi) - n * math.sin(chi),
                                self.platform_radius * math.sin(chi) + n * math.cos(chi), 0.0],
                **self._shared(index),
            ))
        return cranks


class _DeltaLayout(_Layout):
    """Three limbs 120 degrees apart, named and placed as LinuxCNC's delta modules do."""

    calibrate: dict[str, Annotated[list[CalibrationField], Field(min_length=3, max_length=3)]] = {}


class LinearDeltaLayout(_DeltaLayout):
    """A linear (Rostock-style) delta as LinuxCNC's lineardeltakins: towers 0, 1, 2 at 90, 210
    and 330 degrees, at distance R from the axis, carriages moving up +z; a rod of length L
    joins each carriage to the effector's controlled point (the effector and carriage offsets
    are taken off R, as lineardeltakins' R). The joint is the carriage's height; the
    carriage above the effector is branch 1 (docs/explanation/conventions.md, 'Linear delta')."""

    type: Literal["linear_delta"]
    R: Length
    """lineardeltakins.R (mm): horizontal distance from the axis to a tower's rod joint, less the effector offset."""
    L: Length
    """lineardeltakins.L (mm): the diagonal rod's length."""
    limb_class: ClassVar[type] = Rail

    def limbs(self):
        """The three rails, their points computed as lineardeltakins computes them."""
        sin_60, cos_60 = math.sqrt(3) / 2, 0.5
        towers = [(0.0, self.R), (-sin_60 * self.R, -cos_60 * self.R), (sin_60 * self.R, -cos_60 * self.R)]
        return [Rail(model=model_name(Rail), name=f"tower{index}", rail_point=[x, y, 0.0], direction=[0.0, 0.0, 1.0],
                     carriage_offset=[0.0, 0.0, 0.0], platform_point=[0.0, 0.0, 0.0], link_length=self.L,
                     **self._shared(index))
                for index, (x, y) in enumerate(towers)]


class RotaryDeltaLayout(_DeltaLayout):
    """A rotary (Clavel) delta as LinuxCNC's rotarydeltakins: hips in the plane z = 0 at
    distance platformradius, thighs of thighlength pointing out at -90, 30 and 150 degrees for
    joints 0, 1 and 2, shins of shinlength to the foot's joints at footradius from the
    controlled point. Joints in degrees, 0 with the thigh horizontal, positive moving the knee
    down (docs/explanation/conventions.md, 'Rotary delta')."""

    type: Literal["rotary_delta"]
    platformradius: Length
    thighlength: Length
    shinlength: Length
    footradius: Annotated[float, Field(ge=0, le=MAX_MM)]
    limb_class: ClassVar[type] = Crank
    HIP_ANGLES: ClassVar[tuple] = (-90.0, 30.0, 150.0)

    def limbs(self):
        cranks = []
        for index, angle in enumerate(self.HIP_ANGLES):
            c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
            cranks.append(Crank(model=model_name(Crank), name=f"hip{index}",
                                pivot=[self.platformradius * c, self.platformradius * s, 0.0], crank_direction=angle,
                                crank_length=self.thighlength, rod_length=self.shinlength,
                                platform_point=[self.footradius * c, self.footradius * s, 0.0],
                                **self._shared(index)))
        return cranks


LAYOUTS = (StewartGoughLayout, Rus6Layout, LinearDeltaLayout, RotaryDeltaLayout)
Layout = Annotated[Union[LAYOUTS], Field(discriminator="type")]
