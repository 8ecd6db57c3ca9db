"""``kingen package ROBOT --host c``: the folder a controller engineer drops in. CMake
configures, builds and runs its example (whose output the inverse and forward make), a C++
project links it through add_subdirectory and, after ``cmake --install``, through
find_package; pkg-config finds the installed library. Skipped where cmake is absent (failed
under KINGEN_REQUIRE_TOOLCHAINS=1)."""

import os
import subprocess
from pathlib import Path

import pytest

from kingen.cli import main
from kingen.robot.model import load_robot
from kingen.kinematics.reference import solve
from kingen.conventions import t6_from_pose

from conftest import require_tool

ROBOT = Path(__file__).resolve().parent.parent / "robots" / "tau.yaml"
CPP = """#include <cstdio>
#include "kingen_tau.h"

int main()
{
    const double pose[16] = {1, 0, 0, -1200, 0, 1, 0, -750, 0, 0, 1, -1900, 0, 0, 0, 1};
    double joints[KINGEN_TAU_DOF][KINGEN_TAU_POSTURES];
    int warnings[KINGEN_TAU_POSTURES];
    int returned = kingen_tau_inverse(&kingen_tau_default_geometry, pose, joints, warnings);
    std::printf("%d %d %.9f\\n", returned, warnings[0], joints[0][0]);
    return 0;
}
"""


def _run(command, cwd=None):
    done = subprocess.run([str(part) for part in command], capture_output=True, text=True, timeout=300, cwd=cwd)
    assert done.returncode == 0, f"{command}: {done.stdout}{done.stderr}"
    return done.stdout


@pytest.fixture(scope="module")
def package(tmp_path_factory):
    require_tool("cmake", "cmake")
    folder = tmp_path_factory.mktemp("c-package") / "kingen_tau"
    assert main(["package", str(ROBOT), "--host", "c", "-o", str(folder)]) == 0
    return folder


def test_the_package_holds_what_the_issue_names(package):
    names = sorted(str(path.relative_to(package)) for path in package.rglob("*") if path.is_file())
    assert names == [".kingen-package", "CMakeLists.txt", "SETUP.md", "example/main.c", "include/kingen_tau.h",
                     "kingen_tau.pc", "src/kingen_tau.c"]
    setup = (package / "SETUP.md").read_text()
    for words in ("mm", "radians", "row-major", "Posture k takes branch", "KINGEN_TAU_WARN_GOOD_SOLUTION", "_SINGULAR_SOLUTION",
                  "calibrated = kingen_tau_default_geometry;", "kingen::tau"):
        assert words in setup


