"""Hand-written plugins in the style of the published thesis ones (K&R definitions,
long double, pow, printf debugging, one routine per library), each with one classic
mistake: verify must pass the right ones and name the defect in the wrong ones."""

import json

import numpy as np
import pytest

from kingen.cli import main
from kingen.runtime.resources import robots_dir

_THESIS = {}


def thesis_hexapod():
    """The hexapod as the DELMIA thesis defines it, without kingen's direct-singularity
    threshold (``singularity:``): its hand-written routine gives no such warning."""
    if "path" not in _THESIS:
        import tempfile
        from pathlib import Path

        text = (robots_dir() / "hexapod.yaml").read_text()
        kept = "".join(line for line in text.splitlines(keepends=True) if not line.startswith("singularity:"))
        assert kept != text
        path = Path(tempfile.mkdtemp(prefix="kingen-thesis-")) / "hexapod.yaml"
        path.write_text(kept)
        _THESIS["path"] = str(path)
    return _THESIS["path"]

HEXAPOD_LEGACY = r"""
/* kin_hexapodFullTest.c: hand-written in the thesis's style */
#include "shlibdefs.h"
#include <math.h>

#define NUM_DOFS 6
#define NUM_SOLUTIONS 1

static long double b[6][3] = {
    {31, 118.156, 40.205}, {-31, 118.156, 40.205}, {-117.826, -32.231, 40.205},
    {-86.826, -85.925, 40.205}, {86.826, -85.925, 40.205}, {117.826, -32.231, 40.205}};
static long double t[6][3] = {
    {31, 48.799, -31.45}, {-31, 48.799, -31.45}, {-57.761, 2.447, -31.45},
    {-26.761, -51.246, -31.45}, {26.761, -51.246, -31.45}, {57.761, 2.447, -31.45}};
static int order[6] = {ORDER};

DllExport int get_kin_config(kin_routine, kin_dof, solution_count, usrKinDataHint)
char *kin_routine;
int *kin_dof;
int *solution_count;
int *usrKinDataHint;
{
    if (NAME_CHECK)
        return 1;
    *kin_dof = NUM_DOFS;
    *solution_count = NUM_SOLUTIONS;
    *usrKinDataHint = HINT;
    return 0;
}

DllExport int kin_hexapodFullTest(link_lengths, link_offsets, T6, solutions, warnings, pData)
double link_lengths[];
double link_offsets[];
double T6[4][4];
double solutions[][NUM_SOLUTIONS];
int warnings[];
void *pData;
{
    int i, j, k;
    long double L0 = REFERENCE_LENGTH;
    long double p[3];
    if (CHECK_DEFINITION && !kin_check_definition(NUM_DOFS, NUM_SOLUTIONS)) {
        REFUSE
        return 1;
    }
    if (CRASH && T6[3][0] > 40.0 && T6[3][0] < 1e6)
        *(volatile int *)0 = 1;
    for (i = 0; i < 4; i++)
        for (j = 0; j < 3; j++)
            if (!(T6[i][j] - T6[i][j] == 0.0)) {
                for (k = 0; k < NUM_DOFS; k++)
                    solutions[k][0] = 0.0;
                warnings[0] = WARN_UNREACHABLE;
                return 1;
            }
    for (i = 0; i < 6; i++) {
        for (j = 0; j < 3; j++)
            p[j] = ROTATED - b[i][j];
        solutions[order[i]][0] = SIGN (sqrt(pow(p[0], 2) + pow(p[1], 2) + pow(p[2], 2)) - L0) * SCALE;
        if (PRINT)
            printf("leg %d = %f\n", i + 1, (double)solutions[order[i]][0]);
    }
    if (OUT_OF_BOUNDS)
        solutions[NUM_DOFS][0] = 0.0;
    warnings[0] = WARN_GOOD_SOLUTION;
    return 0;
}
"""

