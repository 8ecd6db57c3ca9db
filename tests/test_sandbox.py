"""The sandbox foreign code runs in (kingen.runtime.sandbox): a plugin that signals its parent
or every process, starts a daemon, opens a socket, writes outside its folder or runs a program
makes kingen answer exit 1 with a failed ``sandbox`` check naming what it did, kingen itself
never stopped or killed, nothing it started left running and nothing written. Each plugin
is the correct probe of tests/test_hostile.py with one constructor added (compiled here)."""

import hashlib
import json
import os
import shutil
import subprocess
import sys
import time

import pytest

from test_hostile import ROBOT, plugin_source

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the sandbox is Linux's")

def spinner(tmp_path):
    """The name a test's plugin daemon gives itself (prctl PR_SET_NAME, at most 15 characters):
    its mark in the process table, the test's own (tests may run side by side)."""
    return "kg" + hashlib.sha256(str(tmp_path).encode()).hexdigest()[:12]
HEADERS = "#include <signal.h>\n#include <sys/prctl.h>\n#include <sys/socket.h>\n#include <stdio.h>\n"


def constructor(body):
    return HEADERS + f"__attribute__((constructor)) static void hostile(void) {{ {body} }}"


def verify(tmp_path, body, *command_prefix, env=None):
    """``kingen verify`` of the probe with ``body`` in a constructor, as a user runs it (in a
    session of its own: were a signal to reach the test's process group, the test survives);
    its result, and the seconds it took."""
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    source = tmp_path / "kin_probe.c"
    source.write_text(plugin_source(CONSTRUCTOR=constructor(body)))
    start = time.monotonic()
    result = subprocess.run([*command_prefix, sys.executable, "-m", "kingen.cli", "verify", str(robot), "--source",
                             str(source), "-o", str(tmp_path / "lib"), "--samples", "200", "--timeout", "10",
                             "--json", str(tmp_path / "report.json")],
                            capture_output=True, text=True, timeout=120, cwd=tmp_path, start_new_session=True,
                            stdin=subprocess.DEVNULL, env=env)
    assert "Traceback" not in result.stderr, result.stderr
    return result, time.monotonic() - start


def spinners(name):
    """The pids of processes called ``name`` still running (zombies are ended)."""
    found = []
    for entry in os.listdir("/proc"):
        try:
            with open(f"/proc/{entry}/stat") as stream:
                called, rest = stream.read().split("(", 1)[1].rsplit(")", 1)
        except (OSError, IndexError):
            continue
        if called == name and rest.split()[0] != "Z":
            found.append(int(entry))
    return found


def isolation(tmp_path):
    return json.loads((tmp_path / "report.json").read_text())["isolation"]


def test_the_probe_passes_in_the_sandbox_and_the_report_names_it(tmp_path):
    result, _ = verify(tmp_path, "")
    assert result.returncode == 0, result.stdout + result.stderr
    assert isolation(tmp_path) in result.stdout
    assert isolation(tmp_path).startswith(("sandbox: user, PID, network, mount and IPC namespaces of its own",
                                           "no namespaces"))


SIGNALS = {
    "SIGSTOP to its parent": ("kill(getppid(), SIGSTOP);", "called kill(1, SIGSTOP)"),
    "SIGKILL to its parent": ("kill(getppid(), SIGKILL);", "called kill(1, SIGKILL)"),
    "SIGKILL to every process": ("kill(-1, SIGKILL);", "called kill(-1, SIGKILL)"),
    "SIGSTOP to its process group": ("kill(0, SIGSTOP);", "called kill(0, SIGSTOP)"),
}


@pytest.mark.parametrize("name", sorted(SIGNALS))
def test_a_signal_to_a_process_outside_the_plugin_is_refused_and_named(tmp_path, name):
    """kingen is neither stopped nor killed (it answers, within the test's time limit), and
    names the call; in the sandbox's PID namespace the plugin's parent is pid 1."""
    body, words = SIGNALS[name]
    result, seconds = verify(tmp_path, body)
    assert result.returncode == 1, result.stdout + result.stderr
    stage = "during loading the plugin (its constructors and get_kin_config), which the sandbox refused"
    if isolation(tmp_path).startswith("sandbox"):
        assert f"FAILED sandbox: the plugin {words} {stage}: the run was stopped" in result.stdout, result.stdout
    else:
        assert "FAILED sandbox: the plugin called kill(" in result.stdout, result.stdout
    assert seconds < 60


@pytest.mark.parametrize("how", ["fork", "setsid and a double fork"])
def test_a_daemon_the_plugin_starts_is_named_and_ended(tmp_path, how):
    """A constructor that forks (and detaches with setsid) a sleeping process: the run fails
    naming it, the process is gone when kingen has answered, and kingen's $TMPDIR is left empty."""
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    spin = f'prctl(PR_SET_NAME, "{spinner(tmp_path)}"); for (;;) sleep(1);'
    body = {"fork": f"if (fork() == 0) {{ {spin} }}",
            "setsid and a double fork": f"if (fork() == 0) {{ setsid(); if (fork() == 0) {{ {spin} }} _exit(0); }}"}[how]
    result, _ = verify(tmp_path, body, env={**os.environ, "TMPDIR": str(temporary)})
    left = spinners(spinner(tmp_path))
    for pid in left:
        os.kill(pid, 9)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "FAILED sandbox: the plugin left 1 process running when its job ended, which kingen ended" in result.stdout
    assert left == []
    assert list(temporary.iterdir()) == []


