"""Verification: a compiled routine (kingen's or hand-written) against the numpy
reference, the golden values and the interface contract of shared/delmia-abi.md.

Everything is compared, nothing sampled away: every joint of every posture of
every pose, and every warning. Where the reference calls a posture unreachable the
interface asks only for finite joints, so only finiteness is checked there (the
warning itself is compared as everywhere). A warning may differ only inside the documented
tolerance band (``WARNING_BAND``): where the reference's decision quantity (a
normalised radicand or a joint value) lies that close to its threshold, both
answers are right within floating-point rounding. Each clause is a named check;
failed value checks carry diagnoses (:mod:`kingen.diagnose`).
"""

import faulthandler
import math
import multiprocessing
import signal
import time
import xml.etree.ElementTree as ElementTree
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field

import numpy as np

from . import abi
from .conventions import joint_errors, t6_from_pose
from .diagnose import diagnose, diagnose_warnings
from .host import UNWRITTEN_WARNING, captured_output, host_state
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
CHUNK_ENTRIES = 400000
"""Joint entries (poses x dof x postures) per batch: keeps arrays small enough to stay in cache."""
DIAGNOSIS_POSES = 2000
DETERMINISM_POSES = 1000


@dataclass
class Check:
    """One clause of the contract: its name, verdict, the evidence, and diagnoses when it failed."""

    name: str
    passed: bool
    detail: str = ""
    diagnoses: list = field(default_factory=list)


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
    checks: list = field(default_factory=list)
    notices: list = field(default_factory=list)
    seconds: float = 0.0
    link_lengths: list = None
    link_offsets: list = None

    @property
    def golden_checked(self):
        return len(self.golden)

    @property
    def golden_failed(self):
        return sum(1 for result in self.golden if not result.passed)

    @property
    def passed(self):
        return all(check.passed for check in self.checks)

    @property
    def failures(self):
        return [check for check in self.checks if not check.passed]

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
            "link_lengths": self.link_lengths,
            "link_offsets": self.link_offsets,
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
            "checks": [asdict(check) for check in self.checks],
            "interface_failures": [check.detail for check in self.failures if check.name in INTERFACE_CHECKS],
            "diagnoses": [text for check in self.checks for text in check.diagnoses],
            "notices": list(self.notices),
            "seconds": round(self.seconds, 6),
            "poses_per_second": _json_number(self.poses_per_second),
            "passed": self.passed,
        }


UNREACHABLE = abi.WARNINGS["WARN_UNREACHABLE"]
INTERFACE_CHECKS = ("get_kin_config", "kin_check_definition", "refusal", "non-finite T6")


def _json_number(value):
    return value if math.isfinite(value) else None


def sample_poses(robot, count, seed):
    """``count`` poses (mm, degrees) uniform in the robot's verification region, seeded."""
    region = robot.verification
    rng = np.random.default_rng(seed)
    return np.asarray(region.home) + rng.uniform(-1.0, 1.0, size=(count, 6)) * np.asarray(region.range)


