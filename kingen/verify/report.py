"""The outcome of a verification and its two file forms: JSON (the CLI's ``--json``)
and JUnit XML (``--junit``). Both are always well-formed: non-finite numbers are written
as JSON null, and text is stripped of what XML 1.0 cannot hold."""

import json
import math
import xml.etree.ElementTree as ElementTree
from dataclasses import asdict, dataclass, field
from typing import Dict, List, Optional, Tuple, Union

from ..runtime.text import counted, xml_text


@dataclass
class Check:
    """One clause of the contract: its name, verdict, the evidence, and diagnoses when it failed.

    ``exercised`` is False for a check that judged nothing (no case it applies to was met): it
    then reads ``not exercised``, never ``ok``, and fails nothing; checks that must be
    exercised fail instead. ``judged`` counts what it judged (poses, postures, calls), or None
    where no count applies."""

    name: str
    passed: bool
    detail: str = ""
    diagnoses: List[str] = field(default_factory=list)
    exercised: bool = True
    judged: Optional[int] = None

    @property
    def status(self):
        """'ok', 'FAILED' or 'not exercised'."""
        if not self.passed:
            return "FAILED"
        return "ok" if self.exercised else "not exercised"


def not_exercised(name, why):
    """A check that judged nothing, saying why."""
    return Check(name, True, why, exercised=False, judged=0)


@dataclass
class GoldenResult:
    """One golden value: published joints against the plugin's and the reference's (YAML units)."""

    source: str
    pose: List[float]
    posture: int
    expected: List[float]
    plugin: List[float]
    reference: List[float]
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
    golden: List[GoldenResult] = field(default_factory=list)
    checks: List[Check] = field(default_factory=list)
    notices: List[str] = field(default_factory=list)
    seconds: float = 0.0
    processes: int = 1
    """How many processes compared the sampled poses (``seconds`` is their wall time)."""
    tolerance_mm: float = 1e-9
    """The bound on prismatic joints: 1e-9 mm, or relative to the robot's size for large robots."""
    tolerance_rad: float = 1e-9
    boundary_poses: Dict[str, Union[int, Dict[str, int], Dict[str, Dict[str, Union[int, float, str]]]]] = field(
        default_factory=dict)
    """{poses: how many poses on warnings' boundaries joined the sample, boundaries_found:
    {warning, or direct_index_min for the direct index's threshold: boundaries found},
    searched: {boundary the rays missed: the descent that sought it (kingen.verify.descent.Descent's
    fields)}} (kingen.verify.boundaries)."""
    interface_checks: Tuple[str, ...] = ()
    """Names of the host's interface checks (their failures are listed as ``interface_failures``)."""
    posture_statistics: List[Dict[str, Union[int, float, None]]] = field(default_factory=list)
    """Per posture: {posture, right, wrong, unreachable_wrongly, missed, worst_error_mm,
    worst_error_rad}: poses solved right, solved wrong (joints beyond their bound), reported
    unreachable where the reference solves them, and solved where the reference finds none."""
    isolation: str = ""
    """What the routine ran in (kingen.runtime.sandbox.description), as kingen's own process
    was told by the sandbox's keeper; empty for a routine verified in the calling process."""

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

    def as_json(self, options=None):
        """The report as JSON-ready data, with the calibration fields it was run with (``options``,
        a VerifyOptions); NaN and infinities become None (JSON null)."""
        return _finite({
            "robot": self.robot,
            "routine": self.routine,
            "samples": self.samples,
            "seed": self.seed,
            "postures": self.postures,
            "link_lengths": _listed(getattr(options, "link_lengths", None)),
            "link_offsets": _listed(getattr(options, "link_offsets", None)),
            "max_abs_error_mm": self.max_abs_error_mm,
            "max_abs_error_rad": self.max_abs_error_rad,
            "tolerance_mm": self.tolerance_mm,
            "tolerance_rad": self.tolerance_rad,
            "singular_entries": self.singular_entries,
            "singular_out_of_bound": self.singular_out_of_bound,
            "warning_mismatches": self.warning_mismatches,
            "warnings_in_band": self.warnings_in_band,
            "golden_checked": self.golden_checked,
            "golden_failed": self.golden_failed,
            "golden": [asdict(result) for result in self.golden],
            "posture_statistics": self.posture_statistics,
            "boundary_poses": self.boundary_poses,
            "checks": [{**asdict(check), "status": check.status} for check in self.checks],
            "interface_failures": [check.detail for check in self.failures if check.name in self.interface_checks],
            "diagnoses": [text for check in self.checks for text in check.diagnoses],
            "notices": list(self.notices),
            "seconds": round(self.seconds, 6),
            "poses_per_second": self.poses_per_second,
            "processes": self.processes,
            "isolation": self.isolation,
            "passed": self.passed,
        })


