"""The ``optimize:`` section of a robot file (:mod:`kingen.design.problem` turns it into a design
problem). Defaults are the 6-RUS thesis's (``../shared/optimisation.md``); lengths mm,
angles degrees."""

from typing import Annotated, Literal, Optional

import numpy as np
from pydantic import Field, model_validator

from ..defaults import AZIMUTH_STEP_DEG, MAX_MM, TILT_MAX_DEG, TILT_STEP_DEG
from .schema import MAX_DEGREES, Coordinate, Strict


class Variable(Strict):
    """One design variable (or one per entry of a list field)."""

    field: Annotated[str, Field(min_length=1)]
    """``layout.<field>``, ``depth`` or ``height``."""
    bounds: Annotated[list[Coordinate], Field(min_length=2, max_length=2)]
    """mm or degrees, within the geometry range (kingen.design.problem.Problem holds an angle's to +/-MAX_DEGREES)."""

    @model_validator(mode="after")
    def _ordered(self):
        if not self.bounds[0] < self.bounds[1]:
            raise ValueError(f"lower bound {self.bounds[0]} must be below upper bound {self.bounds[1]}")
        return self


def _within(bounds):
    """A float field within (least, most), both included: the bounds analyze's options have too."""
    return Annotated[float, Field(ge=bounds[0], le=bounds[1])]


class Objective(Strict):
    """What a design is judged by (analyze's settings and their bounds, the thesis's by
    default). ``posture`` is checked against the robot's postures when the file is read
    (kingen.robot.model)."""

    posture: Optional[Annotated[int, Field(ge=0)]] = None
    tilt_convention: Literal["axis", "euler"] = "euler"
    tilt_step: _within(TILT_STEP_DEG) = 1.0
    azimuth_step: _within(AZIMUTH_STEP_DEG) = 1.0
    tilt_max: _within(TILT_MAX_DEG) = 120.0
    collision: Literal["segments", "thesis"] = "thesis"


MIN_STEP = 1e-6
"""The refinement's difference steps at least (mm or degrees): a difference of objectives over
a smaller one (down to 5e-324) could overflow the gradient to infinity."""
MAX_COEFFICIENT = 100.0
"""c1 and c2 at most: phi = c1 + c2 and phi^2 stay far from overflow, so the constriction
factor K and the swarm's coefficients K, K c1, K c2 are finite and positive (beyond about
1e154, phi^2 overflows and K is 0 or NaN: a frozen swarm or NaN velocities)."""


class Search(Strict):
    """The particle swarm (constriction form: v <- K [v + c1 r1 (p - x) + c2 r2 (g - x)])."""

    swarm: Annotated[int, Field(ge=2, le=1000)] = 30
    iterations: Annotated[int, Field(ge=1, le=100000)] = 3000
    c1: Annotated[float, Field(gt=0, le=MAX_COEFFICIENT)] = 2.8
    """The pull towards each particle's own best."""
    c2: Annotated[float, Field(gt=0, le=MAX_COEFFICIENT)] = 1.3
    """The pull towards the swarm's best."""
    patience: Annotated[int, Field(ge=1)] = 300
    """Stop when the best objective has not improved for this many iterations."""

    @property
    def constriction(self):
        """K = 2 / |2 - phi - sqrt(phi^2 - 4 phi)|, phi = c1 + c2 (> 4)."""
        phi = self.c1 + self.c2
        return 2.0 / abs(2.0 - phi - np.sqrt(phi * phi - 4.0 * phi))

    @model_validator(mode="after")
    def _constricted(self):
        if self.c1 + self.c2 <= 4.0:
            raise ValueError(f"c1 + c2 must exceed 4 for the constriction factor (it is {self.c1 + self.c2:g})")
        return self


class Refine(Strict):
    """The interior-point refinement from the swarm's best (scipy's trust-constr), with
    central differences of these absolute steps."""

    method: Literal["trust-constr", "none"] = "trust-constr"
    angle_step: Annotated[float, Field(ge=MIN_STEP, le=MAX_DEGREES)] = 1.0
    """degrees"""
    length_step: Annotated[float, Field(ge=MIN_STEP, le=MAX_MM)] = 50.0
    """mm"""
    iterations: Annotated[int, Field(ge=1, le=10000)] = 20


class Optimize(Strict):
    """``optimize:`` in a robot file."""

    variables: Annotated[list[Variable], Field(min_length=1)]
    objective: Objective = Objective()
    search: Search = Search()
    refine: Refine = Refine()
