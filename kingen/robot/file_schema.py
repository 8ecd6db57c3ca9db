"""The robot file's schema: the fields a robot file may hold, validated by pydantic
(documented field by field in docs/how-to/robot-files.md). kingen.robot.model builds a Robot from
a validated file."""

import functools
from typing import Annotated, Literal, Optional, Union

from pydantic import AfterValidator, Field

from .design_schema import Optimize
from .layouts import Layout
from .loads_schema import Gravity, PayloadFile
from .limbs import MODELS
from .passive_leg import PassiveLegFile
from .schema import MAX_MM, Coordinate, Identifier, Length, Pose, Strict
from .wrist import WristJoint

MAX_GOLDEN = 1000
MAX_LIMBS = 64
MAX_TWO_BRANCH_LIMBS = 8
"""At most 2**8 = 256 postures: the solutions array is NUM_DOFS x NUM_SOLUTIONS doubles."""

NAME_CHECKS = {}
"""How each host judges the names it makes from a robot's name: host name -> function (robot
name -> why it cannot be used, or None). kingen.hosts fills it as hosts register, so that
reading a robot file asks every host without knowing any."""


def _check_c_names(name):
    """The robot's own name may be anything identifier-shaped ('int' gives kin_int); the names
    every registered host makes from it must not collide with what that host or C reserves."""
    problems = [problem for check in NAME_CHECKS.values() if (problem := check(name))]
    if problems:
        raise ValueError("; ".join(problems))
    return name


def _check_non_negative(values):
    if any(value < 0 for value in values):
        raise ValueError("ranges must not be negative")
    return values


class Region(Strict):
    """Verification region: poses drawn uniformly in home +/- range (mm, degrees)."""

    home: Pose
    range: Annotated[Pose, AfterValidator(_check_non_negative)]


class Golden(Strict):
    """A published (or independently derived) pose -> joints pair, with its source."""

    source: Annotated[str, Field(min_length=1)]
    pose: Pose
    posture: Annotated[int, Field(ge=0)] = 0
    joints: Annotated[list[Coordinate], Field(max_length=MAX_LIMBS)]
    """mm for prismatic joints, degrees for revolute joints."""
    tolerance: Annotated[float, Field(gt=0, le=MAX_MM)]
    """In the units of ``joints``: half a unit of the last published digit is typical."""


class Singularity(Strict):
    """``singularity:`` in a robot file: when to call a pose a direct singularity."""

    direct_index_min: Length
    """mm: postures whose direct index is at most this answer WARN_SINGULAR_SOLUTION."""


class Forward(Strict):
    """``forward:`` in a robot file: which pose coordinates forward kinematics solves for."""

    free: Annotated[list[Literal["x", "y", "z", "roll", "pitch", "yaw"]], Field(min_length=1, max_length=6)]


class Collision(Strict):
    """``collision:`` in a robot file: radii (mm) of the cylinders passive links and cranks
    are modelled as; analyze reports clearances below them as collisions."""

    leg_radius: Optional[Length] = None
    rod_radius: Optional[Length] = None
    crank_radius: Optional[Length] = None


def robot_file_schema():
    """The YAML schema over the registered limb models (built anew when the registry changed);
    documented field by field in docs/how-to/robot-files.md."""
    return _schema_over(tuple(MODELS.values()))


@functools.lru_cache(maxsize=None)
def _schema_over(models):
    limb = Annotated[Union[models], Field(discriminator="model")]

    class RobotFile(Strict):
        name: Annotated[Identifier, AfterValidator(_check_c_names),
                        Field(description="The robot's name; each host makes its C names from it.")]
        description: Annotated[str, Field(min_length=1, description="What the robot is, in a sentence.")]
        source: Optional[str] = Field(None, description="Where the geometry comes from (a drawing, a paper).")
        limbs: Optional[Annotated[list[limb], Field(min_length=1, max_length=MAX_LIMBS)]] = Field(
            None, description="The limbs, one joint each, in joint order (or give a `layout`).")
        layout: Optional[Layout] = Field(None, description="A parametric layout that makes the limbs.")
        verification: Region = Field(description="The region verify draws its poses from, around a home pose.")
        golden: Annotated[list[Golden], Field(max_length=MAX_GOLDEN)] = Field(
            [], description="Published pose-to-joints pairs every routine must reproduce.")
        singularity: Optional[Singularity] = Field(None, description="When a pose counts as a direct singularity.")
        forward: Optional[Forward] = Field(None, description="The pose coordinates forward kinematics solves for.")
        task: Optional[list[Literal["x", "y", "z", "roll", "pitch", "yaw"]]] = Field(
            None, description="A lower-mobility machine's task coordinates: [z, roll, pitch] (x, y, yaw follow) or "
                  "[x, y, z] (roll, pitch, yaw follow).")
        passive_leg: Optional[PassiveLegFile] = Field(None, description="A passive constraining leg (universal "
                                                      "joint, prismatic joint, fixed to the platform): task [x, y, z].")
        wrist: Optional[Annotated[list[WristJoint], Field(min_length=1, max_length=3)]] = Field(
            None, description="A serial wrist on the platform: its joints in chain order, axes and origins in the "
                              "platform frame with every wrist joint at 0 (task [x, y, z]).")
        tool: Optional[Pose] = Field(None, description="With a wrist: the tool frame in the platform frame with every "
                                                       "wrist joint at 0 (mm, degrees).")
        working_posture: Annotated[int, Field(ge=0)] = Field(
            0, description="The posture a host with one answer per pose (LinuxCNC) uses.")
        collision: Optional[Collision] = Field(None, description="The radii `kingen analyze` checks clearances with.")
        units: Literal["mm", "m", "inch"] = Field(
            "mm", description="The file's length unit: mm, m or inch. A file without it is read in mm, and verify "
                              "fails such a machine under 10 mm across (its lengths are likely in metres).")
        optimize: Optional[Optimize] = Field(None, description="The design problem `kingen optimize` searches.")
        payload: Optional[PayloadFile] = Field(None, description="The rigid body the platform carries: `kingen loads` "
                                                                 "and verify's machine check hold it.")
        gravity: Gravity = Field([0.0, 0.0, -9.81], description="m/s^2 in the base frame.")

    return RobotFile
