"""Toolchains beyond the host's cc: sanitizers, the mingw-w64 Windows build, the
package that drops into DELMIA's DNBUserKinematics folder."""

import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import SHIPPED, random_t6, require_tool
from kingen.runtime.compiler import compile_c
from kingen.hosts.delmia.build import MINGW, STRICT_C89, build_plugin, host_support, windows_host_import_library
from kingen.conventions import rotation_from_rpy, t6_from_matrix
from kingen.hosts import get_host
from kingen.robot.model import load_robot
from kingen.hosts.delmia.package import render_package, write_package
from kingen.hosts.delmia.pe import dll_exports
from kingen.kinematics.reference import solve



@pytest.fixture
def needs_mingw():
    require_tool(MINGW, "gcc-mingw-w64-x86-64")

CLIENT = Path(__file__).parent / "c" / "abi_client.c"
SANITIZE = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer", "-g"]


def extreme_t6(robot, seed):
    """Random, extreme (1e9 mm, 1e300 mm, tiny and half-turn rotations) and non-finite T6."""
    rng = np.random.default_rng(seed)
    _, random = random_t6(robot, 300, seed)
    matrices = []
    for position in ([1e9, 0, 0], [-1e9, 1e9, -1e9], [0, 0, 1e300], [1e-300, 0, 0], robot.verification.home[:3]):
        for angles in ([0, 0, 0], [1e-12, -1e-12, 1e-12], [np.pi, 0, 0], [0, np.pi, 0], [0, 0, np.pi],
                       [np.pi, np.pi, np.pi], rng.uniform(-np.pi, np.pi, 3)):
            matrix = np.eye(4)
            matrix[:3, :3] = rotation_from_rpy(*angles)
            matrix[:3, 3] = position
            matrices.append(t6_from_matrix(matrix))
    bad = []
    for value in (np.nan, np.inf, -np.inf):
        for row in range(4):
            for column in range(3):
                t6 = random[0].copy()
                t6[row, column] = value
                bad.append(t6)
    return np.concatenate([random, np.array(matrices), np.array(bad)])


@pytest.fixture(scope="module")
def sanitized_client(tmp_path_factory):
    require_tool("gcc", "gcc")
    folder = tmp_path_factory.mktemp("asan")
    executable = folder / "abi_client"
    compile_c([CLIENT], executable, ["-std=c99", *SANITIZE, "-rdynamic", "-ldl"], compiler=["gcc"])
    return executable


@pytest.mark.parametrize("name", SHIPPED)
def test_sanitized_plugin_reports_nothing_on_random_extreme_and_non_finite_t6(sanitized_client, tmp_path, name):
    robot = load_robot(name)
    (file_name, text), = __import__("kingen.hosts.delmia.render", fromlist=["render"]).render(robot).items()
    source = tmp_path / file_name
    source.write_text(text)
    include, _ = host_support()
    library = tmp_path / f"lib{name}.so"
    compile_c([source], library, [*STRICT_C89, *SANITIZE, "-fPIC", "-shared", f"-I{include}"], compiler=["gcc"])
    t6 = extreme_t6(robot, seed=17)
    lines = "\n".join(" ".join(repr(float(v)) for v in matrix.ravel()) for matrix in t6)
    result = subprocess.run([str(sanitized_client), str(library), get_host("delmia").routine_name(robot)], input=lines,
                            capture_output=True, text=True, env={"ASAN_OPTIONS": "detect_leaks=0",
                                                                 "UBSAN_OPTIONS": "print_stacktrace=1"})
    assert result.returncode == 0 and result.stderr == "", result.stderr[-3000:]
    rows = result.stdout.splitlines()[1:]
    assert len(rows) == len(t6)
    values = np.array([[float(v) for v in row.split()[1 + robot.postures:]] for row in rows])
    assert np.all(np.isfinite(values)), "a joint value is not finite"
    expected = solve(robot, t6).warnings
    np.testing.assert_array_equal(np.array([[int(w) for w in row.split()[1:1 + robot.postures]] for row in rows]),
                                  expected)


@pytest.mark.usefixtures("needs_mingw")
@pytest.mark.parametrize("name", ["tau", "ceart", "hexapod"])
def test_windows_dll_exports_both_entry_points(tmp_path, name):
    robot = load_robot(name)
    result = build_plugin(robot, tmp_path, target="windows")
    assert result.library.name == f"lib{name}.dll"
    assert dll_exports(result.library) == sorted(["get_kin_config", get_host("delmia").routine_name(robot),
                                                  "kingen_build_info"])


@pytest.mark.usefixtures("needs_mingw")
def test_pe_reader_agrees_with_objdump(tmp_path):
    result = build_plugin(load_robot("tau"), tmp_path, target="windows")
    dump = subprocess.run(["x86_64-w64-mingw32-objdump", "-p", str(result.library)], capture_output=True,
                          text=True, check=True).stdout
    table = dump.split("[Ordinal/Name Pointer] Table")[1]
    names = re.findall(r"^\s*\[\s*\d+\]\s+(\S+)\s*$", table, flags=re.MULTILINE)
    assert sorted(names) == dll_exports(result.library)


@pytest.mark.usefixtures("needs_mingw")
def test_windows_package_builds_with_its_own_makefile_defines_and_def_file(tmp_path):
    robot = load_robot("tau")
    paths = write_package(robot, tmp_path / "package", "windows")
    assert sorted(p.name for p in paths) == ["BUILD.txt", "SETUP.md", "kin_tau.c", "libtau.def", "makefile"]
    makefile = (tmp_path / "package" / "makefile").read_bytes().decode()
    assert "\r\n" in makefile
    assert re.search(r"^DEST = \.\\lib\r$", makefile, flags=re.MULTILINE)
    assert re.search(r"^LIBRARY = libtau\r$", makefile, flags=re.MULTILINE)
    assert re.search(r"^OBJS = kin_tau\.obj\r$", makefile, flags=re.MULTILINE)
    assert "\n\tlink -nologo -dll" in makefile
    flags = re.search(r"^CFLAGS = (.*)\r$", makefile, flags=re.MULTILINE).group(1).split()
    defines = [flag for flag in flags if flag.startswith("-D")]
    assert {"-DWINDOWS_SHELL", "-D_DNBUSERLIB", "-DNDEBUG", "-DWIN32", "-DWINNT", "-DWINDOWS_NT"} <= set(defines)
    include, _ = host_support()
    dll = tmp_path / "libtau.dll"
    compile_c([tmp_path / "package" / "kin_tau.c", tmp_path / "package" / "libtau.def", windows_host_import_library()],
              dll, [*STRICT_C89, "-O2", "-shared", f"-I{include}", *defines], compiler=[MINGW])
    assert dll_exports(dll) == ["get_kin_config", "kin_tau", "kingen_build_info"]


def test_package_never_ships_a_shlibdefs_h(tmp_path):
    for target in ("windows", "linux"):
        assert "shlibdefs.h" not in render_package(load_robot("exechon"), target)


def test_linux_package_holds_a_working_library(tmp_path):
    from kingen.hosts.delmia.loader import Plugin
    paths = write_package(load_robot("exechon"), tmp_path, "linux")
    assert sorted(p.name for p in paths) == ["SETUP.md", "kin_exechon.c", "libexechon.so"]
    plugin = Plugin(tmp_path / "libexechon.so", "kin_exechon")
    assert plugin.config.dof == 3
