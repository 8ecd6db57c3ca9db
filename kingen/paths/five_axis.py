"""A machine with a serial wrist checked along its program (docs/how-to/check-path.md, 'A
five-axis machine').

A G-code program commands LinuxCNC's five-axis world as the machine's module reads it
(kingen.hosts.linuxcnc.five_axis): X Y Z the tool tip (base frame, mm) and A, C the tool axis
w = Rz(C) Rx(A) w0 (degrees), w0 the tool axis at the verification home with the wrist at 0.
B and the turn about the tool axis are not read. The interpreter moves X Y Z A B C linearly
together, so the check samples the world linearly and turns each sample into the tool's T6
here: the home tool frame turned by Rz(C) Rx(A) (its axis w; the turn about w, which the
inverse kinematics ignores, the home frame's carried along). A CSV of poses gives tool poses
(x, y, z, roll, pitch, yaw) and needs nothing of this module.
"""

import numpy as np

from ..conventions import matrix_from_pose, t6_from_matrix
from ..hosts.linuxcnc.five_axis import COORDINATES, home_axis, world_of_t6
from ..kinematics.hybrid.wrist import rotation_about
from ..units import number_text

NOT_READ = "B, and the turn about the tool axis"
"""What of a pose a five-axis machine does not read."""


class FiveAxis:
    """``robot`` (with a wrist) read as its LinuxCNC five-axis module reads it."""

    def __init__(self, robot):
        self.robot = robot
        self.home = matrix_from_pose(np.asarray(robot.verification.home, dtype=float))
        self.axis = home_axis(robot)

    def start(self):
        """(6,) the world X Y Z A B C (mm, degrees; B 0) of the verification home: where a
        G-code program starts."""
        return world_of_t6(self.robot, t6_from_matrix(self.home[None]))[0, :6]

    def t6(self, world):
        """(n, 4, 4) the tool T6 (base frame, mm) at world positions ``world`` (n, 6) X Y Z A B C
        (mm, degrees): tool tip X Y Z, tool axis Rz(C) Rx(A) w0 (B not read)."""
        world = np.asarray(world, dtype=float)
        x_axis, z_axis = np.eye(3)[0], np.eye(3)[2]
        turn = rotation_about(z_axis, np.radians(world[:, 5])) @ rotation_about(x_axis, np.radians(world[:, 3]))
        matrix = np.tile(self.home, (len(world), 1, 1))
        matrix[:, :3, :3] = turn @ self.home[:3, :3]
        matrix[:, :3, 3] = world[:, :3]
        return t6_from_matrix(matrix)

    def summary(self, gcode):
        """Plain data for the report: how the program's poses are read, the home tool axis, the
        wrist's joints."""
        wrist = self.robot.wrist
        return {"program": "G-code: LinuxCNC's five-axis world" if gcode else "CSV: tool poses",
                "read": ", ".join(COORDINATES) if gcode else "x, y, z, roll, pitch, yaw (the tool tip and axis)",
                "not_read": NOT_READ if gcode else "the turn about the tool axis",
                "pose_columns": "X Y Z A B C as commanded" if gcode else "x y z roll pitch yaw of the tool",
                "home_axis": [float(value) for value in self.axis], "wrist_joints": list(wrist.names)}

    def line(self, gcode, peaks, names):
        """The report's line about the five-axis reading and the wrist joints' travel over the
        path (``peaks`` Findings.peaks in display units, ``names`` the robot's joint names)."""
        data = self.summary(gcode)
        used = {name: peaks[names.index(name)] for name in data["wrist_joints"]}
        ranges = ", ".join(f"{name} {number_text(peak.low)} .. {number_text(peak.high)} deg" if peak.low <= peak.high else f"{name} -"
                           for name, peak in used.items())
        return f"five-axis: {data['read']} read; {data['not_read']} not read; wrist over the path: {ranges}"