def test_cmake_builds_and_runs_the_example(package, tmp_path):
    """A Release build (CMake's -O3) with every warning an error."""
    build = tmp_path / "build"
    _run(["cmake", "-S", package, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DCMAKE_C_FLAGS=-Wall -Wextra -Werror"])
    _run(["cmake", "--build", build])
    printed = _run([build / "kingen_tau_example"])
    robot = load_robot(ROBOT)
    expected = solve(robot, t6_from_pose([robot.verification.home])).joints[0, :, 0]
    shown = [float(line.split(":")[1]) for line in printed.splitlines() if line.strip().startswith("joint")]
    assert shown == pytest.approx(expected, abs=1e-6)  # the example prints to 6 decimals
    assert "forward: returned 0" in printed


def _cpp_project(folder, cmake_lines):
    folder.mkdir()
    (folder / "main.cpp").write_text(CPP)
    (folder / "CMakeLists.txt").write_text("cmake_minimum_required(VERSION 3.13)\nproject(app LANGUAGES C CXX)\n"
                                           + cmake_lines + "add_executable(app main.cpp)\n"
                                           "target_link_libraries(app PRIVATE kingen::tau)\n")
    return folder


def _links_and_agrees(project, build, *configure):
    _run(["cmake", "-S", project, "-B", build, *configure])
    _run(["cmake", "--build", build])
    returned, warning, joint = _run([build / "app"]).split()
    robot = load_robot(ROBOT)
    expected = solve(robot, t6_from_pose([robot.verification.home]))
    assert (int(returned), int(warning)) == (0, 0)
    assert float(joint) == pytest.approx(expected.joints[0, 0, 0], abs=1e-9)


def test_a_cpp_project_links_it_through_add_subdirectory(package, tmp_path):
    require_tool("g++", "g++")
    project = _cpp_project(tmp_path / "app", f'add_subdirectory("{package}" kingen_tau)\n')
    _links_and_agrees(project, tmp_path / "build")


@pytest.fixture(scope="module")
def installed(package, tmp_path_factory):
    """The package built by CMake (its default: a static library) and installed: the prefix."""
    folder = tmp_path_factory.mktemp("c-install")
    build, prefix = folder / "library-build", folder / "prefix"
    _run(["cmake", "-S", package, "-B", build])
    _run(["cmake", "--build", build])
    _run(["cmake", "--install", build, "--prefix", prefix])
    return prefix


def test_installed_it_is_found_by_find_package(installed, tmp_path):
    require_tool("g++", "g++")
    project = _cpp_project(tmp_path / "app", "find_package(kingen_tau REQUIRED)\n")
    _links_and_agrees(project, tmp_path / "app-build", f"-DCMAKE_PREFIX_PATH={installed}")


def test_the_documented_pkg_config_line_links_a_c_program_to_the_static_library(installed, tmp_path):
    """`cc main.c $(pkg-config --cflags --libs kingen_tau)`, as the page says, against the
    installed static library: a C program (a C++ driver would bring libm itself) links, and its
    inverse agrees with the reference."""
    require_tool("pkg-config", "pkg-config")
    assert (installed / "lib" / "libkingen_tau.a").is_file()
    found = subprocess.run(["pkg-config", "--cflags", "--libs", "kingen_tau"], capture_output=True, text=True,
                           env={**os.environ, "PKG_CONFIG_PATH": str(installed / "lib" / "pkgconfig")})
    assert found.returncode == 0, found.stderr
    (tmp_path / "main.c").write_text(CPP.replace("#include <cstdio>", "#include <stdio.h>").replace("std::printf", "printf")
                                     .replace("int main()", "int main(void)"))
    _run(["cc", "-std=c99", tmp_path / "main.c", "-o", tmp_path / "app", *found.stdout.split()])
    returned, warning, joint = _run([tmp_path / "app"]).split()
    robot = load_robot(ROBOT)
    expected = solve(robot, t6_from_pose([robot.verification.home]))
    assert (int(returned), int(warning)) == (0, 0)
    assert float(joint) == pytest.approx(expected.joints[0, 0, 0], abs=1e-9)


def test_a_constrained_machines_package_builds_and_its_example_comes_back(tmp_path):
    """The 3-PRS head (task coordinates z, roll, pitch): CMake builds the example, whose inverse
    joints at the verification home are the reference's (its parasitic x, y, yaw solved by
    kingen's numpy reference), whose forward returns the whole pose (the example exits 0
    only when every entry is within 1e-6) and whose machine pose of the home is the home."""
    require_tool("cmake", "cmake")
    robot = load_robot("prs_head")
    folder = tmp_path / "kingen_prs_head"
    assert main(["package", "prs_head", "--host", "c", "-o", str(folder)]) == 0
    assert "## Task coordinates" in (folder / "SETUP.md").read_text()
    _run(["cmake", "-S", folder, "-B", tmp_path / "build"])
    _run(["cmake", "--build", tmp_path / "build"])
    printed = _run([tmp_path / "build" / "kingen_prs_head_example"])
    posture = int(printed.split("posture ")[1].split(":")[0])
    expected = solve(robot, t6_from_pose([robot.verification.home])).joints[0, :, posture]
    shown = [float(line.split(":")[1]) for line in printed.splitlines() if line.strip().startswith("joint")]
    assert shown == pytest.approx(expected, abs=1e-6)
    assert "warning 0" in printed and "forward: returned 0" in printed
    # The home is on the manifold: its machine pose is itself (the example exits 0 only then).
    assert "machine pose for the task coordinates: status 0, largest difference from the pose: " in printed


def test_a_folder_kingen_did_not_write_is_refused(tmp_path, capsys):
    (tmp_path / "mine.txt").write_text("not kingen's")
    assert main(["package", str(ROBOT), "--host", "c", "-o", str(tmp_path)]) == 2
    assert capsys.readouterr().err == f"kingen: error: {tmp_path}: exists and is not a kingen package folder; choose another -o\n"
    assert sorted(path.name for path in tmp_path.iterdir()) == ["mine.txt"]
