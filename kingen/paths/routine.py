"""The robot's generated routine solving a check's regular samples (``check-path --routine``):
compiled for the host whose interpolation is followed (skipped when up to date), loaded in a
child process for each batch (kingen.runtime.isolation.run_in_child) and called there through
the host's batch driver, its Calls sent back as plain data and decoded field by field, as
verify's are. The numpy reference still gives what only it gives: the radicands, the direct
index, the force lines' determinant, the clearances, and the samples refinement adds.
"""

from dataclasses import dataclass

import numpy as np

from ..defaults import DEFAULT_TIMEOUT
from ..errors import KingenError, PluginDefect
from ..hosts import get_host
from ..kinematics.routine import calls_decoder
from ..runtime.isolation import run_in_child


def _call_job(channel, host, model, library, routine, t6):
    """In a child process: the routine's Calls on ``t6`` (n, 4, 4), mm."""
    plugin = host.load(library, routine, model)
    channel.stage("the routine's call")
    return plugin.call(t6)


@dataclass
class Agreement:
    """How the routine's answers compared with the reference's at the regular samples: how many,
    the largest joint difference (mm for prismatic joints, degrees for revolute ones), and the
    samples whose warning differs."""

    samples: int = 0
    joint_difference: float = 0.0
    warning_mismatches: int = 0


class RoutineSolver:
    """The routine of ``robot`` for ``host_name`` at ``posture``, called on batches of T6."""

    def __init__(self, robot, host_name, posture, out_dir=None, timeout=DEFAULT_TIMEOUT):
        self.host = get_host(host_name)
        self.model = self.host.as_seen(robot)
        if self.model.postures == 1 and posture != robot.working_posture:
            raise KingenError(f"--routine: the {host_name} routine answers posture {robot.working_posture} only "
                              f"(the robot file's working_posture), not {posture}")
        self.column = posture if self.model.postures > 1 else 0
        built = self.host.build(robot, out_dir, timeout=timeout)
        self.library, self.routine, self.timeout = built.library, built.routine, timeout
        self.host.prepare_load()
        self.agreement = Agreement()

    def __call__(self, t6):
        """(joints (n, dof) mm or rad, warnings (n,) WARN_* codes) at ``t6`` (n, 4, 4), mm."""
        calls, failure = run_in_child(_call_job, (self.host, self.model, self.library, self.routine, t6),
                                      self.timeout, first_stage=self.host.loading_stage,
                                      decoders={"result": calls_decoder(len(t6))})
        if failure is not None:
            raise PluginDefect(failure.detail)
        return calls.solutions[:, :, self.column], calls.warnings[:, self.column]

    def compare(self, joints, warnings, expected_joints, expected_warnings, reachable, display_scale):
        """Add one batch's comparison (routine against reference, internal units; joints where
        ``reachable``, warnings everywhere) to the agreement."""
        if np.any(reachable):
            difference = np.abs(joints[reachable] - expected_joints[reachable]) * display_scale
            self.agreement.joint_difference = max(self.agreement.joint_difference, float(np.max(difference)))
        self.agreement.samples += len(joints)
        self.agreement.warning_mismatches += int(np.sum(warnings != expected_warnings))
