"""Hostile and broken plugins: whatever a library does when it is loaded or called, kingen
ends with a verdict (exit 1 and a named check) within its time limit, never with exit 0,
a traceback, a hang or a dead process. Each plugin is a correct one-leg routine with one
defect injected; the correct one passes, so every failure below is the defect's."""

import os
import signal
import subprocess
import sys
import time

import pytest

from conftest import FORGED, forging_constructor

ROBOT = """\
name: probe
description: One leg from the origin to the platform origin, q = |p| - 100 mm.
limbs:
  - {model: leg, base_point: [0, 0, 0], platform_point: [0, 0, 0], reference_length: 100}
verification: {home: [0, 0, 150, 0, 0, 0], range: [20, 20, 20, 10, 10, 10]}
"""

PLUGIN = r"""
#include "shlibdefs.h"
#include <stdlib.h>
#include <unistd.h>

CONSTRUCTOR

DllExport int get_kin_config(char *kin_routine, int *kin_dof, int *solution_count, int *usrKinDataHint)
{
    if (strcmp(kin_routine, "kin_probe") != 0)
        return 1;
    CONFIG
    *kin_dof = DOF;
    *solution_count = SOLUTIONS;
    *usrKinDataHint = USR_KIN_DATA_NULL;
    return 0;
}

DllExport int kin_probe(double link_lengths[], double link_offsets[], double T6[4][4],
                        double solutions[][1], int warnings[], void *pData)
{
    int i, j;
    if (!kin_check_definition(1, 1))
        return 1;
    for (i = 0; i < 4; i++)
        for (j = 0; j < 3; j++)
            if (!(T6[i][j] - T6[i][j] == 0.0)) {
                solutions[0][0] = 0.0;
                warnings[0] = WARN_UNREACHABLE;
                return 1;
            }
    ROUTINE
    solutions[0][0] = sqrt(T6[3][0] * T6[3][0] + T6[3][1] * T6[3][1] + T6[3][2] * T6[3][2]) - 100.0;
    warnings[0] = WARN_GOOD_SOLUTION;
    return 0;
}
"""

RIGHT = {"CONSTRUCTOR": "", "CONFIG": "", "ROUTINE": "", "DOF": "1", "SOLUTIONS": "1"}


def plugin_source(**defect):
    text = PLUGIN
    for key, value in {**RIGHT, **defect}.items():
        text = text.replace(key, value)
    return text


def run_kingen(tmp_path, *argv, timeout=60):
    """kingen as a user runs it: a separate process, its exit code, stdout and stderr."""
    result = subprocess.run([sys.executable, "-m", "kingen.cli", *argv], capture_output=True, text=True,
                            timeout=timeout, cwd=tmp_path)
    assert "Traceback" not in result.stderr, result.stderr
    return result


def verify_source(tmp_path, source, *extra):
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    path = tmp_path / "kin_probe.c"
    path.write_text(source)
    return run_kingen(tmp_path, "verify", str(robot), "--source", str(path), "-o", str(tmp_path / "lib"),
                      "--samples", "200", *extra)


def test_the_right_probe_passes(tmp_path):
    result = verify_source(tmp_path, plugin_source())
    assert result.returncode == 0, result.stdout
    assert "PASSED" in result.stdout


HOSTILE = [
    # (defect, expected exit, words in the output)
    ({"CONSTRUCTOR": "__attribute__((constructor)) static void leave(void) { exit(0); }"},
     1, "FAILED crash: the plugin ended the host process (exit status 0) during loading the plugin"),
    ({"CONSTRUCTOR": "__attribute__((constructor)) static void fault(void) { *(volatile int *)8 = 1; }"},
     1, "FAILED crash: the plugin ended the host process (signal SIGSEGV) during loading the plugin"),
    ({"CONSTRUCTOR": "__attribute__((constructor)) static void spin(void) { for (;;) ; }"},
     1, "FAILED timeout: no progress for 2 s during loading the plugin"),
    ({"CONFIG": "exit(0);"},
     1, "FAILED crash: the plugin ended the host process (exit status 0) during loading the plugin"),
    ({"SOLUTIONS": "-5"},
     1, "FAILED get_kin_config: get_kin_config answers 1 joint and -5 solutions"),
    ({"DOF": "1000000000", "SOLUTIONS": "1000000000"},
     1, "FAILED get_kin_config: get_kin_config answers 1000000000 joints and 1000000000 solutions"),
    ({"ROUTINE": "for (;;) ;"},
     1, "FAILED timeout: no progress for 2 s during the interface checks"),
    ({"ROUTINE": "sleep(1);"},
     1, "FAILED timeout: no progress for 2 s during"),
    ({"ROUTINE": "solutions[1000][0] = 1.0;"},
     1, "FAILED buffers: 200 calls: the routine wrote past the end of solutions[][]"),
    ({"ROUTINE": "warnings[1000] = 1;"},
     1, "the routine wrote past the end of warnings[]"),
    ({"ROUTINE": "solutions[-1000][0] = 1.0;"},
     1, "the routine wrote before solutions[0][0]"),
    ({"ROUTINE": "warnings[-3] = 1;"},
     1, "the routine wrote before warnings[0]"),
    ({"ROUTINE": "T6[3][3] = 2.0;"},
     1, "the routine modified its inputs (T6, link_lengths or link_offsets)"),
    ({"ROUTINE": "*(volatile int *)8 = 1;"},
     1, "FAILED crash: the plugin ended the host process (signal SIGSEGV) during the interface checks"),
    ({"ROUTINE": "abort();"},
     1, "FAILED crash: the plugin ended the host process (signal SIGABRT) during the interface checks"),
    ({"ROUTINE": "exit(0);"},
     1, "FAILED crash: the plugin ended the host process (exit status 0) during the interface checks"),
]