def test_a_socket_is_refused_and_named(tmp_path):
    result, _ = verify(tmp_path, "socket(AF_INET, SOCK_STREAM, 0);")
    assert result.returncode == 1, result.stdout + result.stderr
    assert "FAILED sandbox: the plugin called socket(AF_INET) during loading the plugin" in result.stdout


def test_a_write_outside_the_plugins_folder_is_refused_and_named(tmp_path):
    outside = tmp_path / "outside.txt"
    result, _ = verify(tmp_path, f'FILE *f = fopen("{outside}", "w"); if (f) {{ fputs("x", f); fclose(f); }}')
    assert result.returncode == 1, result.stdout + result.stderr
    assert f"FAILED sandbox: the plugin opened {outside} for writing during loading the plugin" in result.stdout
    assert not outside.exists()


def test_running_a_program_is_refused_and_named(tmp_path):
    marker = tmp_path / "the-shell-ran"
    result, _ = verify(tmp_path, f'execl("/bin/sh", "sh", "-c", "touch {marker}", (char *)0);')
    assert result.returncode == 1, result.stdout + result.stderr
    assert "FAILED sandbox: the plugin called execve(/bin/sh) during loading the plugin" in result.stdout
    assert not marker.exists()


@pytest.mark.skipif(shutil.which("unshare") is None, reason="needs util-linux's unshare")
def test_where_the_kernel_refuses_namespaces_the_report_says_so_and_the_filter_still_names(tmp_path):
    """A user namespace that may create none (max_user_namespaces 0), as an unprivileged
    container is: the run falls back on a child without namespaces and says so; the filter
    still refuses a signal to kingen and names it."""
    prefix = ("unshare", "--user", "--map-root-user", "sh", "-c",
              'echo 0 > /proc/sys/user/max_user_namespaces && exec "$@"', "sh")
    probe = subprocess.run([*prefix, "true"], capture_output=True)
    if probe.returncode != 0:
        pytest.skip("this kernel lets no user namespace be made here")
    result, _ = verify(tmp_path, "", *prefix)
    assert result.returncode == 0, result.stdout + result.stderr
    assert isolation(tmp_path).startswith("no namespaces (the kernel refuses them: unshare: No space left on device)")
    assert "a child process of your user, with your user's access; a seccomp filter" in isolation(tmp_path)
    result, _ = verify(tmp_path, "kill(getppid(), SIGSTOP);", *prefix)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "FAILED sandbox: the plugin called kill(" in result.stdout and ", SIGSTOP) during loading" in result.stdout


