"""``golden[i]``: each golden value of the robot file (published joints for a pose) against
the routine and the reference, in the file's units, with empty calibration fields."""

import numpy as np

from ...conventions import t6_from_pose
from ...reference import solve
from ...report import GoldenResult
from .base import Check, VerifyCheck


def _golden_detail(result):
    return (f"{result.source}: pose {result.pose} posture {result.posture}: expected {result.expected}, "
            f"plugin {[round(v, 6) for v in result.plugin]}, reference {[round(v, 6) for v in result.reference]}, "
            f"tolerance {result.tolerance:g}")


def check_golden(robot, plugin):
    """Each golden value of the robot against the plugin and the reference, in YAML units."""
    results = []
    scale = robot.joint_scale()
    for golden in robot.golden:
        t6 = t6_from_pose(np.asarray([golden.pose]))
        plugin.reset_host()
        from_plugin = plugin.call(t6).solutions[0, :, golden.posture] / scale
        from_reference = solve(robot, t6).joints[0, :, golden.posture] / scale
        expected = np.asarray(golden.joints)
        passed = bool(
            np.all(np.abs(from_plugin - expected) <= golden.tolerance)
            and np.all(np.abs(from_reference - expected) <= golden.tolerance)
        )
        results.append(GoldenResult(
            source=" ".join(golden.source.split()), pose=list(golden.pose), posture=golden.posture,
            expected=list(golden.joints), plugin=[float(v) for v in from_plugin],
            reference=[float(v) for v in from_reference], tolerance=golden.tolerance, passed=passed,
        ))
    return results


class Golden(VerifyCheck):
    name = "golden"
    needs = "golden values"

    def run(self, context):
        context.report.golden = check_golden(context.robot, context.routine)
        return [Check(f"golden[{i}]", result.passed, _golden_detail(result))
                for i, result in enumerate(context.report.golden)]
