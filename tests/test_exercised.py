"""verify says only what it checked: a check that judged nothing reads `not exercised` (text,
JSON status, JUnit skipped), never `ok`; values must have judged reachable poses, else verify
fails naming the cause; every check states how much it judged."""

import json
import xml.etree.ElementTree as ElementTree

import numpy as np
import pytest

from kingen.cli import main
from kingen.runtime.resources import robots_dir


def run(capsys, *argv):
    code = main([str(arg) for arg in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_a_region_outside_the_workspace_fails_instead_of_passing(tmp_path, capsys):
    path = tmp_path / "tau.yaml"
    path.write_text((robots_dir() / "tau.yaml").read_text().replace("home: [-1200, -750, -1900, 0, 0, 0]",
                                                                    "home: [9000, -750, -1900, 0, 0, 0]"))
    code, out, _ = run(capsys, "verify", path, "-o", tmp_path / "b", "--samples", "500", "--json", tmp_path / "r.json")
    assert code == 1
    assert ("FAILED values: no pose of the verification region is reachable at any posture: at least 10 needed to "
            "compare joints") in out
    assert "  jacobian: not exercised: no reachable, regular joint-posture among the 200 poses" in out
    assert "  ok     jacobian" not in out and "  ok     round trip" not in out
    checks = {check["name"]: check for check in json.loads((tmp_path / "r.json").read_text())["checks"]}
    assert checks["values"]["status"] == "FAILED" and checks["values"]["judged"] == 0
    assert checks["round trip"]["status"] == "not exercised" and checks["round trip"]["exercised"] is False


def test_a_robot_without_forward_kinematics_does_not_claim_a_round_trip(tmp_path, capsys):
    path = tmp_path / "legs.yaml"
    from conftest import THREE_LEGS

    path.write_text(THREE_LEGS)
    code, out, _ = run(capsys, "verify", path, "-o", tmp_path / "b", "--samples", "500",
                       "--junit", tmp_path / "r.xml", "--json", tmp_path / "r.json")
    assert code == 0 and "  round trip: not exercised: forward kinematics needs free pose coordinates" in out
    suite = ElementTree.parse(tmp_path / "r.xml").getroot()
    assert suite.get("skipped") == "1" and suite.get("failures") == "0"
    skipped = [case.get("name") for case in suite if case.find("skipped") is not None]
    assert skipped == ["round trip"]
    checks = {check["name"]: check for check in json.loads((tmp_path / "r.json").read_text())["checks"]}
    assert checks["values"]["judged"] == 500 and checks["warnings"]["judged"] == 500
    assert checks["jacobian"]["judged"] > 0 and checks["closure"]["judged"] == 3 * 500


class WithoutWarning:
    """A loaded routine that answers WARN_GOOD_SOLUTION wherever it should give ``code``."""

    def __init__(self, plugin, code):
        self._plugin, self._code = plugin, code

    def __getattr__(self, name):
        return getattr(self._plugin, name)

    def call(self, t6, *arguments, **keywords):
        calls = self._plugin.call(t6, *arguments, **keywords)
        calls.warnings[calls.warnings == self._code] = 0
        return calls


def cases():
    from conftest import SHIPPED
    from kingen.robot.model import load_robot
    from kingen.verify.boundaries import warnings_to_exercise

    return [(name, kind) for name in SHIPPED for kind in warnings_to_exercise(load_robot(name))]


@pytest.mark.parametrize("name, kind", cases())
def test_a_routine_that_never_gives_a_warning_fails_warnings(name, kind, plugin):
    """Every shipped robot, every warning it can give: the boundary poses make a routine that
    never gives it fail, even where the uniform sample holds no such pose."""
    from kingen.kinematics.routine import WARNINGS
    from kingen.verify import VerifyOptions, verify

    robot, routine = plugin(name)
    report = verify(robot, routine, VerifyOptions(samples=300))
    assert report.passed, [(check.name, check.detail) for check in report.failures]
    # A constrained machine of legs is unreachable only off its manifold: its sample's off-manifold
    # poses (one in eight) give the warning, with no boundary on the manifold to find.
    off_manifold_only = robot.task and kind == "WARN_UNREACHABLE" and not any(limb.has_radicand for limb in robot.limbs)
    assert off_manifold_only or report.boundary_poses["boundaries_found"][kind] > 0
    broken = verify(robot, WithoutWarning(routine, WARNINGS[kind]), VerifyOptions(samples=300))
    warnings = next(check for check in broken.checks if check.name == "warnings")
    assert not warnings.passed and not warnings.detail.startswith("0 mismatches"), warnings.detail


def threshold_robots():
    from conftest import SHIPPED
    from kingen.robot.model import load_robot

    return [name for name in SHIPPED if load_robot(name).direct_index_min is not None]


@pytest.mark.parametrize("name", threshold_robots())
def test_a_routine_without_the_direct_index_fails_warnings(name, tmp_path):
    """Every shipped robot with a direct-index threshold: a routine built from the same file
    without it (its limbs' singular band still gives WARN_SINGULAR_SOLUTION) fails warnings,
    CEART's included, whose threshold no ray from home meets and the descent finds."""
    from dataclasses import replace

    from kingen.hosts.delmia.build import build_plugin
    from kingen.hosts.delmia.loader import Plugin
    from kingen.robot.model import load_robot
    from kingen.verify import VerifyOptions, verify
    from kingen.verify.boundaries import threshold_boundaries

    robot = load_robot(name)
    built = build_plugin(replace(robot, direct_index_min=None), tmp_path)
    report = verify(robot, Plugin(built.library, built.routine), VerifyOptions(samples=300))
    warnings = next(check for check in report.checks if check.name == "warnings")
    assert threshold_boundaries(robot, report.boundary_poses["boundaries_found"]) > 0
    assert not warnings.passed and report.warning_mismatches > 0, warnings.detail
    said = " ".join(warnings.diagnoses)
    assert "WARN_GOOD_SOLUTION" in said and "WARN_SINGULAR_SOLUTION" in said, said


def test_a_threshold_the_search_does_not_meet_is_not_exercised_with_where_it_looked(plugin, monkeypatch):
    """Where neither the rays nor the descent meet the direct index's threshold, the warnings
    check says so with the search's region, method and how low it came, and passes on the
    warning's other cause (CEART's cranks' singular band); a descent of 3 steps stands for
    one that found nothing."""
    from kingen.verify import VerifyOptions, descent, verify

    monkeypatch.setattr(descent, "DESCENT_STEPS", 3)
    robot, routine = plugin("ceart")
    report = verify(robot, routine, VerifyOptions(samples=200))
    warnings = next(check for check in report.checks if check.name == "warnings")
    searched = report.boundary_poses["searched"]["direct_index_min"]
    assert report.boundary_poses["boundaries_found"]["direct_index_min"] == 0 and warnings.passed
    assert searched["steps"] == 3 and searched["crossed"] == 0 and searched["lowest"] > 0
    assert ("the direct-index threshold (direct_index_min 29.3 mm) not exercised: no compared posture's index is at "
            "or below it, no ray from the verification home met it, and a descent of its margin (16 chains, 16 at a "
            "time, over 3 steps from 256 seeds in home +- 4 x the verification range, and home +- 325.2 mm and +- 45 "
            f"degrees) came no lower than {searched['lowest']:.4g} mm above it") in warnings.detail


def test_a_snapshot_in_other_units_or_of_an_unknown_version_is_refused(tmp_path, capsys):
    snapshot = tmp_path / "tau.golden.json"
    assert main(["golden", "record", "tau", "-o", str(snapshot), "--samples", "5"]) == 0
    capsys.readouterr()
    data = json.loads(snapshot.read_text())
    for change, words in ((("joint_units", ["rad", "mm", "mm"]), ": joint_units: 'rad' for joint carriage1, which is in "
                                                                   "mm: a snapshot's units are the robot's"),
                          (("joint_units", ["mm"]), ": joint_units: 1 units for 3 joints"),
                          (("kingen_snapshot", 999), ": kingen_snapshot: version 999 is not one this kingen reads")):
        bad = tmp_path / "bad.json"
        bad.write_text(json.dumps({**data, change[0]: change[1]}))
        code, _, err = run(capsys, "verify", "tau", "--golden", bad, "-o", tmp_path / "b", "--samples", "50")
        assert code == 2 and words in err and err.count("\n") == 1, err


def test_a_misspelt_key_is_named_with_the_key_it_resembles(tmp_path, capsys):
    path = tmp_path / "robot.yaml"
    path.write_text((robots_dir() / "tau.yaml").read_text().replace("verification:", "verificaton:"))
    code, _, err = run(capsys, "verify", path)
    assert code == 2 and err == f"kingen: error: {path}:19: verificaton: unknown key 'verificaton' (did you mean " \
                                "'verification'?)\n"


def test_one_posture_is_one_posture(tmp_path, capsys):
    code, out, _ = run(capsys, "verify", "hexapod", "-o", tmp_path / "b", "--samples", "50")
    assert code == 0 and out.startswith("verify hexapod: 50 poses x 1 posture, ")


def test_bad_host_settings_are_one_line_errors(tmp_path, capsys):
    from conftest import require_linuxcnc_headers

    require_linuxcnc_headers()  # the last setting is refused only once the module is built
    for argv, words in ((["--setp", "x"], "'x': give NAME=VALUE with a number"),
                        (["--setp", "a=nan"], "'a=nan': give NAME=VALUE with a finite number"),
                        (["--units", "furlong"], "Invalid value for '--units'"),
                        (["--setp", "hexapodkins.no-such-pin=1"],
                         "--setp hexapodkins.no-such-pin: the module has no such pin or parameter")):
        code, _, err = run(capsys, "verify", "hexapod", "--host", "linuxcnc", "-o", tmp_path / "b", "--samples", "50",
                           *argv)
        assert code == 2 and words in err and err.count("\n") == 1, err
        assert "Traceback" not in err
    code, _, err = run(capsys, "build", "hexapod", "--units", "inch", "-o", tmp_path / "d")
    assert code == 2 and err == "kingen: error: --units: host delmia takes no such setting\n"


def test_a_library_kingen_did_not_build_has_its_definition_not_exercised(tmp_path, capsys):
    from kingen.robot.model import load_robot
    from kingen.hosts import get_host
    from kingen.verify import VerifyOptions, verify_library

    from conftest import require_file

    require_file("/usr/lib/linuxcnc/modules/lineardeltakins.so", "linuxcnc-uspace")
    host = get_host("linuxcnc")
    robot = host.as_seen(load_robot("linear_delta"))
    report = verify_library(robot, "/usr/lib/linuxcnc/modules/lineardeltakins.so", "lineardeltakins",
                            VerifyOptions(samples=200), host=host)
    definition = report.checks[0]
    assert definition.name == "definition" and definition.status == "not exercised" and definition.passed


@pytest.mark.parametrize("levels", [1, 2, 3, 5])
def test_halvings_decided_together_give_the_brackets_of_one_at_a_time(levels):
    """boundaries._bisected against plain bisection (one midpoint per step) on brackets with
    several crossings (a predicate that is not monotone), so that a 'first crossing' search
    would differ: the same brackets, bit for bit."""
    from kingen.verify.boundaries import _bisected

    rng = np.random.default_rng(levels)
    low = rng.uniform(0.0, 0.9, size=40)
    high = low + rng.uniform(1e-9, 0.1, size=40)
    frequency = rng.uniform(50.0, 5000.0, size=40)

    def beyond(fractions, rays):
        return np.sin(frequency[rays] * fractions) > 0.0

    calls = []

    def inside(fractions):
        calls.append(len(fractions))
        return beyond(fractions, np.tile(np.arange(40), len(fractions) // 40)).reshape(-1, 40)

    one_low, one_high = low, high
    for _ in range(levels):
        middle = 0.5 * (one_low + one_high)
        past = beyond(middle, np.arange(40))
        one_high, one_low = np.where(past, middle, one_high), np.where(past, one_low, middle)
    together_low, together_high = _bisected(low, high, levels, inside)
    assert calls == [40 * ((1 << levels) - 1)]
    np.testing.assert_array_equal(together_low, one_low)
    np.testing.assert_array_equal(together_high, one_high)


@pytest.mark.parametrize("kind", ["WARN_JOINT_LIMITS_EXCEEDED", "WARN_UNREACHABLE", "WARN_SINGULAR_SOLUTION"])
def test_the_descent_steps_across_each_kind_of_boundary(kind):
    """kingen.verify.descent on the Gantry-Tau (travel limits, and rails' unreachable poses and
    singular band): each segment it returns starts where the reference's posture is on the
    good side of ``kind`` and ends where some posture is beyond it, as bisection needs."""
    from kingen.conventions import t6_from_pose
    from kingen.kinematics.reference import solve
    from kingen.kinematics.routine import WARNINGS
    from kingen.robot.model import load_robot
    from kingen.verify.boundaries import PAST
    from kingen.verify.descent import descend

    robot = load_robot("tau")
    region = robot.verification
    origins, directions, search = descend(robot, kind, np.array(region.home, dtype=float),
                                          np.array(region.range, dtype=float), 4.0, np.random.default_rng(0))
    assert search.crossed == len(origins) > 0 and search.lowest <= 0.0 and 0 < search.steps <= 400
    beyond = [WARNINGS[name] for name in PAST[kind]]
    before, after = (solve(robot, t6_from_pose(poses)).warnings for poses in (origins, origins + directions))
    assert np.all(np.any(~np.isin(before, beyond), axis=1)) and np.all(np.any(np.isin(after, beyond), axis=1))
