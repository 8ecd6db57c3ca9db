"""Untrusted input: robot files, options, environments and file-system states that once
ended in a traceback, ran code, hung or wrote the wrong thing. Each now ends in exit 0,
1 or 2 with one located line, within its limits, leaving no partial output."""

import contextlib
import json
import os
import socket
import stat
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ElementTree

import numpy as np
import pytest

from kingen.runtime.compiler import first_diagnostic
from kingen.runtime.files import cache_dir
from kingen.hosts.delmia.build import build_plugin, host_support
from kingen.cli import main
from kingen.errors import KingenError
from kingen.robot.model import load_robot, robots_dir
from kingen.hosts.delmia.pe import dll_exports
from kingen.verify.report import Check, Report, json_text, junit_xml
from kingen.kinematics.poses import PoseStream, pose_chunks, sample_poses

LEG = """\
name: NAME
description: DESCRIPTION
limbs:
  - {model: leg, base_point: [0, 0, 0], platform_point: [0, 0, 0], reference_length: 100}
verification: {home: [0, 0, 150, 0, 0, 0], range: [20, 20, 20, 10, 10, 10]}
"""


def leg_file(tmp_path, name="probe", description="A probe.", file_name="probe.yaml"):
    path = tmp_path / file_name
    path.write_text(LEG.replace("NAME", name).replace("DESCRIPTION", json.dumps(description)))
    return path