RIGHT = {
    "NAME_CHECK": 'strcmp(kin_routine, "kin_hexapodFullTest") != 0',
    "HINT": "USR_KIN_DATA_NULL",
    "REFUSE": "",
    "ORDER": "0, 1, 2, 3, 4, 5",
    "REFERENCE_LENGTH": "399.413",
    "CHECK_DEFINITION": "1",
    "ROTATED": "T6[0][j] * t[i][0] + T6[1][j] * t[i][1] + T6[2][j] * t[i][2] + T6[3][j]",
    "SIGN": "",
    "SCALE": "1.0",
    "PRINT": "0",
    "OUT_OF_BOUNDS": "0",
    "CRASH": "0",
}

TAU_LEGACY = r"""
#include "shlibdefs.h"

static double s[3][3] = {{0, 0, 0}, {-1100, 700, 0}, {-2200, 0, 0}};
static double d[3][3] = {{-96.569, -185, -400}, {0, -322.843, -173.726}, {96.569, 0, -400}};
static double n[3][3] = {{224.999, -240.001, 171.568}, {0, 39.705, 336.862}, {-182.574, -80, 213.994}};
static double l[3] = {1500, 1500, 1499.775};

DllExport int get_kin_config(char *kin_routine, int *kin_dof, int *solution_count, int *usrKinDataHint)
{
    if (strcmp(kin_routine, "kin_tau") != 0)
        return 1;
    *kin_dof = 3;
    *solution_count = 8;
    *usrKinDataHint = USR_KIN_DATA_NULL;
    return 0;
}

DllExport int kin_tau(double link_lengths[], double link_offsets[], double T6[4][4],
                      double solutions[][8], int warnings[], void *pData)
{
    int i, j, k, bad = 0, limits;
    double w[3], along, radicand, q[3][2];
    if (!kin_check_definition(3, 8))
        return 1;
    for (i = 0; i < 4; i++)
        for (j = 0; j < 3; j++)
            if (!(T6[i][j] - T6[i][j] == 0.0))
                bad = 1;
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++)
            w[j] = bad ? 0.0 : T6[0][j] * n[i][0] + T6[1][j] * n[i][1] + T6[2][j] * n[i][2] + T6[3][j] - s[i][j] - d[i][j];
        along = -w[2];
        radicand = l[i] * l[i] - (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) + along * along;
        if (bad || radicand < -1e-5 * l[i] * l[i])
            bad = 1;
        radicand = radicand > 0 ? sqrt(radicand) : 0;
        q[i][BRANCH0] = bad ? 0.0 : along - radicand;
        q[i][1 - BRANCH0] = bad ? 0.0 : along + radicand;
    }
    for (k = 0; k < WRITTEN; k++) {
        limits = 0;
        for (i = 0; i < 3; i++) {
            solutions[i][k] = q[i][(k >> (2 - i)) & 1];
            if (solutions[i][k] < -1 || solutions[i][k] > 2600)
                limits = 1;
        }
        warnings[k] = bad ? WARN_UNREACHABLE : limits ? WARN_JOINT_LIMITS_EXCEEDED : WARN_GOOD_SOLUTION;
    }
    for (k = WRITTEN; k < 8; k++)
        for (i = 0; i < 3; i++)
            solutions[i][k] = q[i][(k >> (2 - i)) & 1];
    return bad;
}
"""