def test_linuxcncs_interpreter_dies_with_a_killed_kingen(tmp_path):
    """check-path reads G-code through LinuxCNC's interpreter in a child process; a program
    that never ends keeps it busy, and SIGKILL of kingen (nothing of kingen runs to end it)
    ends it too (PR_SET_PDEATHSIG)."""
    from test_check_path import needs_interpreter
    from test_hostile import _children

    needs_interpreter()
    program = tmp_path / "endless.ngc"
    program.write_text("G21 G90\no100 while [1]\no100 endwhile\nM2\n")
    kingen = subprocess.Popen([sys.executable, "-m", "kingen.cli", "check-path", "linuxcnc_hexapod", str(program)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL,
                              cwd=tmp_path)
    deadline, interpreter = time.monotonic() + 60, []
    while not interpreter and time.monotonic() < deadline and kingen.poll() is None:
        time.sleep(0.2)
        interpreter = [pid for pid in _children(kingen.pid) if "linuxcnc_canon" in _command(pid)]
    assert interpreter, "the interpreter never started"
    kingen.kill()
    kingen.wait()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and os.path.exists(f"/proc/{interpreter[0]}"):
        time.sleep(0.1)
    alive = os.path.exists(f"/proc/{interpreter[0]}") and "linuxcnc_canon" in _command(interpreter[0])
    if alive:
        os.kill(interpreter[0], 9)
    assert not alive


def _command(pid):
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as stream:
            return stream.read().decode(errors="replace")
    except OSError:
        return ""


def _forged_report(robot, plugin, options, **ignored):
    """What a routine that took its child over could send with the channel's key: a report of
    its own making in which every check passed."""
    from kingen.verify.processes import empty_report
    from kingen.verify.report import Check

    report = empty_report(robot, plugin.routine, options)
    report.checks = [Check("values", True, "max |error| 0 mm"), Check("warnings", True, "0 mismatches")]
    return report


@pytest.mark.parametrize("answers", ["the routine's", "none"])
def test_a_forged_passing_report_of_a_wrong_routine_fails(tmp_path, monkeypatch, capsys, answers):
    """The routine is 1 mm off everywhere; its child sends a forged report that passes (with
    the routine's real answers on the sample's first poses, or none): kingen's own process
    compares those answers with the reference itself, and the run fails check 'report'."""
    from kingen.cli import main
    import kingen.verify

    monkeypatch.setattr(kingen.verify, "verify", _forged_report)
    if answers == "none":
        monkeypatch.setattr(kingen.verify, "answers", None)  # the child then sends nothing but its report
        monkeypatch.setattr(kingen.verify, "_verify_job", lambda channel, robot, library, routine, host, options:
                            _forged_report(robot, host.load(library, routine, robot), options))
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    source = tmp_path / "kin_probe.c"
    source.write_text(plugin_source().replace("- 100.0;", "- 99.0;"))
    code = main(["verify", str(robot), "--source", str(source), "-o", str(tmp_path / "lib"), "--samples", "200"])
    out = capsys.readouterr().out
    assert code == 1, out
    if answers == "none":
        assert ("FAILED report: the host process said values passed but sent no answers on the first 64 poses for "
                "kingen to compare itself: its report was not used") in out, out
    else:
        assert ("FAILED report: the host process said values passed, but the routine's answers on the first 64 "
                "poses, compared with the reference in kingen's own process, are off by up to 1 mm") in out, out


def test_a_signal_to_a_process_of_yours_outside_kingen_is_refused_and_named(tmp_path):
    """This test's own process (SIGWINCH: harmless were it delivered): outside the sandbox,
    and no process the plugin started."""
    result, _ = verify(tmp_path, f"kill({os.getpid()}, SIGWINCH);")
    assert result.returncode == 1, result.stdout + result.stderr
    assert f"FAILED sandbox: the plugin called kill({os.getpid()}, SIGWINCH) during loading the plugin" in result.stdout


@pytest.mark.parametrize("missing", ["the filter", "the filter and the namespaces"])
def test_without_libseccomp_or_namespaces_the_run_goes_on_and_says_so(tmp_path, monkeypatch, capsys, missing):
    """Where libseccomp is missing (and the kernel refuses namespaces too) a right routine
    still passes, and the report's isolation line says what the run lacked."""
    from kingen.cli import main
    from kingen.runtime import isolation, sandbox

    monkeypatch.setattr(isolation, "filtering_available", lambda: "libseccomp or its binding pyseccomp is missing")
    if missing != "the filter":
        monkeypatch.setattr(sandbox, "_namespaces", lambda folder, network: "the kernel refuses them: refused here")
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    source = tmp_path / "kin_probe.c"
    source.write_text(plugin_source())
    code = main(["verify", str(robot), "--source", str(source), "-o", str(tmp_path / "lib"), "--samples", "200"])
    out = capsys.readouterr().out
    assert code == 0, out
    if missing == "the filter":
        assert ("isolation: sandbox: user, PID, network, mount and IPC namespaces of its own, the file system "
                "read-only but its folder; no seccomp filter (libseccomp or its binding pyseccomp is missing); "
                "limits on processor time, memory, file size and processes") in out, out
    else:
        assert ("isolation: no namespaces (the kernel refuses them: refused here): a child process of your user, "
                "with your user's access; no seccomp filter (libseccomp or its binding pyseccomp is missing); "
                "limits on processor time, memory, file size") in out, out


def test_nothing_a_plugin_started_outlives_a_kingen_killed_with_sigkill(tmp_path):
    """A constructor starts a detached daemon, then the plugin spins; kingen is killed with
    SIGKILL (nothing of it runs to clean up): the daemon ends all the same."""
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    source = tmp_path / "kin_probe.c"
    spin = f'prctl(PR_SET_NAME, "{spinner(tmp_path)}"); for (;;) sleep(1);'
    source.write_text(plugin_source(
        CONSTRUCTOR=constructor(f"if (fork() == 0) {{ setsid(); if (fork() == 0) {{ {spin} }} _exit(0); }}"),
        ROUTINE="for (;;) ;"))
    kingen = subprocess.Popen([sys.executable, "-m", "kingen.cli", "verify", str(robot), "--source", str(source), "-o",
                               str(tmp_path / "lib"), "--timeout", "600"], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL, cwd=tmp_path, start_new_session=True)
    deadline = time.monotonic() + 60
    while not spinners(spinner(tmp_path)) and time.monotonic() < deadline and kingen.poll() is None:
        time.sleep(0.2)
    assert spinners(spinner(tmp_path)), "the plugin's daemon never started"
    kingen.kill()
    kingen.wait()
    deadline = time.monotonic() + 10
    while spinners(spinner(tmp_path)) and time.monotonic() < deadline:
        time.sleep(0.1)
    left = spinners(spinner(tmp_path))
    for pid in left:
        os.kill(pid, 9)
    assert left == []
