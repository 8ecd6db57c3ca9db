"""Verification: a compiled routine against the numpy reference, the published
golden values and the interface contract of shared/delmia-abi.md.

Everything is compared, nothing sampled away: every joint of every posture of
every pose, and every warning. A warning may differ only inside the documented
tolerance band (``WARNING_BAND``): where the reference's decision quantity (a
normalised radicand or a joint value) lies that close to its threshold, both
answers are right within floating-point rounding.
"""

import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from . import abi
from .conventions import angle_difference, t6_from_pose
from .host import UNWRITTEN_WARNING, host_state
from .model import REVOLUTE
from .reference import SINGULAR_TOLERANCE, solve

VALUE_TOLERANCE_MM = 1e-9
VALUE_TOLERANCE_RAD = 1e-9
WARNING_BAND = 1e-9
"""Half-width of the band around a warning threshold (radicand +/- tolerance: relative;
travel limits: mm or rad) inside which plugin and reference may disagree."""
CONDITIONING_FACTOR = 16.0 * np.finfo(float).eps
"""Inside a limb's singular band its joint is ill-conditioned (a square root of a radicand
near 0): there it is compared within CONDITIONING_FACTOR * scale / sqrt(max(|D|, eps)),
scale = link length (mm) for rails, 1 rad for cranks. Everywhere else the fixed limits hold."""
CHUNK = 20000
"""Poses per batch: bounds memory (a 64-posture robot holds 6 x 64 doubles per pose)."""


@dataclass
class GoldenResult:
    """One golden value: published joints against the plugin's and the reference's (YAML units)."""

    source: str
    pose: list
    posture: int
    expected: list
    plugin: list
    reference: list
    tolerance: float
    passed: bool


@dataclass
class Report:
    """The outcome of ``verify``; ``as_json`` gives the contract keys of the CLI's --json."""

    robot: str
    routine: str
    samples: int
    seed: int
    postures: int
    max_abs_error_mm: float = 0.0
    max_abs_error_rad: float = 0.0
    singular_entries: int = 0
    singular_out_of_bound: int = 0
    warning_mismatches: int = 0
    warnings_in_band: int = 0
    golden: list = field(default_factory=list)
    interface_failures: list = field(default_factory=list)
    seconds: float = 0.0

    @property
    def golden_checked(self):
        return len(self.golden)

    @property
    def golden_failed(self):
        return sum(1 for result in self.golden if not result.passed)

    @property
    def passed(self):
        return (
            self.max_abs_error_mm <= VALUE_TOLERANCE_MM
            and self.max_abs_error_rad <= VALUE_TOLERANCE_RAD
            and self.singular_out_of_bound == 0
            and self.warning_mismatches == 0
            and self.golden_failed == 0
            and not self.interface_failures
        )

    @property
    def poses_per_second(self):
        return self.samples / self.seconds if self.seconds > 0 else math.inf

    def as_json(self):
        return {
            "robot": self.robot,
            "routine": self.routine,
            "samples": self.samples,
            "seed": self.seed,
            "postures": self.postures,
            "max_abs_error_mm": _json_number(self.max_abs_error_mm),
            "max_abs_error_rad": _json_number(self.max_abs_error_rad),
            "tolerance_mm": VALUE_TOLERANCE_MM,
            "tolerance_rad": VALUE_TOLERANCE_RAD,
            "singular_entries": self.singular_entries,
            "singular_out_of_bound": self.singular_out_of_bound,
            "warning_mismatches": self.warning_mismatches,
            "warnings_in_band": self.warnings_in_band,
            "golden_checked": self.golden_checked,
            "golden_failed": self.golden_failed,
            "golden": [asdict(result) for result in self.golden],
            "interface_failures": list(self.interface_failures),
            "seconds": round(self.seconds, 6),
            "poses_per_second": _json_number(self.poses_per_second),
            "passed": self.passed,
        }


def _json_number(value):
    return value if math.isfinite(value) else None


def sample_poses(robot, count, seed):
    """``count`` poses (mm, degrees) uniform in the robot's verification region, seeded."""
    region = robot.verification
    rng = np.random.default_rng(seed)
    return np.asarray(region.home) + rng.uniform(-1.0, 1.0, size=(count, 6)) * np.asarray(region.range)


def joint_errors(robot, solutions, joints):
    """|plugin - reference| per entry, (n, dof, postures); angle-aware for revolute joints.

    A non-finite plugin value (unwritten or NaN) counts as an infinite error.
    """
    revolute = np.array([t == REVOLUTE for t in robot.joint_types])[None, :, None]
    difference = np.where(revolute, angle_difference(solutions, joints), solutions - joints)
    return np.where(np.isfinite(solutions), np.abs(difference), np.inf)


def singular_bounds(robot, reference_solution):
    """(n, dof) error bound for joints in their singular band; 0 where the fixed limits apply."""
    radicands = reference_solution.radicands
    scale = np.array([limb.link_length if limb.model == "rail" else 1.0 for limb in robot.limbs])
    in_band = np.abs(radicands) <= SINGULAR_TOLERANCE + WARNING_BAND
    eps = np.finfo(float).eps
    with np.errstate(invalid="ignore"):
        bound = CONDITIONING_FACTOR * scale / np.sqrt(np.maximum(np.abs(radicands), eps))
    return np.where(in_band, bound, 0.0)