CRANK_LEGACY = r"""
/* a 6-RUS routine in the thesis's style: one loop per crank, angles in DEGREES */
#include "shlibdefs.h"

static long double A[6][3] = {PIVOTS};
static long double C[6][3] = {POINTS};
static long double beta[6] = {DIRECTIONS};

DllExport int get_kin_config(char *kin_routine, int *kin_dof, int *solution_count, int *usrKinDataHint)
{
    if (strcmp(kin_routine, "kin_ceart") != 0)
        return 1;
    *kin_dof = 6;
    *solution_count = 64;
    *usrKinDataHint = USR_KIN_DATA_NULL;
    return 0;
}

DllExport int kin_ceart(double link_lengths[], double link_offsets[], double T6[4][4],
                        double solutions[][64], int warnings[], void *pData)
{
    int i, j, k, bad = 0;
    long double g[3], a, b, K, rho, theta[6][2], pi = 3.14159265358979323846L;
    if (!kin_check_definition(6, 64))
        return 1;
    for (i = 0; i < 4; i++)
        for (j = 0; j < 3; j++)
            if (!(T6[i][j] - T6[i][j] == 0.0))
                bad = 1;
    for (i = 0; i < 6; i++) {
        for (j = 0; j < 3; j++)
            g[j] = bad ? 1.0 : T6[0][j] * C[i][0] + T6[1][j] * C[i][1] + T6[2][j] * C[i][2] + T6[3][j] - A[i][j];
        a = g[0] * cos(beta[i] * pi / 180) + g[1] * sin(beta[i] * pi / 180);
        b = -g[2];
        K = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2] + 194.0L * 194.0L - 650.0L * 650.0L) / (2 * 194.0L);
        rho = sqrt(a * a + b * b);
        if (fabs(K / rho) > 1)
            bad = 1;
        theta[i][0] = bad ? 0 : atan2(b, a) + acos(K / rho);
        theta[i][1] = bad ? 0 : atan2(b, a) - acos(K / rho);
        for (j = 0; j < 2; j++) {
            if (theta[i][j] > pi) theta[i][j] -= 2 * pi;
            if (theta[i][j] <= -pi) theta[i][j] += 2 * pi;
            theta[i][j] = theta[i][j] * UNIT;
        }
    }
    for (k = 0; k < 64; k++) {
        for (i = 0; i < 6; i++)
            solutions[i][k] = theta[i][(k >> (5 - i)) & 1];
        warnings[k] = bad ? WARN_UNREACHABLE : WARN_GOOD_SOLUTION;
    }
    return bad;
}
"""


def crank_source(unit):
    from kingen.robot.model import load_robot
    limbs = load_robot("ceart").limbs
    table = lambda rows: ", ".join("{" + ", ".join(repr(v) for v in row) + "}" for row in rows)  # noqa: E731
    return (CRANK_LEGACY.replace("PIVOTS", table(l.pivot for l in limbs))
            .replace("POINTS", table(l.platform_point for l in limbs))
            .replace("DIRECTIONS", ", ".join(repr(float(l.crank_direction)) for l in limbs))
            .replace("UNIT", unit))


def hexapod_source(**mistake):
    text = HEXAPOD_LEGACY
    for key, value in {**RIGHT, **mistake}.items():
        text = text.replace(key, value)
    return text


def run_verify(capsys, tmp_path, robot, text, routine, samples="3000", *options):
    source = tmp_path / f"{routine}.c"
    source.write_text(text)
    report = tmp_path / "report.json"
    code = main(["verify", robot, "--source", str(source), "--routine", routine, "-o", str(tmp_path / "lib"),
                 "--samples", samples, "--json", str(report), "--junit", str(tmp_path / "report.xml"), *options])
    out, err = capsys.readouterr()
    data = json.loads(report.read_text()) if report.exists() else None
    return code, out, err, data


def diagnoses(data):
    return " | ".join(data["diagnoses"])


def failed_checks(data):
    return sorted(check["name"] for check in data["checks"] if not check["passed"])


def test_right_hexapod_in_thesis_style_passes(capsys, tmp_path):
    code, out, _, data = run_verify(capsys, tmp_path, thesis_hexapod(), hexapod_source(), "kin_hexapodFullTest")
    assert code == 0, out
    assert data["passed"] and data["max_abs_error_mm"] <= 1e-9
    assert (tmp_path / "lib" / "libhexapodFullTest.so").is_file()
    assert '<testcase classname="kingen.hexapod" name="values">' in (tmp_path / "report.xml").read_text()


def test_debug_printing_is_a_notice_not_a_failure(capsys, tmp_path):
    code, out, _, data = run_verify(capsys, tmp_path, thesis_hexapod(), hexapod_source(PRINT="1"), "kin_hexapodFullTest")
    assert code == 0
    assert "notice: the routine printed" in out and "'leg 1 = " in out
    assert "debug printing slows the host" in data["notices"][0]


