"""DELMIA's interface contract (docs/explanation/delmia-abi.md) as four checks: ``get_kin_config``,
``kin_check_definition``, ``refusal`` and ``non-finite T6``, run on the loaded routine before
any sampled pose."""

import numpy as np

from ....conventions import t6_from_pose
from ....kinematics.routine import UNWRITTEN_WARNING, WARNINGS
from ....runtime.text import counted
from ....verify.checks.base import Check, VerifyCheck
from .. import abi


def _home(robot):
    return t6_from_pose(np.asarray([robot.verification.home]))


class GetKinConfig(VerifyCheck, name="get_kin_config", needs="routine", item="interface"):
    """get_kin_config answers the robot's counts and a known data hint, and refuses other names."""

    def run(self, context):
        robot, plugin = context.robot, context.routine
        config = plugin.config
        problems = []
        if (config.dof, config.solutions) != (robot.joint_count, robot.postures):
            problems.append(f"answers {counted(config.dof, 'joint')} and {counted(config.solutions, 'solution')}; "
                            f"the robot has {robot.joint_count} and {robot.postures}")
        if config.data_hint not in (abi.CONSTANTS["USR_KIN_DATA_NULL"], abi.CONSTANTS["USR_KIN_DATA_KINSTAT"]):
            problems.append(f"answers an unknown data hint {config.data_hint}")
        if plugin.kin_config(plugin.routine + "_unknown").status == 0:
            problems.append(f"accepts a routine name that is not '{plugin.routine}'")
        return [Check("get_kin_config", not problems, "; ".join(problems) or
                      f"answers '{plugin.routine}' with {counted(config.dof, 'joint')}, "
                      f"{counted(config.solutions, 'solution')}, "
                      f"hint {config.data_hint}; refuses other names")]


class KinCheckDefinition(VerifyCheck, name="kin_check_definition", needs="routine", item="interface"):
    """The routine asks the host once per call whether the device definition matches."""

    def run(self, context):
        plugin = context.routine
        plugin.reset_host()
        plugin.call(_home(context.robot))
        calls, dof, solutions = plugin.host_state()
        return [Check("kin_check_definition", (calls, dof, solutions) == (1, plugin.dof, plugin.postures),
                      f"called {calls} times, last with ({dof}, {solutions}); expected once with "
                      f"({plugin.dof}, {plugin.postures})")]


class Refusal(VerifyCheck, name="refusal", needs="routine", item="interface"):
    """When the host refuses the definition, the routine returns 1 and writes nothing."""

    def run(self, context):
        plugin = context.routine
        plugin.reset_host(refuse=True)
        refused = plugin.call(_home(context.robot))
        plugin.reset_host()
        problems = []
        if refused.returned[0] != 1:
            problems.append(f"returns {refused.returned[0]}, not 1")
        if not (np.all(np.isnan(refused.solutions)) and np.all(refused.warnings == UNWRITTEN_WARNING)):
            problems.append("writes solutions or warnings")
        return [Check("refusal", not problems, "when kin_check_definition refuses, the routine " +
                      (" and ".join(problems) if problems else "returns 1 and writes nothing"))]


class NonFiniteT6(VerifyCheck, name="non-finite T6", needs="routine", item="interface"):
    """A T6 holding NaN or inf gives return 1, finite joints and WARN_UNREACHABLE everywhere."""

    def run(self, context):
        plugin = context.routine
        plugin.reset_host()
        problems = []
        for bad in (np.nan, np.inf):
            t6 = _home(context.robot)
            t6[0, 3, 0] = bad
            result = plugin.call(t6)
            if not (result.returned[0] == 1 and np.all(np.isfinite(result.solutions))
                    and np.all(result.warnings == WARNINGS["WARN_UNREACHABLE"])):
                problems.append(f"a T6 holding {bad} gives return {result.returned[0]}, "
                                f"{'finite' if np.all(np.isfinite(result.solutions)) else 'non-finite'} joints, "
                                f"warnings {sorted(set(result.warnings[0].tolist()))}")
        return [Check("non-finite T6", not problems, "; ".join(problems) or
                      "NaN and inf give return 1, finite joints, WARN_UNREACHABLE everywhere")]
