"""A robot file with a serial wrist on its parallel part, read for the numpy reference
(kingen.robot.wrist says what this version solves; docs/how-to/hybrid.md)."""

from dataclasses import dataclass

from pydantic import ValidationError, create_model

from .located import Locator, diagnostic
from .model import Golden, resolve_robot_path, robot_from_data
from .reading import read_robot_file
from .schema import Strict
from .wrist import WRIST_FIELDS, Wrist, wrist_of


@dataclass(frozen=True, eq=False)
class HybridRobot:
    """A parallel part (kingen.robot.model.Robot, task x, y, z) with a wrist; ``golden`` the
    file's golden entries over the tool pose (kingen.robot.model.Golden, joints legs then wrist)."""

    robot: object
    wrist: Wrist
    golden: tuple

    @property
    def joint_names(self):
        return self.robot.joint_names + self.wrist.names

    @property
    def postures(self):
        """The parallel part's postures times the wrist's two branches (branch: the last bit)."""
        return self.robot.postures * 2


def load_hybrid(spec):
    """The HybridRobot of the robot file ``spec`` (a path): its parallel part read as any robot
    file without ``wrist``, ``tool`` and ``golden``, then the wrist and the golden entries (each
    with the parallel part's joints then the wrist's); KingenError (one located line) otherwise."""
    path = resolve_robot_path(spec)
    data, lines, raw = read_robot_file(path)
    locate = Locator(str(path), lines)
    if not isinstance(data, dict) or "wrist" not in data:
        raise locate.error(["wrist"], "required key missing")
    parallel = {key: value for key, value in data.items() if key not in WRIST_FIELDS + ("golden",)}
    robot = robot_from_data(parallel, path, lines, raw)
    wrist = wrist_of(data, robot, locate)
    entries = create_model("HybridGolden", __base__=Strict, golden=(list[Golden], []))
    try:
        golden = entries.model_validate({"golden": data.get("golden") or []}).golden
    except ValidationError as error:
        raise diagnostic(error, locate) from None
    for index, entry in enumerate(golden):
        if len(entry.joints) != robot.dof + len(wrist.names):
            raise locate.error(["golden", index, "joints"], f"expected {robot.dof + len(wrist.names)} joint values "
                                                            f"(the legs', then the wrist's), got {len(entry.joints)}")
    return HybridRobot(robot=robot, wrist=wrist, golden=tuple(golden))
