"""Unit tests where an end-to-end failure would be hard to locate: bench, package, diagnose,
build and host, each on inputs whose right answer is written out here."""

import os
import stat

import numpy as np
import pytest

from kingen.kinematics.routine import UNWRITTEN_WARNING, WARNINGS, check_routine_name, warnings_to_exercise
from kingen.verify.bench import benchmark
from kingen.runtime.compiler import CompileError, compile_c, compiler_command
from kingen.runtime.files import PACKAGE_MARKER as MARKER
from kingen.runtime.files import write_atomic
from kingen.hosts.delmia.build import WINDOWS_DEFINES, legacy_library_name
from kingen.conventions import t6_from_pose
from kingen.verify.diagnose import diagnose, diagnose_warnings
from kingen.errors import KingenError
from kingen.hosts.delmia.loader import KinStat
from kingen.robot.model import load_robot
from kingen.hosts.delmia.package import render_package, write_package
from kingen.kinematics.reference import solve

GOOD, UNREACHABLE = WARNINGS["WARN_GOOD_SOLUTION"], WARNINGS["WARN_UNREACHABLE"]


# --- bench

def test_bench_times_the_routine_and_reports_every_figure(plugin):
    robot, loaded = plugin("tau")
    ticks = []
    figures = benchmark(robot, loaded, calls=3000, repeats=1, tick=lambda: ticks.append(1))
    assert figures["calls"] == 3000 and figures["postures"] == 8 and figures["verify_passed"] is True
    for key in ("batch_ns_per_call", "cffi_ns_per_call", "reference_poses_per_second", "verify_poses_per_second"):
        assert 0 < figures[key] < float("inf"), key
    assert len(ticks) >= 3


def test_bench_reuses_a_bounded_pool_for_many_calls(plugin):
    robot, loaded = plugin("hexapod")
    figures = benchmark(robot, loaded, calls=45000, repeats=1)
    assert figures["calls"] == 60000  # three passes over a pool of 20000 poses


# --- package

def test_windows_package_files_line_ends_and_defines():
    files = render_package(load_robot("tau"), "windows")
    assert sorted(files) == ["BUILD.txt", "SETUP.md", "kin_tau.c", "libtau.def", "makefile"]
    cflags = next(line for line in files["makefile"].splitlines() if line.startswith("CFLAGS"))
    assert cflags.split()[5:5 + len(WINDOWS_DEFINES)] == [f"-D{define}" for define in WINDOWS_DEFINES]
    assert "EXPORTS\n    get_kin_config\n    kin_tau\n    kingen_build_info DATA\n" in files["libtau.def"]


def test_build_txt_explains_the_host_import_library():
    """The makefile's placeholder import library is explained: what it resolves (the host
    symbols the plugin imports), where it comes from (DELMIA's installation, the vendor
    makefile's link line)."""
    files = render_package(load_robot("tau"), "windows")
    assert "HOST_IMPORT_LIB = DELMIA_HOST_IMPORT_LIB.lib" in files["makefile"]
    text = " ".join(files["BUILD.txt"].split())
    assert "replace DELMIA_HOST_IMPORT_LIB.lib (HOST_IMPORT_LIB) with DELMIA's import library" in text
    assert ("DNBVMAP_kin_check_definition, DNBVMAP_Sqrt, DNBVMAP_Asin, DNBVMAP_Acos, DNBVMAP_Atan, "
            "DNBVMAP_Atan2.") in text
    assert "Where it comes from: DELMIA's installation provides it." in text
    assert "the .lib named on the link line of the vendor makefile in the DNBUserKinematics folder" in text


def test_written_packages_carry_their_marker_and_crlf(tmp_path):
    written = write_package(load_robot("tau"), tmp_path / "kit", "windows")
    assert sorted(path.name for path in written) == ["BUILD.txt", "SETUP.md", "kin_tau.c", "libtau.def", "makefile"]
    assert (tmp_path / "kit" / MARKER).is_file()
    assert b"\r\n" in (tmp_path / "kit" / "makefile").read_bytes()
    assert b"\r\n" not in (tmp_path / "kit" / "kin_tau.c").read_bytes()
    linux = write_package(load_robot("exechon"), tmp_path / "kit-linux", "linux")
    assert sorted(path.name for path in linux) == ["SETUP.md", "kin_exechon.c", "libexechon.so"]
    assert (tmp_path / "kit-linux" / "libexechon.so").read_bytes()[:4] == b"\x7fELF"