def test_wrong_reference_length_is_named_with_its_offset(capsys, tmp_path):
    code, out, _, data = run_verify(capsys, tmp_path, thesis_hexapod(), hexapod_source(REFERENCE_LENGTH="376.5"),
                                    "kin_hexapodFullTest")
    assert code == 1
    # every golden entry of the hexapod (home, and genhexkins' two poses) is 22.913 mm off
    assert failed_checks(data) == ["closure", "golden[0]", "golden[1]", "golden[2]", "round trip", "values"]
    text = diagnoses(data)
    assert "joint 0 (leg1) is off by a constant +22.913 mm" in text
    assert "as if L0 = 376.5 mm; the robot says 399.413 mm" in text
    assert "diagnosis: joint 5 (leg6) is off by a constant +22.913 mm" in out


def test_untransposed_t6_is_named(capsys, tmp_path):
    untransposed = "T6[j][0] * t[i][0] + T6[j][1] * t[i][1] + T6[j][2] * t[i][2] + T6[j][3]"
    code, _, _, data = run_verify(capsys, tmp_path, thesis_hexapod(), hexapod_source(ROTATED=untransposed),
                                  "kin_hexapodFullTest")
    assert code == 1
    assert "reads T6 untransposed" in diagnoses(data)


def test_swapped_joints_are_named(capsys, tmp_path):
    code, _, _, data = run_verify(capsys, tmp_path, thesis_hexapod(), hexapod_source(ORDER="1, 0, 2, 3, 4, 5"),
                                  "kin_hexapodFullTest")
    assert code == 1
    text = diagnoses(data)
    assert "joint 0 (leg1) holds the values of reference joint 1 (leg2)" in text
    assert "joint 1 (leg2) holds the values of reference joint 0 (leg1)" in text


@pytest.mark.parametrize("mistake, words", [
    ({"SCALE": "0.001"}, "scaled by 0.001 (metres instead of mm)"),
    ({"SIGN": "-"}, "has its sign flipped"),
])
def test_scale_and_sign_are_named(capsys, tmp_path, mistake, words):
    code, _, _, data = run_verify(capsys, tmp_path, thesis_hexapod(), hexapod_source(**mistake), "kin_hexapodFullTest")
    assert code == 1
    assert words in diagnoses(data)


def test_writing_past_the_solutions_array_is_caught(capsys, tmp_path):
    code, _, _, data = run_verify(capsys, tmp_path, thesis_hexapod(), hexapod_source(OUT_OF_BOUNDS="1"),
                                  "kin_hexapodFullTest")
    assert code == 1
    assert failed_checks(data) == ["buffers", "return value", "values", "warnings"]
    assert "3000 calls: the routine wrote past the end of solutions[][]" in next(
        c["detail"] for c in data["checks"] if c["name"] == "buffers")


def test_ignoring_kin_check_definition_is_caught(capsys, tmp_path):
    code, _, _, data = run_verify(capsys, tmp_path, thesis_hexapod(), hexapod_source(CHECK_DEFINITION="0"),
                                  "kin_hexapodFullTest")
    assert code == 1
    assert failed_checks(data) == ["kin_check_definition", "refusal"]
    assert "called 0 times" in " ".join(data["interface_failures"])


@pytest.mark.parametrize("mistake, check, words", [
    ({"NAME_CHECK": 'strncmp(kin_routine, "kin_hexapod", 11) != 0'}, "get_kin_config",
     "accepts a routine name that is not 'kin_hexapodFullTest'"),
    ({"HINT": "7"}, "get_kin_config", "answers an unknown data hint 7"),
    ({"REFUSE": "warnings[0] = WARN_UNREACHABLE;"}, "refusal",
     "when kin_check_definition refuses, the routine writes solutions or warnings"),
])
def test_interface_mistakes_are_named(capsys, tmp_path, mistake, check, words):
    code, _, _, data = run_verify(capsys, tmp_path, thesis_hexapod(), hexapod_source(**mistake), "kin_hexapodFullTest",
                                  samples="200")
    assert code == 1
    assert failed_checks(data) == [check]
    assert words in " ".join(data["interface_failures"])


