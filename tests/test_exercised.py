"""verify says only what it checked: a check that judged nothing reads `not exercised` (text,
JSON status, JUnit skipped), never `ok`; values must have judged reachable poses, else verify
fails naming the cause; every check states how much it judged."""

import json
import xml.etree.ElementTree as ElementTree

from kingen.cli import main
from kingen.resources import robots_dir


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
    path.write_text("name: legs\ndescription: Three legs, no forward coordinates.\nlimbs:\n"
                    + "".join(f"  - {{model: leg, base_point: [{x}, {y}, 0], platform_point: [0, 0, 0], "
                              f"reference_length: 100}}\n" for x, y in ((100, 0), (-50, 87), (-50, -87)))
                    + "verification: {home: [0, 0, 120, 0, 0, 0], range: [10, 10, 10, 0, 0, 0]}\n")
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
