"""The robot at a batch of poses along a move: its joints in one posture (the numpy reference,
vectorised over the batch) and every decision quantity of the checks, signed so that a
positive value is within its limit and 0 is the boundary.

Decision quantities (one column each), internal units:

- ``travel``: upper - q and q - lower per joint with a limit (mm or rad);
- ``unreachable``: D + tol and ``limb singular``: D - tol per limb with a radicand (D the
  limb's normalised radicand, tol kingen.kinematics.routine.SINGULAR_TOLERANCE), as the
  routine's warnings decide them; a wrist's joints have theirs (kingen.kinematics.hybrid.wrist: the
  first's 1 - (a1.w)^2, 0 where the tool axis lies along the first axis, only singular; the
  second's, below 0 where no wrist angle reaches the axis); a machine with task coordinates has the pair for its
  constraint's radicand too (kingen.kinematics.hybrid.parasitic: below 0 no pose has the sample's
  task coordinates), its ``part`` 'constraint';
- ``direct index``: the direct index minus the robot's ``direct_index_min`` (mm);
- ``assembly change``: det of the six unit force lines (mm^3), which the caller signs by its
  sign at the move's start: its sign changes where the platform changes assembly mode;
- ``collision``: the least clearance (mm) between passive links, and between cranks, as
  cylinders of the robot file's ``collision`` radii (kingen.kinematics.collision, model
  ``segments``): below 0 the cylinders overlap. Present only where the file gives radii;
- ``joint angle``: a limb's ``joint_limits`` minus its base or platform passive joint's angle
  from its neutral axis (degrees; kingen.kinematics.loads), its ``part`` 'base' or 'platform';
- ``actuator load``: a limb's max_force or max_torque minus the magnitude of the load that holds
  the payload at rest (N or N m; kingen.kinematics.loads).
"""

from dataclasses import dataclass

import numpy as np

from ..kinematics.collision import clearances
from ..kinematics.loads import SIDES, loads_of
from ..kinematics.reference import solve
from ..kinematics.routine import SINGULAR_TOLERANCE
from ..kinematics.singularity import limb_wrenches
from ..robot.one_posture import at_posture


@dataclass(frozen=True)
class Quantity:
    """One column of the decision quantities: its check ``kind``, the joint or limb it is of
    (None: the platform's), which side of a limit (``upper``: the value must stay below it)."""

    kind: str
    joint: int = None
    upper: bool = False
    part: str = None
    """For a collision: which links' clearance ('rods' or 'cranks'); 'constraint' for a
    machine's constraint radicand."""


FIELDS = ("piece", "u", "poses", "joints", "margins", "radicand", "direct_index", "warnings")


@dataclass
class Batch:
    """Samples of pieces of moves: piece (n,) which piece each is of, u (n,) its parameter on its
    move, poses (n, 6) mm and degrees; joints (n, dof) mm or rad; margins (n, quantities);
    radicand (n,) the smallest limb (or constraint) radicand (inf: none); direct_index (n,) mm (NaN: none);
    warnings (n,) the reference's WARN_* code in the posture."""

    piece: np.ndarray
    u: np.ndarray
    poses: np.ndarray
    joints: np.ndarray
    margins: np.ndarray
    radicand: np.ndarray
    direct_index: np.ndarray
    warnings: np.ndarray

    def take(self, order):
        """This batch's samples in ``order`` (an index array or a boolean mask)."""
        return Batch(*(getattr(self, name)[order] for name in FIELDS))

    @staticmethod
    def joined(first, second):
        """Both batches' samples, sorted by piece, then u."""
        joined = Batch(*(np.concatenate([getattr(first, name), getattr(second, name)]) for name in FIELDS))
        return joined.take(np.lexsort((joined.u, joined.piece)))