def test_setup_sheet_warning_table_comes_from_the_interface():
    """The sheet lists, with the interface's codes, exactly the warnings the routine can give."""
    for robot_name in ("hexapod", "tau"):
        robot = load_robot(robot_name)
        sheet = render_package(robot, "windows")["SETUP.md"]
        possible = {"WARN_GOOD_SOLUTION", *warnings_to_exercise(robot)}
        for name, code in WARNINGS.items():
            assert (f"| {code} | {name} |" in sheet) == (name in possible), (robot_name, name)
    assert "within 1e-05 (normalised radicand)" in render_package(load_robot("tau"), "windows")["SETUP.md"]


# --- diagnose

def test_diagnoses_name_offset_sign_scale_and_swap():
    robot = load_robot("hexapod")
    t6 = t6_from_pose(np.tile([[0, 0, 465, 0, 0, 0]], (20, 1)) + np.linspace(0, 10, 20)[:, None])
    expected = solve(robot, t6)
    solutions = expected.joints.copy()
    solutions[:, 0] += 2.5
    solutions[:, 1] *= -1
    solutions[:, 2] *= 1e-3
    solutions[:, [3, 4]] = solutions[:, [4, 3]]
    text = " | ".join(diagnose(robot, t6, solutions, expected.joints, expected.warnings))
    assert "joint 0 (leg1) is off by a constant +2.5 mm on every pose and posture: a wrong reference length" in text
    assert "joint 1 (leg2) has its sign flipped" in text
    assert "joint 2 (leg3) is scaled by 0.001 (metres instead of mm)" in text
    assert "joint 3 (leg4) holds the values of reference joint 4 (leg5)" in text
    assert "joint 5" not in text


def test_diagnoses_of_warnings():
    reference = np.array([[GOOD, UNREACHABLE], [UNREACHABLE, GOOD]])
    assert diagnose_warnings(np.full((2, 2), GOOD), reference, {v: k for k, v in WARNINGS.items()}) == [
        "the routine always answers WARN_GOOD_SOLUTION; the reference finds {'WARN_UNREACHABLE': 2}"]
    unwritten = np.array([[GOOD, UNWRITTEN_WARNING], [UNREACHABLE, GOOD]])
    assert diagnose_warnings(unwritten, reference, {v: k for k, v in WARNINGS.items()})[0] == \
        "the warnings of postures 1 are never written on some poses"


# --- build and host

def test_compiler_command_splits_like_a_shell(monkeypatch):
    monkeypatch.setenv("CC", "gcc -m64 '-DNAME=a b'")
    assert compiler_command() == ["gcc", "-m64", "-DNAME=a b"]
    monkeypatch.delenv("CC")
    assert compiler_command() == ["cc"]


def test_write_atomic_leaves_no_temporary_file_on_failure(tmp_path):
    with pytest.raises(TypeError):
        write_atomic(tmp_path / "x.txt", 12345)
    assert list(tmp_path.iterdir()) == []
    write_atomic(tmp_path / "x.txt", "text", executable=False)
    assert stat.S_IMODE((tmp_path / "x.txt").stat().st_mode) == 0o666 & ~_umask()


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_compile_errors_are_compile_errors_with_the_shown_name(tmp_path):
    source = tmp_path / "scratch.c"
    source.write_text("int f(void) { return 0 }\n")
    with pytest.raises(CompileError, match=r"does not compile: shown\.c:1:\d+: error: expected"):
        compile_c([source], tmp_path / "x.so", ["-shared", "-fPIC"], shown_source="shown.c")
    assert [path.name for path in tmp_path.iterdir()] == ["scratch.c"]


@pytest.mark.parametrize("source, library", [("kin_hexapodFullTest.c", "libhexapodFullTest.so"),
                                             ("tau.c", "libtau.so"), ("kin_.c", "libkin_.so")])
def test_legacy_library_names_follow_the_thesis(source, library):
    assert legacy_library_name(source) == library


@pytest.mark.parametrize("name, good", [("kin_tau", True), ("_x9", True), ("a b", False), ("1abc", False),
                                        ("kin-tau", False), ("", False)])
def test_routine_names_must_be_c_identifiers(name, good):
    if good:
        assert check_routine_name(name) == name
    else:
        with pytest.raises(KingenError, match="is not a C identifier"):
            check_routine_name(name)


def test_kinstat_is_filled_as_delmia_fills_it():
    robot = load_robot("ceart")
    status = KinStat(robot, joint_values=[0.1] * 6)
    assert status.pointer.dof_count == 6
    assert [status.pointer.joint_types[i] for i in range(6)] == [0] * 6  # ROTATIONAL
    assert status.pointer.joint_values[5] == 0.1
    assert status.pointer.jnt_trvl_lmts[0][0] == -1e30  # no limits declared