@pytest.mark.parametrize("defect, code, words", HOSTILE, ids=[str(d) for d, _, _ in HOSTILE])
def test_hostile_plugins_end_in_a_named_verdict(tmp_path, defect, code, words):
    start = time.monotonic()
    result = verify_source(tmp_path, plugin_source(**defect), "--timeout", "2")
    assert result.returncode == code, result.stdout + result.stderr
    assert words in result.stdout, result.stdout
    assert time.monotonic() - start < 30


@pytest.mark.parametrize("name", FORGED)
def test_a_plugin_writing_into_kingens_channel_can_only_fail_its_own_run(tmp_path, name):
    """No frame a plugin writes reaches kingen as its message: kingen does not unpickle (the
    pickle frame would exit 0) and judges nothing the child sends unchecked."""
    result = verify_source(tmp_path, plugin_source(CONSTRUCTOR=forging_constructor(FORGED[name])))
    assert result.returncode == 1, result.stdout + result.stderr
    carried = "bytes that are not kingen's message" if name == "pickle" else \
        "a message that is not kingen's (its check failed)"
    assert (f"FAILED crash: kingen's channel to the host process carried {carried} during loading the plugin "
            "(its constructors and get_kin_config): the host process was stopped and nothing it sent was used") \
        in result.stdout, result.stdout


def test_a_library_without_get_kin_config_fails_the_check(tmp_path):
    result = verify_source(tmp_path, plugin_source().replace("get_kin_config", "get_kin_konfig"))
    assert result.returncode == 1
    assert "FAILED get_kin_config: the library does not export get_kin_config" in result.stdout


def test_a_library_the_host_cannot_load_fails_the_load_check(tmp_path):
    result = verify_source(tmp_path, plugin_source(
        ROUTINE="{ extern void DNBVMAP_Nonexistent(void); DNBVMAP_Nonexistent(); }"))
    assert result.returncode == 1
    assert "FAILED load: the library cannot be loaded:" in result.stdout
    assert "undefined symbol: DNBVMAP_Nonexistent" in result.stdout


def test_what_a_constructor_prints_is_a_notice_and_stays_out_of_the_output(tmp_path):
    printing = '__attribute__((constructor)) static void hello(void) { printf("hello from the plugin\\n"); }'
    result = verify_source(tmp_path, plugin_source(CONSTRUCTOR=printing))
    assert result.returncode == 0
    assert "notice: loading the library printed 22 bytes on stdout/stderr (first line: 'hello from the plugin')" \
        in result.stdout
    assert not result.stdout.startswith("hello")


@pytest.mark.parametrize("command", ["solve", "bench"])
def test_solve_and_bench_run_plugins_in_a_child_too(tmp_path, command):
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    source = tmp_path / "kin_probe.c"
    source.write_text(plugin_source(CONSTRUCTOR="__attribute__((constructor)) static void leave(void) { exit(0); }"))
    library = tmp_path / "libprobe.so"
    assert run_kingen(tmp_path, "verify", str(robot), "--source", str(source), "-o", str(tmp_path)).returncode == 1
    if command == "solve":
        result = run_kingen(tmp_path, "solve", str(robot), "--pose", "0", "0", "150", "0", "0", "0")
        assert result.returncode == 0  # kingen's own build of the robot, not the hostile library
        return
    result = run_kingen(tmp_path, "bench", str(robot), "--plugin", str(library), "--routine", "kin_probe",
                        "--calls", "1000")
    assert result.returncode == 1
    assert result.stderr == ("kingen: plugin failed: the plugin ended the host process (exit status 0) during "
                             "loading the plugin (its constructors and get_kin_config)\n")