class Evaluator:
    """Solves poses for ``robot`` held at ``posture`` and forms the decision quantities against
    ``limits`` (kingen.paths.limits.Limits)."""

    def __init__(self, robot, posture, limits):
        self.robot = at_posture(robot, posture)
        self.limits = limits
        self.six_lines = self.robot.has_direct_index
        self.threshold = robot.direct_index_min
        columns = []
        for joint in range(self.robot.joint_count):
            if np.isfinite(limits.upper[joint]):
                columns.append(Quantity("travel", joint, True))
            if np.isfinite(limits.lower[joint]):
                columns.append(Quantity("travel", joint, False))
        for joint, limb in enumerate(self.robot.limbs):
            if limb.has_radicand:
                columns += [Quantity("unreachable", joint), Quantity("limb singular", joint)]
        if self.robot.wrist is not None:  # its first joint's radicand (the axes aligned) is never below 0
            dof = self.robot.dof
            columns += [Quantity("limb singular", dof), Quantity("unreachable", dof + 1),
                        Quantity("limb singular", dof + 1)]
        if self.robot.task:
            columns += [Quantity("unreachable", part="constraint"), Quantity("limb singular", part="constraint")]
        if self.six_lines and self.threshold is not None:
            columns.append(Quantity("direct index"))
        if self.six_lines:
            columns.append(Quantity("assembly change"))
        self.collisions = self._collision_pairs()
        columns += [Quantity("collision", part=pair) for pair in self.collisions]
        columns += self._load_quantities()
        self.quantities = tuple(columns)
        self.loads_judged = any(quantity.kind in LOAD_KINDS for quantity in columns)

    def _load_quantities(self):
        """The passive joints' angles and the actuators' loads that the robot file limits."""
        columns = []
        for joint, limb in enumerate(self.robot.limbs):
            for side in SIDES:
                if limb.cone(side) is not None:
                    columns.append(Quantity("joint angle", joint, True, part=side))
            if limb.actuator_limit is not None:
                columns.append(Quantity("actuator load", joint, True))
        return columns

    def _collision_pairs(self):
        """Which clearances the robot file's radii judge: 'rods' (passive links) when it gives
        radii and has two limbs or more, 'cranks' too when two limbs or more have actuator arms."""
        if self.robot.collision is None or self.robot.dof < 2:
            return ()
        arms = sum(limb.actuator_segment(np.zeros(1)) is not None for limb in self.robot.limbs)
        return ("rods", "cranks") if arms >= 2 else ("rods",)

    def kinds(self):
        """The checks these quantities judge, in report order."""
        return tuple(dict.fromkeys(quantity.kind for quantity in self.quantities))

    def evaluate(self, piece, u, poses, t6):
        """The Batch of pieces ``piece`` at parameters ``u`` with poses (n, 6) and their T6 (n, 4, 4)."""
        solution = solve(self.robot, t6, indices=self.six_lines)
        joints = solution.branch_joints[:, :, 0]
        margins = np.empty((len(u), len(self.quantities)))
        radicands = solution.radicands
        if solution.constraint is not None:
            radicands = np.column_stack([radicands, np.where(np.isnan(solution.constraint), -np.inf, solution.constraint)])
        determinant = self._determinant(solution) if self.six_lines else None
        clearance = dict(zip(("rods", "cranks"), clearances(self.robot, solution.points, joints))) \
            if self.collisions else {}
        index = solution.direct_index[:, 0] if solution.direct_index is not None else np.full(len(u), np.nan)
        held = loads_of(self.robot, t6, solution) if self.loads_judged else None
        for column, quantity in enumerate(self.quantities):
            joint = quantity.joint
            if quantity.kind == "travel":
                margins[:, column] = (self.limits.upper[joint] - joints[:, joint] if quantity.upper
                                      else joints[:, joint] - self.limits.lower[joint])
            elif quantity.kind == "unreachable":
                margins[:, column] = radicands[:, -1 if joint is None else joint] + SINGULAR_TOLERANCE
            elif quantity.kind == "limb singular":
                margins[:, column] = radicands[:, -1 if joint is None else joint] - SINGULAR_TOLERANCE
            elif quantity.kind == "direct index":
                margins[:, column] = np.nan_to_num(solution.direct_index[:, 0] - self.threshold, nan=-np.inf)
            elif quantity.kind == "collision":
                margins[:, column] = clearance[quantity.part]
            elif quantity.kind in LOAD_KINDS:
                margins[:, column] = self.limit_of(quantity) - _load_value(quantity, held)
            else:
                margins[:, column] = determinant
        return Batch(np.asarray(piece), np.asarray(u, dtype=float), poses, joints, margins, np.min(radicands, axis=1),
                     index, solution.warnings[:, 0])

    def _determinant(self, solution):
        """det of the six unit force lines (n,), mm^3."""
        wrenches, _ = limb_wrenches(self.robot, solution.points, solution.branch_joints, with_transmissions=False)
        return np.linalg.det(np.ascontiguousarray(wrenches[:, :, 0, :]))

    def assembly_column(self):
        """The column of the determinant in the margins, or None."""
        return next((column for column, quantity in enumerate(self.quantities)
                     if quantity.kind == "assembly change"), None)

    def limit_of(self, quantity):
        """The limit the quantity's value is judged against, in internal units."""
        if quantity.kind == "travel":
            return self.limits.upper[quantity.joint] if quantity.upper else self.limits.lower[quantity.joint]
        if quantity.kind == "unreachable":
            return -SINGULAR_TOLERANCE
        if quantity.kind == "limb singular":
            return SINGULAR_TOLERANCE
        if quantity.kind == "direct index":
            return self.threshold
        if quantity.kind == "joint angle":
            return self.robot.limbs[quantity.joint].cone(quantity.part)
        if quantity.kind == "actuator load":
            return self.robot.limbs[quantity.joint].actuator_limit
        return 0.0

    def value_of(self, quantity, batch, row):
        """The quantity's own value at a batch's sample (joint, radicand, index or determinant)."""
        if quantity.kind == "travel":
            return batch.joints[row, quantity.joint]
        column = self.quantities.index(quantity)
        if quantity.kind in LOAD_KINDS:  # limits from above
            return self.limit_of(quantity) - batch.margins[row, column]
        return batch.margins[row, column] + self.limit_of(quantity)


LOAD_KINDS = ("joint angle", "actuator load")
"""Decision quantities in display units (degrees, N or N m), limited from above."""


def _load_value(quantity, held):
    """(n,) a load quantity's value from kingen.kinematics.loads' Loads ``held`` (posture 0):
    the passive joint's angle in degrees, or the actuator load's magnitude (NaN: unreachable or
    singular, judged beyond)."""
    if quantity.kind == "joint angle":
        angles = held.base_angles if quantity.part == "base" else held.platform_angles
        return np.degrees(angles[:, 0, quantity.joint])
    return np.nan_to_num(np.abs(held.forces[:, 0, quantity.joint]), nan=np.inf)
