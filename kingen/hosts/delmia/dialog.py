"""What DELMIA's dialogs call a robot's routine, library, calibration fields and joints.

The Inverse Kinematics dialog's Solver Attributes tab names the library (``lib<name>``) and
the routine (``kin_<name>``), and holds the fields Length 1-6 and Offset 1-6 that reach the
routine as ``link_lengths[]`` and ``link_offsets[]``: the calibration fields a robot file
reads as ``length1`` .. ``offset6`` (:data:`kingen.robot.schema.CALIBRATION_FIELDS`). The
Actuator Space Map gives each joint a type and an axis.
"""

ACTUATOR_SPACE = {"prismatic": ("Translational", "Trans Z"), "revolute": ("Rotational", "Rot Z")}
"""Joint type name (kingen.conventions.JointType.name) -> (the Actuator Space Map's joint
type, its axis)."""


def routine_name(robot_name):
    """The routine's C name, ``kin_<name>``, as the Solver Attributes tab names it."""
    return f"kin_{robot_name}"


def library_name(robot_name):
    """The library's name without its suffix, ``lib<name>``, as the Solver Attributes tab
    names it (``lib<name>.so`` or ``lib<name>.dll`` on disk)."""
    return f"lib{robot_name}"


def field_label(field):
    """The Solver Attributes tab's label of a calibration field: length3 -> 'Length 3'."""
    return f"{field[:-1].capitalize()} {field[-1]}"