def test_sigterm_ends_kingen_and_its_child(tmp_path):
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    source = tmp_path / "kin_probe.c"
    source.write_text(plugin_source(ROUTINE="for (;;) ;"))
    process = subprocess.Popen([sys.executable, "-m", "kingen.cli", "verify", str(robot), "--source", str(source),
                                "-o", str(tmp_path / "lib"), "--timeout", "600"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path)
    deadline = time.monotonic() + 30
    children = []
    while not children and time.monotonic() < deadline:
        time.sleep(0.2)
        children = _children(process.pid)
    assert children, "the child process never started"
    time.sleep(0.5)
    process.send_signal(signal.SIGTERM)
    assert process.wait(timeout=20) == 128 + signal.SIGTERM
    time.sleep(0.5)
    assert not [pid for pid in children if os.path.exists(f"/proc/{pid}") and _state(pid) != "Z"]
    leftovers = [p for p in (tmp_path / "lib").iterdir() if p.name.startswith(".")] if (tmp_path / "lib").exists() else []
    assert leftovers == []


def _children(pid):
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as stream:
                    fields = stream.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                found.append(int(entry))
    return found


def _state(pid):
    try:
        with open(f"/proc/{pid}/stat") as stream:
            return stream.read().rsplit(")", 1)[1].split()[0]
    except OSError:
        return "gone"


def test_a_constructor_cannot_stop_kingen_through_its_process_group(tmp_path):
    """kill(0, SIGSTOP) reaches no process of kingen: the sandbox refuses it and names it
    (where the kernel refuses the sandbox's filter, the plugin's process group is its own:
    kingen goes on, and names the stopped child's lack of progress)."""
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    source = tmp_path / "kin_probe.c"
    source.write_text(plugin_source(CONSTRUCTOR="#include <signal.h>\n"
                                                "__attribute__((constructor)) static void stop(void) { kill(0, SIGSTOP); }"))
    # its own session: were the group kingen's, this test's process is spared
    result = subprocess.run([sys.executable, "-m", "kingen.cli", "verify", str(robot), "--source", str(source),
                             "-o", str(tmp_path / "lib"), "--samples", "200", "--timeout", "2"],
                            capture_output=True, text=True, timeout=60, cwd=tmp_path, start_new_session=True)
    assert result.returncode == 1, result.stdout + result.stderr
    assert ("FAILED sandbox: the plugin called kill(0, SIGSTOP) during loading the plugin" in result.stdout
            or "FAILED timeout: no progress for 2 s during loading the plugin" in result.stdout), result.stdout


def test_a_reused_yaml_anchor_is_one_error_line_without_ruamels_warning(tmp_path):
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT.replace("base_point: [0, 0, 0], platform_point: [0, 0, 0]",
                                   "base_point: &p [0, 0, 0], platform_point: &p [0, 0, 0]"))
    result = run_kingen(tmp_path, "render", str(robot), "-o", str(tmp_path / "out"))
    assert result.returncode == 2
    assert result.stderr == (f"kingen: error: {robot}:4: limbs[0].platform_point: anchor &p is defined again "
                             "(first on line 4); give each anchor its own name\n")
    assert not (tmp_path / "out").exists()
    robot.write_text(ROBOT.replace("base_point: [0, 0, 0], platform_point: [0, 0, 0]",
                                   "base_point: &p [0, 0, 0], platform_point: *p"))
    result = run_kingen(tmp_path, "render", str(robot), "-o", str(tmp_path / "out"))
    assert result.returncode == 0 and result.stderr == ""


def _spin(channel):
    channel.stage("spinning")
    while True:
        pass


def _answer(channel):
    return 42


def test_a_child_stopped_for_a_timeout_is_killed_at_once_and_a_finished_one_exits_by_itself(monkeypatch):
    """kingen.runtime.isolation: a child that makes no progress is killed as soon as its timeout ends,
    not given EXIT_GRACE to exit first (a routine spinning in native code never would); one that
    sent its result ends by itself (exit status 0)."""
    from kingen.runtime import isolation

    monkeypatch.setattr(isolation, "EXIT_GRACE", 120.0)
    start = time.monotonic()
    result, failure = isolation.run_in_child(_spin, (), timeout=0.5)
    assert result is None and failure.kind == "timeout" and failure.stage == "spinning"
    assert time.monotonic() - start < 60
    ended = []
    monkeypatch.setattr(isolation, "_end",
                        lambda child, finished: ended.append((finished, child.join() or child.exitcode)) or False)
    assert isolation.run_in_child(_answer, (), timeout=30) == (42, None)
    assert ended == [(True, 0)]


def _close_and_spin(channel):
    channel.stage("closing the pipe")
    channel._sender.close()
    while True:
        pass


def test_a_child_that_closes_its_pipe_and_runs_on_is_stopped_and_named(monkeypatch):
    """A plugin that closes kingen's channel (its file descriptor) and goes on running is
    stopped after EXIT_GRACE and named for what it did, not reported as killed from outside."""
    from kingen.runtime import isolation

    monkeypatch.setattr(isolation, "EXIT_GRACE", 0.5)
    result, failure = isolation.run_in_child(_close_and_spin, (), timeout=60)
    assert result is None and failure.kind == "crash" and failure.stage == "closing the pipe"
    assert failure.detail == ("the plugin closed kingen's channel to the host process during closing the pipe, "
                              "which then did not end within 0.5 s: it was stopped")