def test_right_tau_without_the_singular_band_fails_only_warnings(capsys, tmp_path):
    """The thesis-style routine is right everywhere but in the limb singular band, where it
    never warns: the poses verify adds beside that boundary catch it."""
    text = TAU_LEGACY.replace("BRANCH0", "0").replace("WRITTEN", "8")
    code, out, _, data = run_verify(capsys, tmp_path, "tau", text, "kin_tau")
    assert code == 1, out
    assert [check["name"] for check in data["checks"] if not check["passed"]] == ["warnings"]
    assert "where the reference says WARN_SINGULAR_SOLUTION" in diagnoses(data)


def test_postures_in_another_order_give_the_permutation(capsys, tmp_path):
    text = TAU_LEGACY.replace("BRANCH0", "1").replace("WRITTEN", "8")
    code, _, _, data = run_verify(capsys, tmp_path, "tau", text, "kin_tau")
    assert code == 1
    assert "postures are in another order: plugin posture -> reference posture 0->7, 1->6" in diagnoses(data)


def test_warnings_never_written_are_named(capsys, tmp_path):
    text = TAU_LEGACY.replace("BRANCH0", "0").replace("WRITTEN", "1")
    code, _, _, data = run_verify(capsys, tmp_path, "tau", text, "kin_tau")
    assert code == 1
    assert failed_checks(data) == ["non-finite T6", "warnings"]
    assert "the warnings of postures 1-7 are never written" in diagnoses(data)


def test_source_that_does_not_compile_is_bad_input(capsys, tmp_path):
    source = tmp_path / "kin_broken.c"
    source.write_text(hexapod_source().replace("return 0;\n}", "return 0\n}", 1))
    code = main(["verify", "hexapod", "--source", str(source), "--routine", "kin_hexapodFullTest",
                 "-o", str(tmp_path / "lib")])
    _, err = capsys.readouterr()
    assert code == 2
    assert err.count("\n") == 1
    assert err.startswith(f"kingen: error: does not compile: {source}:28:13: error: expected ';'")
    assert not (tmp_path / "lib" / "libbroken.so").exists()


def test_plugin_option_verifies_a_prebuilt_library(capsys, tmp_path):
    run_verify(capsys, tmp_path, thesis_hexapod(), hexapod_source(), "kin_hexapodFullTest", samples="10")
    code = main(["verify", thesis_hexapod(), "--plugin", str(tmp_path / "lib" / "libhexapodFullTest.so"),
                 "--routine", "kin_hexapodFullTest", "--samples", "500"])
    out, _ = capsys.readouterr()
    assert code == 0 and "PASSED" in out


def test_unknown_routine_is_bad_input(capsys, tmp_path):
    run_verify(capsys, tmp_path, thesis_hexapod(), hexapod_source(), "kin_hexapodFullTest", samples="10")
    code = main(["verify", thesis_hexapod(), "--plugin", str(tmp_path / "lib" / "libhexapodFullTest.so"),
                 "--routine", "kin_other"])
    _, err = capsys.readouterr()
    assert code == 2 and "get_kin_config does not know routine 'kin_other'" in err


def test_thesis_crank_routine_fails_where_limbs_reach_their_singular_band(capsys, tmp_path):
    """The thesis-style crank routine agrees with the reference on the uniform sample, but it
    has no singular band: beside a crank's singularity it answers good, or unreachable with
    every joint of the posture cleared. The poses verify adds on both sides of that boundary
    show it, in values, warnings, return value and closure alike."""
    code, out, _, data = run_verify(capsys, tmp_path, "ceart", crank_source("1.0"), "kin_ceart")
    assert code == 1, out
    assert [check["name"] for check in data["checks"] if not check["passed"]] == [
        "values", "warnings", "return value", "closure"]
    assert "postures answer WARN_UNREACHABLE where the reference says WARN_SINGULAR_SOLUTION" in diagnoses(data)
    assert "postures answer WARN_GOOD_SOLUTION where the reference says WARN_SINGULAR_SOLUTION" in diagnoses(data)
    # 16 boundaries per warning (PER_WARNING); CEART's direct-index threshold, met by no ray, by the descent.
    found = data["boundary_poses"]["boundaries_found"]
    assert found["WARN_UNREACHABLE"] == 16 and found["WARN_SINGULAR_SOLUTION"] == 16 and found["direct_index_min"] > 0
    assert data["boundary_poses"]["searched"]["direct_index_min"]["crossed"] > 0