def _finite(data):
    if isinstance(data, float):
        return data if math.isfinite(data) else None
    if isinstance(data, dict):
        return {key: _finite(value) for key, value in data.items()}
    if isinstance(data, (list, tuple)):
        return [_finite(value) for value in data]
    return data


def _listed(values):
    return None if values is None else [float(v) for v in values]


def json_text(report, options=None):
    """The report as JSON text (strict: no NaN or Infinity literals)."""
    return json.dumps(report.as_json(options), indent=2, allow_nan=False) + "\n"


def junit_xml(report):
    """The report as JUnit XML: one test case per check."""
    suite = ElementTree.Element("testsuite", {
        "name": f"kingen verify {report.robot}", "tests": str(len(report.checks)),
        "failures": str(len(report.failures)),
        "skipped": str(sum(1 for check in report.checks if check.passed and not check.exercised)),
        "time": f"{report.seconds:.6f}",
    })
    for check in report.checks:
        case = ElementTree.SubElement(suite, "testcase", {"classname": f"kingen.{report.robot}", "name": check.name})
        if not check.passed:
            failure = ElementTree.SubElement(case, "failure", {"message": xml_text(check.detail)})
            failure.text = xml_text("\n".join([check.detail, *check.diagnoses]))
        elif not check.exercised:
            ElementTree.SubElement(case, "skipped", {"message": xml_text(check.detail)})
        else:
            ElementTree.SubElement(case, "system-out").text = xml_text(check.detail)
    if report.notices:
        ElementTree.SubElement(suite, "system-err").text = xml_text("\n".join(report.notices))
    return ElementTree.tostring(suite, encoding="unicode", xml_declaration=True) + "\n"


def statistics_lines(report, most=8):
    """The per-posture solution statistics as text lines: every posture for robots with at
    most ``most`` postures, else the totals and the ``most`` postures with the most failures."""
    rows = report.posture_statistics
    if not rows:
        return []
    failures = lambda row: row["wrong"] + row["unreachable_wrongly"] + row["missed"]  # noqa: E731
    shown = rows if len(rows) <= most else sorted(rows, key=lambda row: -failures(row))[:most]
    shown = [row for row in shown if len(rows) <= most or failures(row)]
    total = {key: sum(row[key] for row in rows) for key in ("right", "wrong", "unreachable_wrongly", "missed")}
    lines = [f"solutions per posture: right / wrong / unreachable wrongly / missed, worst error "
             f"({'all ' if len(rows) != 1 else ''}{counted(len(rows), 'posture')}: {total['right']} / {total['wrong']} / {total['unreachable_wrongly']} / "
             f"{total['missed']})"]
    for row in shown:
        worst = ", ".join(f"{row[key]:.3g} {unit}" for key, unit in (("worst_error_mm", "mm"), ("worst_error_rad", "rad"))
                          if row[key] is not None)
        lines.append(f"posture {row['posture']}: {row['right']} / {row['wrong']} / {row['unreachable_wrongly']} / "
                     f"{row['missed']}, worst {worst or '-'}")
    return lines
