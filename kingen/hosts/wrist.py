"""The serial wrist's part of every host's view-model (templates/wrist.c.j2): its table as C
text, and the whole machine's joints (the legs', then the wrist's) for a routine of all
postures. Pure, like kingen.hosts.render."""

from ..robot.limbs import c_double, c_vector


def wrist_table(robot):
    """The wrist's table of ``robot`` (with a wrist) as C text: ``axes`` (two rows, unit, platform
    frame), ``start`` the tool's z axis and ``reach`` (mm) the tool tip's distance along it from
    the wrist centre, every wrist joint at 0 (kingen.robot.wrist.Wrist)."""
    wrist = robot.wrist
    return {"axes": [c_vector(axis) for axis in wrist.axes], "start": c_vector(wrist.tool[:3, 2]),
            "reach": c_double(wrist.reach)}