def chunk_size(robot):
    """Poses per batch for ``robot``."""
    return max(1000, CHUNK_ENTRIES // (robot.dof * robot.postures))


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
    if not np.any(np.isfinite(lower) | np.isfinite(upper)):
        return np.broadcast_to(near_radicand[:, None], reference_solution.warnings.shape)
    joints = reference_solution.joints
    near_limit = np.any(
        (np.abs(joints - lower[None, :, None]) < WARNING_BAND) | (np.abs(joints - upper[None, :, None]) < WARNING_BAND),
        axis=1,
    )
    return near_radicand[:, None] | near_limit


@dataclass
class _Tally:
    """Running totals over the chunks of one verification."""

    returns_wrong: int = 0
    guard_violations: int = 0
    inputs_modified: bool = False
    first: tuple = None


class _Printed:
    """What the routine printed on stdout/stderr over several captured blocks."""

    def __init__(self):
        self.bytes = 0
        self.first_line = ""

    @contextmanager
    def capture(self):
        with captured_output() as printed:
            yield
        self.bytes += printed["bytes"]
        if not self.first_line and printed["text"].strip():
            self.first_line = printed["text"].strip().splitlines()[0]


def verify(robot, plugin, samples=10000, seed=0, progress=None, link_lengths=None, link_offsets=None,
           phase=None):
    """Check ``plugin`` against ``robot``'s reference on ``samples`` seeded poses, its golden
    values and the interface contract. ``progress(done)`` is called after each chunk and
    ``phase(text)`` before each stage (both optional).
    ``link_lengths`` / ``link_offsets`` (6 each) are passed to the routine and the reference
    alike; golden values are checked with empty fields (the published geometry).
    What the routine prints on stdout/stderr is captured and reported as a notice."""
    report = _empty_report(robot, plugin, samples, seed, link_lengths, link_offsets)
    phase = phase or (lambda text: None)
    printed = _Printed()
    phase("the interface checks")
    with printed.capture():
        report.checks.extend(check_interface(robot, plugin))
    if (plugin.dof, plugin.postures) == (robot.dof, robot.postures):
        _compare_samples(robot, plugin, report, progress, printed, phase)
        phase("the golden values")
        with printed.capture():
            report.golden = check_golden(robot, plugin)
        report.checks.extend(
            Check(f"golden[{i}]", result.passed, _golden_detail(result)) for i, result in enumerate(report.golden)
        )
    else:
        report.checks.append(Check("values", False, "not compared: the routine's joint or posture count differs"))
    if printed.bytes:
        report.notices.append(
            f"the routine printed {printed.bytes} bytes on stdout/stderr (first line: {printed.first_line!r}); "
            "debug printing slows the host by orders of magnitude"
        )
    return report


def _empty_report(robot, plugin, samples, seed, link_lengths, link_offsets):
    return Report(robot=robot.name, routine=plugin.routine, samples=samples, seed=seed, postures=robot.postures,
                  link_lengths=_listed(link_lengths), link_offsets=_listed(link_offsets))


def verify_isolated(robot, plugin, samples=10000, seed=0, progress=None, link_lengths=None, link_offsets=None):
    """``verify`` in a forked child process, for routines that may crash: a routine that
    kills the process becomes a failed check ``crash`` naming the signal and the stage."""
    context = multiprocessing.get_context("fork")
    receiver, sender = context.Pipe(duplex=False)
    options = {"samples": samples, "seed": seed, "link_lengths": link_lengths, "link_offsets": link_offsets}
    child = context.Process(target=_verify_child, args=(sender, robot, plugin, options), daemon=True)
    child.start()
    sender.close()
    stage, report = "loading", None
    while report is None:
        try:
            kind, value = receiver.recv()
        except EOFError:
            break
        if kind == "phase":
            stage = value
        elif kind == "progress" and progress is not None:
            progress(value)
        elif kind == "report":
            report = value
    child.join()
    if report is not None:
        return report
    code = child.exitcode
    how = f"signal {signal.Signals(-code).name}" if code is not None and code < 0 else f"exit status {code}"
    report = _empty_report(robot, plugin, samples, seed, link_lengths, link_offsets)
    report.checks.append(Check("crash", False, f"the routine crashed the host process ({how}) during {stage}"))
    return report


def _verify_child(sender, robot, plugin, options):
    faulthandler.disable()
    report = verify(robot, plugin, progress=lambda done: sender.send(("progress", done)),
                    phase=lambda text: sender.send(("phase", text)), **options)
    sender.send(("report", report))
    sender.close()


def _listed(values):
    return None if values is None else [float(v) for v in values]


def _compare_samples(robot, plugin, report, progress, printed, phase):
    poses = sample_poses(robot, report.samples, report.seed)
    revolute = robot.revolute
    tally = _Tally()
    start = time.perf_counter()
    chunk = chunk_size(robot)
    for begin in range(0, report.samples, chunk):
        phase(f"poses {begin} to {min(begin + chunk, report.samples) - 1} of seed {report.seed}")
        t6 = t6_from_pose(poses[begin:begin + chunk])
        plugin.reset_host()
        with printed.capture():
            calls = plugin.call_batch(t6, report.link_lengths, report.link_offsets)
        expected = solve(robot, t6, report.link_lengths, report.link_offsets)
        _accumulate(robot, report, tally, revolute, t6, calls, expected)
        if progress is not None:
            progress(min(begin + chunk, report.samples))
    report.seconds = time.perf_counter() - start
    phase("the determinism check")
    with printed.capture():
        report.checks.extend(_sample_checks(robot, plugin, report, tally))


def _accumulate(robot, report, tally, revolute, t6, calls, expected):
    errors = joint_errors(calls.solutions, expected.joints, revolute)
    unreachable = expected.warnings == UNREACHABLE
    errors = np.where(unreachable[:, None, :] & np.isfinite(calls.solutions), 0.0, errors)
    bounds = singular_bounds(robot, expected)[:, :, None]
    singular = np.broadcast_to(bounds > 0, errors.shape)
    report.singular_entries += int(np.count_nonzero(singular))
    report.singular_out_of_bound += int(np.count_nonzero(singular & (errors > bounds)))
    regular = np.where(singular, 0.0, errors)
    if np.any(~revolute):
        report.max_abs_error_mm = max(report.max_abs_error_mm, float(regular[:, ~revolute].max()))
    if np.any(revolute):
        report.max_abs_error_rad = max(report.max_abs_error_rad, float(regular[:, revolute].max()))
    differ = calls.warnings != expected.warnings
    excused = differ & warnings_in_band(robot, expected) & (calls.warnings != UNWRITTEN_WARNING)
    report.warning_mismatches += int(np.count_nonzero(differ & ~excused))
    report.warnings_in_band += int(np.count_nonzero(excused))
    none_reachable = np.all(expected.warnings == UNREACHABLE, axis=1)
    tally.returns_wrong += int(np.count_nonzero(calls.returned != np.where(none_reachable, 1, 0)))
    tally.guard_violations += calls.guard_violations
    tally.inputs_modified |= calls.inputs_modified
    if tally.first is None:
        keep = slice(0, DIAGNOSIS_POSES)
        tally.first = (t6[keep], calls.solutions[keep], calls.warnings[keep], expected.joints[keep],
                       expected.warnings[keep])


def _sample_checks(robot, plugin, report, tally):
    t6, solutions, warnings, reference_joints, reference_warnings = tally.first
    values_ok = (report.max_abs_error_mm <= VALUE_TOLERANCE_MM and report.max_abs_error_rad <= VALUE_TOLERANCE_RAD
                 and report.singular_out_of_bound == 0)
    values = Check("values", values_ok,
                   f"max |error| {report.max_abs_error_mm:.3g} mm, {report.max_abs_error_rad:.3g} rad over "
                   f"{report.samples} poses x {report.postures} postures; {report.singular_entries} entries in a "
                   f"singular band, {report.singular_out_of_bound} beyond their bound")
    if not values_ok:
        values.diagnoses = diagnose(robot, t6, solutions, reference_joints, reference_warnings)
    warnings_check = Check("warnings", report.warning_mismatches == 0,
                           f"{report.warning_mismatches} mismatches, {report.warnings_in_band} inside the tolerance band")
    if not warnings_check.passed:
        warnings_check.diagnoses = diagnose_warnings(warnings, reference_warnings, abi.WARNING_NAMES)
    checks = [values, warnings_check]
    checks.append(Check("return value", tally.returns_wrong == 0,
                        f"{tally.returns_wrong} calls return other than 1 when no posture is reachable, 0 otherwise"))
    checks.append(Check("buffers", tally.guard_violations == 0 and not tally.inputs_modified,
                        f"{tally.guard_violations} calls wrote outside solutions/warnings; inputs "
                        f"{'modified' if tally.inputs_modified else 'untouched'}"))
    plugin.reset_host()
    again = plugin.call_batch(t6[:DETERMINISM_POSES], report.link_lengths, report.link_offsets)
    same = (np.array_equal(again.solutions, solutions[:DETERMINISM_POSES], equal_nan=True)
            and np.array_equal(again.warnings, warnings[:DETERMINISM_POSES]))
    checks.append(Check("determinism", same, "the same T6 gives the same output" if same
                        else "calling again with the same T6 gives different output (state kept between calls?)"))
    return checks


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


def check_interface(robot, plugin):
    """The contract of shared/delmia-abi.md as named checks, each failure in one sentence."""
    config = plugin.config
    problems = []
    if (config.dof, config.solutions) != (robot.dof, robot.postures):
        problems.append(f"answers {config.dof} joints and {config.solutions} solutions; "
                        f"the robot has {robot.dof} and {robot.postures}")
    if config.data_hint not in (abi.CONSTANTS["USR_KIN_DATA_NULL"], abi.CONSTANTS["USR_KIN_DATA_KINSTAT"]):
        problems.append(f"answers an unknown data hint {config.data_hint}")
    if plugin.kin_config(plugin.routine + "_unknown").status == 0:
        problems.append(f"accepts a routine name that is not '{plugin.routine}'")
    checks = [Check("get_kin_config", not problems, "; ".join(problems) or
                    f"answers '{plugin.routine}' with {config.dof} joints, {config.solutions} solutions, "
                    f"hint {config.data_hint}; refuses other names")]
    home = t6_from_pose(np.asarray([robot.verification.home]))

    plugin.reset_host()
    plugin.call(home)
    calls, dof, solutions = host_state()
    expected = (1, plugin.dof, plugin.postures)
    checks.append(Check("kin_check_definition", (calls, dof, solutions) == expected,
                        f"called {calls} times, last with ({dof}, {solutions}); expected once with "
                        f"({plugin.dof}, {plugin.postures})"))

    plugin.reset_host(refuse=True)
    refused = plugin.call(home)
    plugin.reset_host()
    problems = []
    if refused.returned[0] != 1:
        problems.append(f"returns {refused.returned[0]}, not 1")
    if not (np.all(np.isnan(refused.solutions)) and np.all(refused.warnings == UNWRITTEN_WARNING)):
        problems.append("writes solutions or warnings")
    checks.append(Check("refusal", not problems, "when kin_check_definition refuses, the routine " +
                        (" and ".join(problems) if problems else "returns 1 and writes nothing")))

    problems = []
    for bad in (np.nan, np.inf):
        t6 = home.copy()
        t6[0, 3, 0] = bad
        result = plugin.call(t6)
        if not (result.returned[0] == 1 and np.all(np.isfinite(result.solutions))
                and np.all(result.warnings == abi.WARNINGS["WARN_UNREACHABLE"])):
            problems.append(f"a T6 holding {bad} gives return {result.returned[0]}, "
                            f"{'finite' if np.all(np.isfinite(result.solutions)) else 'non-finite'} joints, "
                            f"warnings {sorted(set(result.warnings[0].tolist()))}")
    checks.append(Check("non-finite T6", not problems, "; ".join(problems) or
                        "NaN and inf give return 1, finite joints, WARN_UNREACHABLE everywhere"))
    return checks


def junit_xml(report):
    """The report as JUnit XML: one test case per check."""
    suite = ElementTree.Element("testsuite", {
        "name": f"kingen verify {report.robot}", "tests": str(len(report.checks)),
        "failures": str(len(report.failures)), "time": f"{report.seconds:.6f}",
    })
    for check in report.checks:
        case = ElementTree.SubElement(suite, "testcase", {"classname": f"kingen.{report.robot}", "name": check.name})
        if not check.passed:
            failure = ElementTree.SubElement(case, "failure", {"message": check.detail})
            failure.text = "\n".join([check.detail, *check.diagnoses])
        else:
            ElementTree.SubElement(case, "system-out").text = check.detail
    if report.notices:
        ElementTree.SubElement(suite, "system-err").text = "\n".join(report.notices)
    return ElementTree.tostring(suite, encoding="unicode", xml_declaration=True) + "\n"