def run(capsys, *argv):
    code = main([str(arg) for arg in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def one_error_line(err):
    return err.count("\n") == 1 and err.startswith("kingen: error: ")


# --- item 1 and 2: free text cannot change the meaning of generated text

INJECTION = ('x */ __attribute__((constructor)) static void k(void) { FILE *f = fopen("INJECTED", "w"); } /* '
             "and /* again ??/ \\ trailing ??/")


def test_a_description_cannot_inject_code_into_the_plugin(capsys, tmp_path):
    path = leg_file(tmp_path, description=INJECTION)
    code, out, _ = run(capsys, "verify", path, "-o", tmp_path / "b", "--samples", "100")
    assert code == 0 and "PASSED" in out
    assert not (tmp_path / "INJECTED").exists() and not os.path.exists("INJECTED")
    source = (tmp_path / "b" / "kin_probe.c").read_text()
    banner = source[:source.index("*/")]
    assert "__attribute__((constructor))" in banner  # the text is kept, inside the comment
    assert "??" not in source and "\\" not in banner


@pytest.mark.parametrize("character", ["\x1b", "\u202e", "\u2066", "\x00", "\x85", "\u200b"])
def test_control_and_bidi_characters_are_refused_in_robot_files(tmp_path, character):
    path = leg_file(tmp_path, description=f"looks harmless{character}")
    with pytest.raises(KingenError, match=rf":2: description: contains the invisible or control character "
                                          rf"U\+{ord(character):04X}"):
        load_robot(path)


def test_a_file_name_cannot_add_make_targets_or_lines(tmp_path):
    path = leg_file(tmp_path, file_name="evil\n\tall:\n\t\tdel *.c\n.yaml")
    robot = load_robot(path)
    from kingen.hosts.delmia.package import render_package
    plain = render_package(load_robot(leg_file(tmp_path)), "windows")
    for name, text in render_package(robot, "windows").items():
        assert len(text.splitlines()) == len(plain[name].splitlines()), name
        assert "\tdel" not in text
    assert "evil<U+000A>" not in render_package(robot, "windows")["makefile"]  # whitespace runs became spaces
    assert "evil all: del \\*.c .yaml" in render_package(robot, "windows")["SETUP.md"]


def test_markdown_in_a_description_is_shown_not_interpreted(tmp_path):
    robot = load_robot(leg_file(tmp_path, description="# Title <script>alert(1)</script> | [x](y)"))
    from kingen.hosts.delmia.package import render_package
    sheet = render_package(robot, "windows")["SETUP.md"]
    assert "\\# Title \\<script\\>alert(1)\\</script\\> \\| \\[x\\](y)" in sheet


# --- items 3, 4, 17: YAML that is expensive, ambiguous or huge

BOMB = "a: &a [1,1,1,1,1,1,1,1,1,1]\n" + "".join(
    f"{c}: &{c} [" + ",".join([f"*{p}"] * 10) + "]\n" for p, c in zip("abcdefgh", "bcdefghi"))


@pytest.mark.parametrize("text, words", [
    (BOMB, "expands to more than 100000 values"),
    ("limbs: &a [*a]\n", ":1: alias *a refers to a collection that contains it"),
    ("a: " + "[" * 5000, ":1: nested deeper than 32 levels"),
    ("a:\n" + "- " * 5000 + "1\n", "nested deeper than 32 levels"),
    ("a: 1\n'a': 2\n", ":2: a: duplicate key"),
    ("1: 1\n'1': 2\n", ":1: key 1 is not a field name"),
    ("a: !foo 3\n", ":1: a: YAML tag !foo is not supported"),
    ("a: 2001-12-14\n", ":1: a: expected a number, text, list or mapping"),
    ("a: 1\n---\nb: 2\n", ":2: YAML syntax: but found another document"),
    ("a: " + "9" * 5000 + "\n", "YAML syntax: a number with thousands of digits"),
])
def test_yaml_limits_are_clear_errors_within_a_second(tmp_path, text, words):
    import time
    path = tmp_path / "x.yaml"
    path.write_text(text)
    start = time.monotonic()
    with pytest.raises(KingenError) as raised:
        load_robot(path)
    assert words in str(raised.value) and "\n" not in str(raised.value)
    assert time.monotonic() - start < 1.0


def test_a_file_over_one_megabyte_is_refused_unread(tmp_path):
    path = tmp_path / "big.yaml"
    path.write_text("description: " + "x" * 2_000_000 + "\n")
    with pytest.raises(KingenError, match="larger than 1000 kB"):
        load_robot(path)


def test_long_text_is_refused(tmp_path):
    with pytest.raises(KingenError, match=":2: description: text longer than 4000 characters"):
        load_robot(leg_file(tmp_path, description="x" * 5000))


def test_numbers_mean_what_an_engineer_typed(tmp_path):
    original = (robots_dir() / "hexapod.yaml").read_text()
    path = tmp_path / "hexapod.yaml"
    path.write_text(original.replace("399.413", "3.99413e2").replace("[31,", "[031,", 1))
    robot = load_robot(path)
    assert robot.limbs[0].reference_length == 399.413
    assert 31.0 in robot.limbs[0].base_point
    path.write_text(original.replace("399.413", "6:39"))
    with pytest.raises(KingenError, match="reference_length: Input should be a valid number"):
        load_robot(path)


# --- item 14: names

@pytest.mark.parametrize("name, good", [("int", True), ("check_definition", False), ("routine", False),
                                        ("dof", False), ("while", True)])
def test_final_c_names_are_checked_not_the_robot_name(capsys, tmp_path, name, good):
    code, out, err = run(capsys, "build", leg_file(tmp_path, name=name), "-o", tmp_path / "b")
    if good:
        assert code == 0 and f"routine kin_{name}" in out
    else:
        assert code == 2 and one_error_line(err) and f"gives the C name 'kin_{name}'" in err


# --- items 8, 13, 15: options, reports and messages

@pytest.mark.parametrize("argv, words", [
    (["solve", "tau", "--pose", "0", "0", "0", "0", "0", "0", "--link-lengths", "1e200", "0", "0", "0", "0", "0"],
     "--link-lengths"),
    (["verify", "tau", "--seed", "-1"], "--seed"),
    (["bench", "tau", "--calls", "1000000000"], "--calls"),
    (["verify", "tau", "--plugin", "x.so", "--routine", "a b"], "routine name 'a b' is not a C identifier"),
    (["verify", "tau", "--plugin", "x.so", "--routine", "1abc"], "routine name '1abc' is not a C identifier"),
    (["verify", "tau", "--json", "missing_dir/x.json"], "folder missing_dir does not exist"),
    (["verify", "tau", "--junit", "."], "--junit"),
    (["verify", "tau", "--timeout", "0"], "--timeout"),
    # NaN passes click's FloatRange: every number option refuses it by name
    (["analyze", "tau", "--tilt-step", "nan"], "Invalid value for '--tilt-step': 'nan' is not a finite number"),
    (["analyze", "tau", "--azimuth-step", "nan"], "Invalid value for '--azimuth-step': 'nan' is not a finite number"),
    (["analyze", "tau", "--tilt-max", "nan"], "Invalid value for '--tilt-max': 'nan' is not a finite number"),
    (["analyze", "tau", "--tilt-max", "-nan"], "Invalid value for '--tilt-max': '-nan' is not a finite number"),
    (["verify", "tau", "--timeout", "nan"], "Invalid value for '--timeout' (env var: 'KINGEN_TIMEOUT'): 'nan' is not a"),
    (["build", "tau", "--timeout", "NaN"], "Invalid value for '--timeout' (env var: 'KINGEN_TIMEOUT'): 'NaN' is not a"),
])
def test_bad_options_are_usage_errors(capsys, tmp_path, monkeypatch, argv, words):
    """Refused before any work: one line naming the option, nothing printed or built."""
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, *argv)
    assert code == 2 and one_error_line(err) and words in err and out == "", err
    assert not (tmp_path / "build").exists()


def test_nan_from_the_environment_is_refused_naming_the_variable(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("KINGEN_TIMEOUT", "nan")
    code, _, err = run(capsys, "build", "tau", "-o", tmp_path / "b")
    assert code == 2 and one_error_line(err)
    assert "'--timeout' (env var: 'KINGEN_TIMEOUT'): 'nan' is not a finite number" in err
    assert not (tmp_path / "b").exists()


@pytest.mark.parametrize("width", ["nan", "-nan"])
def test_fk_refuses_a_search_width_that_is_not_a_finite_number(capsys, width):
    # A NaN width made a NaN region: exit 0 with one assembly mode where the search finds six.
    code, out, err = run(capsys, "fk", "exechon", "--joints", "400 400 400", "--search", width)
    assert code == 2 and one_error_line(err) and out == ""
    assert "Invalid value for '--search'" in err


def optimize_file(tmp_path, objective="{}", bounds="[100, 200]"):
    """A leg robot (one posture) with an optimize: section; optimize: is line 6, its variable line 8,
    its objective line 9."""
    path = tmp_path / "probe.yaml"
    path.write_text(LEG.replace("NAME", "probe").replace("DESCRIPTION", "A probe.")
                    + f"optimize:\n  variables:\n    - {{field: height, bounds: {bounds}}}\n"
                      f"  objective: {objective}\n")
    return path


@pytest.mark.parametrize("objective, bounds, words", [
    ("{tilt_step: 1e-9}", "[100, 200]",
     ":9: optimize.objective.tilt_step: Input should be greater than or equal to 0.001 (got 1e-09)"),
    ("{tilt_max: 0.05}", "[100, 200]",
     ":9: optimize.objective.tilt_max: Input should be greater than or equal to 0.1 (got 0.05)"),
    ("{posture: 1000000}", "[100, 200]",
     ":9: optimize.objective.posture: posture 1000000 does not exist (the robot has 1)"),
    ("{posture: 1}", "[100, 200]", ":9: optimize.objective.posture: posture 1 does not exist (the robot has 1)"),
    ("{}", "[100, 1e308]", ":8: optimize.variables[0].bounds[1]: Input should be less than or equal to 1000000"),
    ("{}", "[-1e7, 200]", ":8: optimize.variables[0].bounds[0]: Input should be greater than or equal to -1000000"),
])
def test_an_optimize_section_has_the_command_lines_bounds(capsys, tmp_path, objective, bounds, words):
    path = optimize_file(tmp_path, objective, bounds)
    with pytest.raises(KingenError) as raised:
        load_robot(path)  # every command refuses it, not only optimize
    assert str(raised.value).startswith(f"{path}{words}")
    code, _, err = run(capsys, "optimize", path, "-o", tmp_path / "o")
    assert code == 2 and one_error_line(err) and f"{path}{words}" in err
    assert not (tmp_path / "o").exists()


def test_optimize_refuses_an_output_folder_that_is_a_dangling_link_before_the_search(capsys, tmp_path):
    (tmp_path / "o").symlink_to(tmp_path / "nowhere" / "o")
    code, out, err = run(capsys, "optimize", optimize_file(tmp_path), "-o", tmp_path / "o")
    assert code == 2 and one_error_line(err) and out == ""
    assert f"{tmp_path / 'o'} is a symbolic link to {tmp_path / 'nowhere' / 'o'}, which does not exist" in err
    assert not (tmp_path / "nowhere").exists() and not list(tmp_path.glob(".o*"))


@pytest.mark.parametrize("value, words", [(" ", "$CC holds no command"), ('"x', "$CC: cannot be split")])
def test_unusable_compiler_variables_are_bad_input(capsys, tmp_path, monkeypatch, value, words):
    monkeypatch.setenv("KINGEN_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("CC", value)
    code, _, err = run(capsys, "build", "tau", "-o", tmp_path / "b")
    assert code == 2 and one_error_line(err) and words in err


def test_a_hanging_compiler_is_killed(capsys, tmp_path, monkeypatch):
    compiler = tmp_path / "slowcc"
    compiler.write_text("#!/bin/sh\nsleep 60\n")
    compiler.chmod(0o755)
    monkeypatch.setenv("KINGEN_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("CC", str(compiler))
    code, _, err = run(capsys, "build", "tau", "-o", tmp_path / "b", "--timeout", "1")
    assert code == 2 and "compiler did not finish in 1 s" in err
    assert not (tmp_path / "b").exists() or not [p for p in (tmp_path / "b").iterdir()]


def test_a_source_including_dev_zero_ends_in_a_compiler_error(capsys, tmp_path, monkeypatch):
    # The compiler's address-space limit ends it; at 1 GiB rather than the product's 4 GiB,
    # so that the kernel hands out (and takes back) a quarter of the pages.
    monkeypatch.setattr("kingen.runtime.compiler.COMPILER_MEMORY", 1 << 30)
    source = tmp_path / "kin_zero.c"
    source.write_text('#include "/dev/zero"\n')
    code, _, err = run(capsys, "verify", "hexapod", "--source", source, "-o", tmp_path / "b", "--timeout", "60")
    assert code == 2 and one_error_line(err) and "does not compile" in err


def test_compile_errors_name_the_kept_source(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("KINGEN_CACHE", str(tmp_path / "cache"))
    host_support()
    monkeypatch.setenv("CC", "gcc -DNUM_DOFS=oops")
    code, _, err = run(capsys, "build", "tau", "-o", tmp_path / "b")
    assert code == 2 and one_error_line(err)
    where = err.split("does not compile: ")[1].split(":")[0]
    assert where == str(tmp_path / "b" / "kin_tau.c") and os.path.isfile(where)
    assert not (tmp_path / "b" / "libtau.so").exists()


def test_the_first_error_is_an_error_not_a_file_name_or_warning():
    stderr = ("In file included from /home/error_handling/kin_x.c:1:\n"
              "kin_x.c:3:2: warning: #warning this is an error-prone file [-Wcpp]\n"
              "kin_x.c:9:5: error: expected ';' before '}' token\n")
    assert first_diagnostic(stderr) == "kin_x.c:9:5: error: expected ';' before '}' token"
    assert first_diagnostic("kin_x.c:9: error: ';' expected (got \"}\")\n") == \
        "kin_x.c:9: error: ';' expected (got \"}\")"


def test_terminal_output_escapes_control_characters(capsys, tmp_path):
    path = tmp_path / "x.yaml"
    path.write_text("name: probe\n\"\\e[31mred\": 1\n")
    code, _, err = run(capsys, "render", path)
    assert code == 2 and "\x1b" not in err and ":2: contains the invisible or control character U+001B" in err
    code, _, err = run(capsys, "render", tmp_path / "\x1b[31mred.yaml")
    assert code == 2 and "\x1b" not in err and "<U+001B>[31mred.yaml: no such robot file" in err


def test_an_empty_home_does_not_put_the_cache_at_the_root(monkeypatch):
    monkeypatch.delenv("KINGEN_CACHE", raising=False)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setenv("HOME", "")
    assert cache_dir() != cache_dir().parent.parent / ".cache" or str(cache_dir()) != "/.cache/kingen"
    assert str(cache_dir()) != "/.cache/kingen" and cache_dir().is_absolute()


def test_report_files_are_always_well_formed(tmp_path):
    report = Report(robot="r", routine="kin_r", samples=0, seed=0, postures=1, max_abs_error_mm=float("nan"),
                    max_abs_error_rad=float("inf"))
    report.checks.append(Check("values", False, "printed 'x\x1b[31m\x00y'", ["bad \x07 bell"]))
    data = json.loads(json_text(report))
    assert data["max_abs_error_mm"] is None and data["max_abs_error_rad"] is None
    assert data["poses_per_second"] is None
    root = ElementTree.fromstring(junit_xml(report).split("?>", 1)[1])
    assert "<U+001B>[31m<U+0000>y" in root.find("testcase/failure").get("message")


def test_std_streams_closed_or_cut_short_keep_the_exit_code(tmp_path):
    command = [sys.executable, "-m", "kingen.cli", "verify", "tau", "--samples", "2000", "-o", str(tmp_path / "b")]
    closed = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            stdin=subprocess.DEVNULL, close_fds=True, preexec_fn=lambda: os.close(1))
    assert closed.returncode == 0 and closed.stderr == ""
    piped = subprocess.run(" ".join(command) + " | head -1; exit ${PIPESTATUS[0]}", shell=True,
                           executable="/bin/bash", capture_output=True, text=True)
    assert piped.returncode == 0 and piped.stdout.startswith("verify tau") and piped.stderr == ""


def test_internal_errors_exit_3_with_one_line(capsys, monkeypatch):
    import kingen.robot.model
    monkeypatch.setattr(kingen.robot.model, "shipped_robots", lambda: 1 / 0)
    monkeypatch.delenv("KINGEN_DEBUG", raising=False)
    code, _, err = run(capsys, "list")
    assert code == 3 and err.count("\n") == 1
    assert err.startswith("kingen: internal error: ZeroDivisionError: division by zero at ") and "please report" in err


@pytest.mark.parametrize("mutation", [b"", b"MZ", b"MZ" + b"\0" * 58 + b"\x40\0\0\0PE\0\0" + b"\0" * 20 + b"\x99\x99",
                                      b"MZ" + b"\xff" * 200])
def test_a_malformed_dll_is_a_clear_error(tmp_path, mutation):
    path = tmp_path / "x.dll"
    path.write_bytes(mutation)
    with pytest.raises(KingenError, match="not a readable Windows DLL"):
        dll_exports(path)


# --- items 9, 10, 11, 12: memory, permissions, stale outputs, whole folders

def test_poses_drawn_chunk_by_chunk_are_the_same_bit_for_bit():
    robot = load_robot("ceart")
    whole = sample_poses(robot, 10007, seed=3)
    for chunk in (1, 1000, 4096):
        assert np.array_equal(np.concatenate([p for _, p in pose_chunks(robot, 10007, 3, chunk)]), whole)


def test_skipped_poses_leave_the_others_the_same_bit_for_bit():
    """Each comparing process skips the chunks of the others: the generator moves past them
    without drawing, and the poses after them must not change."""
    robot = load_robot("tau")
    whole = sample_poses(robot, 10007, seed=5)
    stream = PoseStream(robot, 5)
    stream.skip(1)
    assert np.array_equal(stream.draw(999), whole[1:1000])
    stream.skip(5000)
    assert np.array_equal(stream.draw(4007), whole[6000:])


def test_outputs_get_the_users_umask_permissions(capsys, tmp_path):
    old = os.umask(0o022)
    try:
        assert run(capsys, "build", "tau", "-o", tmp_path / "b")[0] == 0
        assert run(capsys, "package", "tau", "-o", tmp_path / "kit")[0] == 0
        assert run(capsys, "package", "tau", "--target", "linux", "-o", tmp_path / "kit-linux")[0] == 0
        assert run(capsys, "verify", "tau", "-o", tmp_path / "b", "--samples", "100",
                   "--json", tmp_path / "r.json")[0] == 0
    finally:
        os.umask(old)
    mode = lambda path: stat.S_IMODE(path.stat().st_mode)  # noqa: E731
    assert mode(tmp_path / "b" / "libtau.so") == 0o755
    assert mode(tmp_path / "b" / "kin_tau.c") == 0o644 and mode(tmp_path / "r.json") == 0o644
    assert mode(tmp_path / "kit") == 0o755 and mode(tmp_path / "kit" / "SETUP.md") == 0o644
    assert mode(tmp_path / "kit-linux" / "libtau.so") == 0o755
    include, library = host_support()  # kingen runs code from its cache: that stays the user's alone
    assert mode(library) & 0o700 == 0o700 and not mode(library) & 0o077
    assert mode(include / "shlibdefs.h") & 0o600 == 0o600 and not mode(include / "shlibdefs.h") & 0o077


def test_an_emptied_library_is_rebuilt_not_trusted(capsys, tmp_path):
    assert run(capsys, "build", "tau", "-o", tmp_path)[0] == 0
    (tmp_path / "libtau.so").write_bytes(b"")
    code, out, _ = run(capsys, "build", "tau", "-o", tmp_path)
    assert code == 0 and "(compiled;" in out and (tmp_path / "libtau.so").stat().st_size > 0


def test_a_junk_host_library_in_the_cache_is_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("KINGEN_CACHE", str(tmp_path / "cache"))
    _, library = host_support()
    library.write_bytes(b"junk")
    _, again = host_support()
    assert again == library and again.read_bytes()[:4] == b"\x7fELF"


def test_package_is_written_whole_and_never_over_foreign_folders(capsys, tmp_path):
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("keep me")
    code, _, err = run(capsys, "package", "tau", "-o", foreign)
    assert code == 2 and "exists and is not a kingen package folder" in err
    assert [p.name for p in foreign.iterdir()] == ["notes.txt"]
    kit = tmp_path / "kit"
    assert run(capsys, "package", "tau", "-o", kit)[0] == 0
    (kit / "stale.txt").write_text("from an older package")
    assert run(capsys, "package", "tau", "-o", kit)[0] == 0
    assert not (kit / "stale.txt").exists() and (kit / "SETUP.md").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kit", "mine"]


def test_a_failed_package_leaves_nothing(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("KINGEN_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("CC", "no-such-compiler-kingen")
    code, _, _ = run(capsys, "package", "tau", "--target", "linux", "-o", tmp_path / "kit")
    assert code == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cache"]


# --- item 16: geometry range and size-relative bound

def test_geometry_outside_the_stated_range_is_refused(tmp_path):
    path = leg_file(tmp_path)
    path.write_text(path.read_text().replace("reference_length: 100", "reference_length: 1.0e+8"))
    with pytest.raises(KingenError, match=r":4: limbs\[0\].reference_length: Input should be less than or equal to "
                                          r"1000000"):
        load_robot(path)


def test_the_prismatic_bound_is_relative_only_for_large_robots(tmp_path):
    from kingen.verify import value_tolerance_mm
    assert value_tolerance_mm(load_robot("tau")) == 1e-9
    path = leg_file(tmp_path)
    path.write_text(path.read_text().replace("reference_length: 100", "reference_length: 900000"))
    assert value_tolerance_mm(load_robot(path)) == pytest.approx(900000 * 256 * np.finfo(float).eps)


def test_plugins_built_by_kingen_verify_at_the_edge_of_the_range(tmp_path):
    from kingen.hosts.delmia.loader import Plugin
    from kingen.verify import VerifyOptions, verify
    text = LEG.replace("NAME", "edge").replace("DESCRIPTION", "edge").replace(
        "platform_point: [0, 0, 0], reference_length: 100", "platform_point: [987654.321, -3.25, 12.5], "
        "reference_length: 123456.789").replace("home: [0, 0, 150", "home: [-999000, 1000, 150000")
    path = tmp_path / "edge.yaml"
    path.write_text(text.replace("range: [20, 20, 20", "range: [1000, 1000, 1000"))
    robot = load_robot(path)
    result = build_plugin(robot, tmp_path / "b")
    report = verify(robot, Plugin(result.library, result.routine), VerifyOptions(samples=5000))
    assert report.passed, [c.detail for c in report.failures]


# --- schedulers: addresses that are not addresses, servers that are not Dask schedulers

@contextlib.contextmanager
def fake_scheduler(answer):
    """The address of a server on 127.0.0.1 that accepts every connection and sends ``answer``
    (b"": says nothing, ever); it stops with the block."""
    server = socket.create_server(("127.0.0.1", 0))
    accepted = []

    def serve():
        with contextlib.suppress(OSError):
            while True:
                connection, _ = server.accept()
                accepted.append(connection)
                connection.sendall(answer)

    threading.Thread(target=serve, daemon=True).start()
    try:
        yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    finally:
        server.shutdown(socket.SHUT_RDWR)
        server.close()
        for connection in accepted:
            connection.close()


SCHEDULER_COMMANDS = {"optimize": ["optimize", "rus_optimized", "--iterations", "1", "--swarm", "2"],
                      "verify": ["verify", "hexapod", "--samples", "10"]}


@pytest.mark.parametrize("command", sorted(SCHEDULER_COMMANDS))
@pytest.mark.parametrize("answer, words", [(b"", "(no answer within 1 s)"),
                                           (b"\xff" * 64 + b"HTTP/1.1 200 OK\r\n\r\n", "(not a Dask scheduler: ")],
                         ids=["silent", "junk"])
def test_a_server_that_is_no_scheduler_is_named_within_the_deadline(command, answer, words, tmp_path, capsys,
                                                                     monkeypatch):
    """Connecting and the first answers share one deadline (SCHEDULER_TIMEOUT, 20 s; 1 s here):
    a server that accepts and says nothing, or says something else, is exit 2 naming it."""
    pytest.importorskip("distributed")
    monkeypatch.setattr("kingen.runtime.executors.SCHEDULER_TIMEOUT", 1.0)
    with fake_scheduler(answer) as address:
        start = time.monotonic()
        code, _, err = run(capsys, *SCHEDULER_COMMANDS[command], "-o", tmp_path / "out", "--scheduler", address)
        elapsed = time.monotonic() - start
    assert code == 2 and one_error_line(err), err
    assert err.startswith(f"kingen: error: --scheduler: no Dask scheduler at {address} ") and words in err, err
    assert elapsed < 30


@pytest.mark.parametrize("command", sorted(SCHEDULER_COMMANDS))
@pytest.mark.parametrize("address, problem", [
    ("notanaddress", "not of the form tcp://HOST:PORT, tls://HOST:PORT or HOST:PORT"),
    ("", "not of the form tcp://HOST:PORT, tls://HOST:PORT or HOST:PORT"),
    ("tcp://[::1", "not of the form tcp://HOST:PORT, tls://HOST:PORT or HOST:PORT"),
    ("http://127.0.0.1:8786", "unknown protocol 'http' (Dask knows tcp, tls, ws, wss, ucx)"),
    ("127.0.0.1:70000", "port 70000 is not within 1 to 65535")])
def test_a_scheduler_address_that_is_not_one_is_refused_before_any_work(command, address, problem, tmp_path, capsys):
    code, _, err = run(capsys, *SCHEDULER_COMMANDS[command], "-o", tmp_path / "out", "--scheduler", address)
    assert code == 2
    assert err == f"kingen: error: --scheduler: {address!r} is not a Dask scheduler address: {problem}\n"
    assert not (tmp_path / "out").exists()


def test_dask_address_forms_are_accepted():
    from kingen.runtime.executors import scheduler_address

    for address in ("tcp://127.0.0.1:8786", "127.0.0.1:8786", "tls://scheduler.example.org:8786",
                    "tcp://[::1]:8786", "ws://localhost:8786", "localhost:8786"):
        assert scheduler_address(address) == address
