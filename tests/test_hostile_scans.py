"""Hostile inputs that used to escape the watchdog or the wording (issue 23, items 4, 11, 12):
reading a library's build information stays linear however its bytes repeat the marker;
a FIFO, device or folder given as an input file is refused up front, never opened for
reading; the compiler's temporaries go to a folder of its own that is always removed; a
comparing process killed from outside is not called a crash of the routine; bench verifies
a floor before timing it; and the build information is reported as a label, not a proof."""

import os
import signal
import subprocess
import sys
import time

import pytest

from kingen.errors import KingenError
from kingen.runtime.library_info import BUILD_INFO_MARKER, build_info
from test_hostile import ROBOT, _children, plugin_source, run_kingen

MARKER = BUILD_INFO_MARKER.encode()
INFO = b" robot=probe routine=kin_probe dof=1 postures=1 sha256=abc kingen=0.1.0"


@pytest.mark.parametrize("unit", [MARKER, MARKER + b"\x01", MARKER + b"ka" * 500 + b"\x01",
                                  MARKER + b"a" * 2000 + b"\x00"],
                         ids=["markers", "marker-then-byte", "marker-then-kaka", "marker-then-too-long"])
def test_a_library_of_repeated_markers_is_read_in_linear_time(tmp_path, unit):
    library = tmp_path / "big.so"
    library.write_bytes(unit * (50_000_000 // len(unit)) + MARKER + INFO + b"\x00")
    start = time.perf_counter()
    info = build_info(library)
    assert time.perf_counter() - start < 3.0  # the old search: about 55 s for 50 MB of markers
    assert info == {"robot": "probe", "routine": "kin_probe", "dof": "1", "postures": "1", "sha256": "abc",
                    "kingen": "0.1.0"}


@pytest.mark.parametrize("data, found", [
    (MARKER + INFO + b"\x00", True),
    (MARKER * 3 + INFO + b"\x00", True),  # the marker nearest the text is read
    (MARKER + INFO, False),  # no NUL
    (MARKER + b"\x00", False),  # no text
    (MARKER + b"a" * 1001 + b"\x00", False),  # more than 1000 bytes
    (MARKER + b" robot=a:b\x00", False),  # kingen never writes a ':' there
], ids=["plain", "after-markers", "no-nul", "no-text", "too-long", "colon"])
def test_what_counts_as_build_information(tmp_path, data, found):
    library = tmp_path / "lib.so"
    library.write_bytes(b"\x7fELF\x00\x01" + data + b"\x01tail")
    assert (build_info(library) is not None) == found


def _fifo(tmp_path, name):
    path = tmp_path / name
    os.mkfifo(path)
    return path


@pytest.mark.parametrize("argv", [
    ["info", "{fifo}"],
    ["info", "/dev/zero"],
    ["verify", "{fifo}"],
    ["verify", "{robot}", "--golden", "{fifo}"],
    ["verify", "{robot}", "--plugin", "{fifo}"],
    ["verify", "{robot}", "--source", "{fifo}"],
    ["bench", "{robot}", "--floor", "{fifo}"],
    ["golden", "record", "{robot}", "--source", "{fifo}", "-o", "{tmp}/snapshot.json"],
    ["verify", "{folder}"],
    ["check-path", "hexapod", "{fifo}"],
    ["check-path", "hexapod", "/dev/zero"],
    ["check-path", "hexapod", "{tmp}/program.csv", "--ini", "{fifo}"],
    ["calibrate", "hexapod", "--measurements", "{fifo}"],
    ["calibrate", "hexapod", "--measurements", "/dev/zero"],
    ["calibrate", "hexapod", "--measurements", "{tmp}/program.csv", "--validate", "{fifo}"],
])
def test_special_input_files_are_refused_up_front(tmp_path, argv):
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    fifo = _fifo(tmp_path, "input")
    (tmp_path / "folder.yaml").mkdir()
    (tmp_path / "program.csv").write_text("x,y,z,roll,pitch,yaw\n")
    names = {"fifo": fifo, "robot": robot, "tmp": tmp_path, "folder": tmp_path / "folder.yaml"}
    result = run_kingen(tmp_path, *[word.format(**names) for word in argv], timeout=30)
    assert result.returncode == 2, result.stdout + result.stderr
    assert len(result.stderr.splitlines()) == 1 and "not a regular file (" in result.stderr, result.stderr


def test_a_fifo_swapped_in_after_the_check_is_still_not_read(tmp_path, monkeypatch):
    """read_limited opens without blocking and checks the open file again: a FIFO that
    takes a regular file's place after the first look is refused, not waited on."""
    from kingen.runtime import file_gate

    fifo = _fifo(tmp_path, "snapshot.json")
    monkeypatch.setattr(file_gate, "refuse_special_file", lambda path: None)  # as if it were swapped in since
    signal.alarm(10)  # a regression hangs here: fail instead
    try:
        with pytest.raises(KingenError, match=r"snapshot.json: not a regular file \(a FIFO\)"):
            file_gate.read_limited(fifo, 1 << 20, "not a kingen snapshot")
    finally:
        signal.alarm(0)


FAKE_COMPILER = """#!/bin/sh
echo "$TMPDIR" >> "{record}"
touch "$TMPDIR/ccFAKE.s"
{rest}
"""


def _fake_compiler(tmp_path, rest):
    compiler = tmp_path / "fake-cc"
    compiler.write_text(FAKE_COMPILER.format(record=tmp_path / "record", rest=rest))
    compiler.chmod(0o755)
    return compiler


def test_the_compiler_gets_a_private_temporary_folder_that_is_removed(tmp_path, monkeypatch):
    import tempfile

    from kingen.runtime.compiler import compile_c

    scratch = tmp_path / "tmp"
    scratch.mkdir()
    monkeypatch.setenv("TMPDIR", str(scratch))
    monkeypatch.setattr(tempfile, "tempdir", None)  # tempfile reads $TMPDIR again
    source = tmp_path / "one.c"
    source.write_text("int one(void) { return 1; }\n")
    compiler = _fake_compiler(tmp_path, 'exec cc "$@"')
    compile_c([source], tmp_path / "libone.so", ["-shared", "-fPIC"], compiler=[str(compiler)])
    compile_c([source], tmp_path / "libone.so", ["-shared", "-fPIC"])  # the real compiler, its cc*.s and all
    private = (tmp_path / "record").read_text().split()
    assert len(private) == 1 and os.path.dirname(private[0]) == str(scratch)
    assert list(scratch.iterdir()) == []  # the private folder, ccFAKE.s with it, is gone


def test_sigterm_during_a_build_leaves_no_compiler_temporaries(tmp_path):
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    compiler = _fake_compiler(tmp_path, "exec sleep 60")
    environment = {**os.environ, "TMPDIR": str(scratch), "CC": str(compiler), "KINGEN_CACHE": str(tmp_path / "cache")}
    process = subprocess.Popen([sys.executable, "-m", "kingen.cli", "build", str(robot), "-o", str(tmp_path / "lib")],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path, env=environment)
    deadline = time.monotonic() + 30
    while not (tmp_path / "record").exists() and time.monotonic() < deadline:
        time.sleep(0.1)
    assert (tmp_path / "record").exists(), "the compiler never started"
    time.sleep(0.3)
    process.send_signal(signal.SIGTERM)
    assert process.wait(timeout=20) == 128 + signal.SIGTERM
    assert list(scratch.iterdir()) == []


def test_a_comparing_process_killed_from_outside_is_not_called_a_crash(plugin, monkeypatch):
    from kingen.verify import VerifyOptions, chunk_size, verify
    from kingen.verify import processes as verify_module

    robot, routine = plugin("tau")
    this = os.getpid()
    compare_chunk = verify_module._compare_chunk

    def killed_in_helpers(poses, first=False):
        if os.getpid() != this:
            os.kill(os.getpid(), signal.SIGKILL)  # as the out-of-memory killer would
        return compare_chunk(poses, first)

    monkeypatch.setattr(verify_module, "_compare_chunk", killed_in_helpers)
    chunk = chunk_size(robot)
    report = verify(robot, routine, VerifyOptions(samples=2 * chunk + 5, processes=2))
    crashes = [check for check in report.checks if check.name == "crash"]
    assert len(crashes) == 1 and not crashes[0].passed
    assert (f"a comparing process was killed by signal SIGKILL (9) from outside (possibly the out-of-memory killer) "
            f"during poses {chunk} to {2 * chunk - 1} of seed 0, not ended by the routine") in crashes[0].detail
    assert "crashed" not in crashes[0].detail


def test_the_host_process_killed_from_outside_is_not_called_a_crash(tmp_path):
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    source = tmp_path / "kin_probe.c"
    source.write_text(plugin_source(ROUTINE="for (;;) ;"))
    process = subprocess.Popen([sys.executable, "-m", "kingen.cli", "verify", str(robot), "--source", str(source),
                                "-o", str(tmp_path / "lib"), "--timeout", "600"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path, text=True)
    deadline = time.monotonic() + 30
    forked = []  # the verify child: forked from kingen, so its command line, for 0.5 s (not the compiler)
    while not forked and time.monotonic() < deadline:
        kingen = _command_line(process.pid)
        found = [pid for pid in _children(process.pid) if _command_line(pid) == kingen]
        time.sleep(0.5)
        forked = [pid for pid in found if _command_line(pid) == kingen]
    assert forked, "the child process never started"
    os.kill(forked[0], signal.SIGKILL)
    out, err = process.communicate(timeout=30)
    assert process.returncode == 1, out + err
    assert "FAILED crash: the host process was killed by signal SIGKILL (9) from outside (possibly the " \
           "out-of-memory killer) during" in out
    assert "the plugin ended" not in out


def _command_line(pid):
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as stream:
            return stream.read()
    except OSError:
        return None


def test_bench_refuses_a_floor_that_fails_verification(tmp_path):
    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    floor = tmp_path / "zero.c"
    floor.write_text(plugin_source(ROUTINE="solutions[0][0] = 0.0; warnings[0] = WARN_GOOD_SOLUTION; return 0;"))
    figures = tmp_path / "bench.json"
    result = run_kingen(tmp_path, "bench", str(robot), "--floor", str(floor), "--calls", "1000", "-o",
                        str(tmp_path / "out"), "--json", str(figures))
    assert result.returncode == 1, result.stdout + result.stderr
    assert len(result.stderr.splitlines()) == 1
    assert result.stderr.startswith(f"kingen: plugin failed: the floor {floor} fails verification on 2000 poses (")
    assert "first values: max |error| " in result.stderr
    assert "ratio" not in result.stdout and not figures.exists()


def test_build_information_is_reported_as_a_label_not_a_proof(tmp_path):
    from kingen.robot.model import load_robot

    robot = tmp_path / "probe.yaml"
    robot.write_text(ROBOT)
    sha = load_robot(str(robot)).sha256
    forged = (f'const char kingen_build_info[] = "kingen-build-info: robot=probe routine=kin_probe dof=1 '
              f'postures=1 sha256={sha} kingen=0.1.0";')
    source = tmp_path / "kin_probe.c"
    source.write_text(plugin_source(CONSTRUCTOR=forged))  # hand-written, not kingen's
    result = run_kingen(tmp_path, "verify", str(robot), "--source", str(source), "-o", str(tmp_path / "lib"),
                        "--samples", "200")
    assert result.returncode == 0, result.stdout
    assert ("ok     definition: the library says it was built by kingen 0.1.0 from this robot file (sha256 "
            f"{sha[:16]}; a label it carries, not a proof)") in result.stdout
    result = run_kingen(tmp_path, "info", str(tmp_path / "lib" / "libprobe.so"))
    assert result.returncode == 0
    assert "says it was built by: kingen 0.1.0\n" in result.stdout
    assert result.stdout.endswith("note: the lines above are the library's build information, a label it carries, "
                                  "not a proof that kingen built it\n")