def test_crank_angles_in_degrees_are_named(capsys, tmp_path):
    code, _, _, data = run_verify(capsys, tmp_path, "ceart", crank_source("(180 / pi)"), "kin_ceart")
    assert code == 1
    assert "joint 0 (crank1) is scaled by 57.2957795 (degrees instead of radians)" in diagnoses(data)


def test_a_crash_in_another_comparing_process_is_named_as_in_the_first(capsys, tmp_path):
    """verify compares chunks in forked processes too: a routine that crashes there (here on
    one pose of chunk 1, the second process's first) is run again on that chunk in the first
    process, where it crashes on the same pose, so the crash is named with its poses as always."""
    from kingen.robot.model import load_robot
    from kingen.kinematics.poses import sample_poses
    from kingen.verify import chunk_size
    robot = load_robot(thesis_hexapod())
    chunk = chunk_size(robot)
    x = sample_poses(robot, 2 * chunk, seed=0)[chunk:, 0]
    crashing = float(x[np.argmax(x > 40.0)])  # the routine's crash switch also asks for x > 40 mm
    text = hexapod_source(CRASH=f"(T6[3][0] == {crashing!r})")
    code, out, _, data = run_verify(capsys, tmp_path, thesis_hexapod(), text, "kin_hexapodFullTest", str(5 * chunk),
                                    "--processes", "3")
    assert code == 1
    assert failed_checks(data) == ["crash"]
    assert f"(signal SIGSEGV) during poses {chunk} to {2 * chunk - 1} of seed 0" in out


def test_a_crash_only_in_another_comparing_process_still_fails(capsys, tmp_path):
    """A routine that crashes in a forked comparing process but not when its chunk is compared
    again in the first one (here: in any process but the one that called it first) has crashed
    all the same: the verdict says so, naming the poses and the signal."""
    from kingen.robot.model import load_robot
    from kingen.verify import chunk_size
    chunk = chunk_size(load_robot(thesis_hexapod()))
    text = ("#include <unistd.h>\nstatic pid_t first_caller = 0;\n"
            + hexapod_source(CRASH="(first_caller == 0 ? (first_caller = getpid(), 0) : getpid() != first_caller)"))
    code, out, _, data = run_verify(capsys, tmp_path, thesis_hexapod(), text, "kin_hexapodFullTest", str(5 * chunk),
                                    "--processes", "2")
    assert code == 1
    assert failed_checks(data) == ["crash"]
    assert (f"a comparing process ended (signal SIGSEGV) during poses {chunk} to {2 * chunk - 1} of seed 0, "
            "which ran to the end when compared again in the first process") in out
    assert data["samples"] == 5 * chunk and data["max_abs_error_mm"] < 1e-9  # every pose compared all the same


def test_a_routine_that_crashes_is_a_failed_check_not_a_dead_process(capsys, tmp_path):
    code, out, _, data = run_verify(capsys, tmp_path, thesis_hexapod(), hexapod_source(CRASH="1"), "kin_hexapodFullTest")
    assert code == 1
    assert failed_checks(data) == ["crash"]
    from kingen.robot.model import load_robot
    from kingen.verify import chunk_size
    last = min(3000, chunk_size(load_robot(thesis_hexapod()))) - 1
    assert f"the plugin ended the host process (signal SIGSEGV) during poses 0 to {last} of seed 0" in out