def warnings_in_band(robot, reference_solution):
    """(n, postures) True where the reference's warning is within WARNING_BAND of a threshold."""
    radicands = reference_solution.radicands
    near_radicand = np.any(
        (np.abs(radicands - SINGULAR_TOLERANCE) < WARNING_BAND) | (np.abs(radicands + SINGULAR_TOLERANCE) < WARNING_BAND),
        axis=1,
    )
    lower, upper = robot.travel_limits()
    joints = reference_solution.joints
    near_limit = np.any(
        (np.abs(joints - lower[None, :, None]) < WARNING_BAND) | (np.abs(joints - upper[None, :, None]) < WARNING_BAND),
        axis=1,
    )
    return near_radicand[:, None] | near_limit


def verify(robot, plugin, samples=10000, seed=0, progress=None):
    """Compare ``plugin`` with the reference on ``samples`` seeded poses, the golden values
    and the interface checks. ``progress(done)`` is called after each chunk."""
    report = Report(robot=robot.name, routine=plugin.routine, samples=samples, seed=seed, postures=robot.postures)
    report.interface_failures = check_interface(robot, plugin)
    if (plugin.dof, plugin.postures) != (robot.dof, robot.postures):
        return report
    poses = sample_poses(robot, samples, seed)
    revolute = np.array([t == REVOLUTE for t in robot.joint_types])
    start = time.perf_counter()
    for begin in range(0, samples, CHUNK):
        t6 = t6_from_pose(poses[begin:begin + CHUNK])
        plugin.reset_host()
        calls = plugin.call_batch(t6)
        expected = solve(robot, t6)
        errors = joint_errors(robot, calls.solutions, expected.joints)
        bounds = singular_bounds(robot, expected)[:, :, None]
        singular = np.broadcast_to(bounds > 0, errors.shape)
        report.singular_entries += int(np.count_nonzero(singular))
        report.singular_out_of_bound += int(np.count_nonzero(singular & (errors > bounds)))
        regular = np.where(singular, 0.0, errors)
        if regular[:, ~revolute].size:
            report.max_abs_error_mm = max(report.max_abs_error_mm, float(regular[:, ~revolute].max()))
        if regular[:, revolute].size:
            report.max_abs_error_rad = max(report.max_abs_error_rad, float(regular[:, revolute].max()))
        differ = calls.warnings != expected.warnings
        excused = differ & warnings_in_band(robot, expected) & (calls.warnings != UNWRITTEN_WARNING)
        report.warning_mismatches += int(np.count_nonzero(differ & ~excused))
        report.warnings_in_band += int(np.count_nonzero(excused))
        if progress is not None:
            progress(min(begin + CHUNK, samples))
    report.seconds = time.perf_counter() - start
    report.golden = check_golden(robot, plugin)
    return report


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
            source=golden.source, pose=list(golden.pose), posture=golden.posture, expected=list(golden.joints),
            plugin=[float(v) for v in from_plugin], reference=[float(v) for v in from_reference],
            tolerance=golden.tolerance, passed=passed,
        ))
    return results


def check_interface(robot, plugin):
    """The contract of shared/delmia-abi.md, each broken clause as one sentence."""
    failures = []
    config = plugin.config
    if (config.dof, config.solutions) != (robot.dof, robot.postures):
        failures.append(
            f"get_kin_config answers {config.dof} joints and {config.solutions} solutions; "
            f"the robot has {robot.dof} and {robot.postures}"
        )
    if config.data_hint not in (abi.CONSTANTS["USR_KIN_DATA_NULL"], abi.CONSTANTS["USR_KIN_DATA_KINSTAT"]):
        failures.append(f"get_kin_config answers an unknown data hint {config.data_hint}")
    if plugin.kin_config(plugin.routine + "_unknown").status == 0:
        failures.append(f"get_kin_config accepts a routine name that is not '{plugin.routine}'")
    home = t6_from_pose(np.asarray([robot.verification.home]))

    plugin.reset_host()
    plugin.call(home)
    calls, dof, solutions = host_state()
    if (calls, dof, solutions) != (1, plugin.dof, plugin.postures):
        failures.append(
            f"kin_check_definition was called {calls} times with ({dof}, {solutions}); "
            f"expected once with ({plugin.dof}, {plugin.postures})"
        )

    plugin.reset_host(refuse=True)
    refused = plugin.call(home)
    plugin.reset_host()
    if refused.returned[0] != 1:
        failures.append(f"the routine returns {refused.returned[0]}, not 1, when kin_check_definition refuses")
    if not (np.all(np.isnan(refused.solutions)) and np.all(refused.warnings == UNWRITTEN_WARNING)):
        failures.append("the routine writes outputs although kin_check_definition refused")

    for bad in (np.nan, np.inf):
        t6 = home.copy()
        t6[0, 3, 0] = bad
        result = plugin.call(t6)
        if not (result.returned[0] == 1 and np.all(np.isfinite(result.solutions))
                and np.all(result.warnings == abi.WARNINGS["WARN_UNREACHABLE"])):
            failures.append(
                f"a T6 holding {bad} must give return 1, finite joints and WARN_UNREACHABLE everywhere"
            )
    return failures
