"""Issue 23's hostile cases on outputs, caches, geometry and numbers: special files are
written in place and never replaced, a cache another user could have written is refused and
every cached source is checked against the text kingen computes, a zero-length leg is not a
false FAIL, out-of-range numbers are bad input, write failures name the real path.

Cases that need root (device nodes, another user's files, a full disk) run inside a private
mount namespace (``unshare -m``) so the machine's own /dev and disks are never touched; in
CI, which runs as root, they fail rather than skip."""

import json
import os
import shutil
import stat
import subprocess
import sys

import jinja2
import pytest

from conftest import skip_or_fail
from kingen.cli import main
from kingen.errors import KingenError
from kingen.runtime.files import write_atomic
from kingen.hosts.delmia.build import host_support


def require_root():
    if os.geteuid() != 0 or shutil.which("unshare") is None:
        skip_or_fail("needs root and unshare (CI runs as root)")


def in_private_mounts(script, tmp_path):
    """Run ``script`` (sh) in a private mount namespace with a fresh tmpfs at tmp_path/mnt."""
    (tmp_path / "mnt").mkdir()
    return subprocess.run(["unshare", "-m", "sh", "-ec", f"mount --make-rprivate / && {script}"],
                          capture_output=True, text=True, timeout=300,
                          env={**os.environ, "MNT": str(tmp_path / "mnt"), "PY": sys.executable})


# --- 1. special files

def test_a_fifo_is_written_in_place_never_replaced(tmp_path, capsys):
    fifo = tmp_path / "report.fifo"
    os.mkfifo(fifo)
    reader = subprocess.Popen(["cat", str(fifo)], stdout=subprocess.PIPE)
    assert main(["fk", "tau", "--joints", "417.207213586 361.089021702 265.814725691", "--json", str(fifo)]) == 0
    received = reader.communicate(timeout=30)[0]
    assert json.loads(received)["robot"] == "tau" and stat.S_ISFIFO(os.lstat(fifo).st_mode)


def test_a_symlink_keeps_pointing_at_its_target(tmp_path):
    target = tmp_path / "real.json"
    target.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    write_atomic(link, "new")
    assert link.is_symlink() and target.read_text() == "new"


def test_json_to_dev_stdout_reaches_stdout(tmp_path):
    done = subprocess.run([sys.executable, "-m", "kingen.cli", "fk", "tau", "--joints",
                           "417.207213586 361.089021702 265.814725691", "--json", "/dev/stdout"],
                          capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert done.returncode == 0 and '"robot": "tau"' in done.stdout


def test_a_device_node_stays_a_device(tmp_path):
    require_root()
    done = in_private_mounts(
        'mount -t tmpfs tmpfs "$MNT" && mknod "$MNT/null" c 1 3 && chmod 666 "$MNT/null" && '
        '"$PY" -m kingen.cli fk tau --joints "417.207213586 361.089021702 265.814725691" --json "$MNT/null" '
        '>/dev/null && test -c "$MNT/null" && test ! -s "$MNT/null" && echo still-a-device', tmp_path)
    assert "still-a-device" in done.stdout, done.stderr


# --- 2. shared caches

def test_a_cache_others_may_write_is_refused(tmp_path, monkeypatch, capsys):
    cache = tmp_path / "cache"
    cache.mkdir()
    cache.chmod(0o777)
    monkeypatch.setenv("KINGEN_CACHE", str(cache))
    assert main(["build", "tau", "-o", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1 and "is writable by others" in error and "KINGEN_CACHE" in error


def test_a_tampered_cached_header_is_rebuilt_from_kingens_text(tmp_path, monkeypatch):
    monkeypatch.setenv("KINGEN_CACHE", str(tmp_path / "cache"))
    include, library = host_support()
    header = include / "shlibdefs.h"
    original, built = header.read_text(), library.read_bytes()
    header.write_text(original + "\n__attribute__((constructor)) static void planted(void) {}\n")
    include_again, library_again = host_support()
    assert (include_again / "shlibdefs.h").read_text() == original
    assert library_again.read_bytes() == built or library_again.stat().st_mtime >= library.stat().st_mtime


def test_a_cache_under_umask_002_stays_private_and_usable(tmp_path, monkeypatch):
    monkeypatch.setenv("KINGEN_CACHE", str(tmp_path / "cache"))
    old = os.umask(0o002)
    try:
        include, library = host_support()
        host_support()  # the second use accepts what the first made
    finally:
        os.umask(old)
    for path in (include, library, include / "shlibdefs.h"):
        assert not os.stat(path).st_mode & 0o022


def test_a_cache_folder_another_user_owns_is_refused(tmp_path, monkeypatch, capsys):
    require_root()
    monkeypatch.setenv("KINGEN_CACHE", str(tmp_path / "cache"))
    include, library = host_support()
    for path in [include.parent, *include.parent.rglob("*")]:
        os.chown(path, 65534, 65534)
    library.write_bytes(library.read_bytes())  # planted: the stamp could be recomputed by its owner
    with pytest.raises(KingenError, match="is owned by another user"):
        host_support()


def plant_compiled_template(name, planted_text):
    """Compile DELMIA's template ``name`` with ``planted_text`` appended, and store that
    code in kingen's template cache under the real source's key and checksum (as another
    user could, into a cache they may write): the file a render would load."""
    from kingen.hosts.delmia.render import TEMPLATES
    from kingen.hosts.render import _partial_source
    from kingen.runtime.templates import _environment

    environment = _environment("c", TEMPLATES, _partial_source)
    source, filename, _ = environment.loader.get_source(environment, name)
    cache = environment.bytecode_cache
    bucket = jinja2.bccache.Bucket(environment, cache.get_cache_key(name, filename), cache.get_source_checksum(source))
    bucket.code = environment.compile(source + planted_text, name, filename)
    path = cache._path(bucket)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as stream:
        bucket.write_bytecode(stream)
    return path


@pytest.fixture
def render_afresh():
    """render_afresh(name) -> the shipped robot's DELMIA source, rendered by new template
    environments (nothing compiled in this process: what a new process loads or compiles);
    they are dropped again after the test."""
    from kingen.hosts.delmia.render import render
    from kingen.robot.model import load_robot
    from kingen.runtime.templates import _environment

    def rendered(name):
        _environment.cache_clear()
        return render(load_robot(name))[f"kin_{name}.c"]

    yield rendered
    _environment.cache_clear()


@pytest.mark.parametrize("mode, loaded", [(0o600, True), (0o620, False), (0o602, False)])
def test_compiled_templates_are_loaded_only_from_a_private_file(tmp_path, monkeypatch, render_afresh, mode, loaded):
    """A planted compiled template is rendered from a private file (so that the test can
    tell) and never from one its group or others may write."""
    monkeypatch.setenv("KINGEN_CACHE", str(tmp_path / "cache"))
    render_afresh("tau")  # compiles into this cache
    plant_compiled_template("kin_robot.c.j2", "/* planted */\n").chmod(mode)
    assert render_afresh("tau").endswith("/* planted */\n") == loaded


def test_an_unwritable_or_junk_template_cache_still_renders(tmp_path, monkeypatch, render_afresh):
    monkeypatch.setenv("KINGEN_CACHE", str(tmp_path / "cache"))
    expected = render_afresh("tau")
    compiled = list((tmp_path / "cache").glob("templates-*/*.jinja"))
    assert compiled and all(stat.S_IMODE(path.stat().st_mode) == 0o600 for path in compiled)
    for path in compiled:
        path.write_bytes(path.read_bytes()[:40])  # cut short
    assert render_afresh("tau") == expected
    monkeypatch.setenv("KINGEN_CACHE", "/proc/kingen-cache")  # cannot be made
    assert render_afresh("tau") == expected


# --- 5. a leg of no length

def test_a_leg_whose_ends_meet_is_not_a_false_fail(tmp_path, capsys):
    limbs = [("[-582.93, 336.55, 0]", "[-25.4, 292.1, 0]"), ("[582.93, 336.55, 0]", "[25.4, 292.1, 0]"),
             ("[582.93, 336.55, 0]", "[265.6586, -124.0536, 0]"), ("[0, -673.1, 0]", "[240.2586, -168.0464, 0]"),
             ("[0, -673.1, 0]", "[-240.2586, -168.0464, 0]"), ("[-582.93, 336.55, 0]", "[-265.6586, -124.0536, 0]")]
    limbs[0] = ("[-25.4, 292.1, 508]", limbs[0][1])  # its base point is its platform point at home
    text = "\n".join(f"  - {{model: leg, base_point: {base}, platform_point: {top}, reference_length: 0}}"
                     for base, top in limbs)
    robot = tmp_path / "meet.yaml"
    robot.write_text(f"name: meet\ndescription: a leg of no length at home\nlimbs:\n{text}\n"
                     "verification: {home: [0, 0, 508, 0, 0, 0], range: [0, 0, 0, 0, 0, 0]}\n")
    assert main(["verify", str(robot), "--samples", "200", "-o", str(tmp_path / "out")]) == 1
    out = capsys.readouterr()
    # only the machine itself fails: a leg of no length has no force line, its direct index is 0
    failed = [line for line in out.out.splitlines() if line.startswith("  FAILED")]
    assert len(failed) == 1 and failed[0].startswith("  FAILED machine: the direct index at the verification home is 0 mm")
    assert "FAILED (1 of 14 checks)" in out.out
    assert "RuntimeWarning" not in out.err


# --- 7. numbers

@pytest.mark.parametrize("near", [["1e308", "0", "0", "0", "0", "0"], ["nan", "0", "0", "0", "0", "0"],
                                  ["0", "0", "0", "0", "1e4", "0"]])
def test_fk_refuses_a_near_pose_out_of_range(near, tmp_path, capsys):
    assert main(["fk", "tau", "--joints", "417.2 361 265.8", "--near", *near, "--json", str(tmp_path / "a.json")]) == 2
    assert "--near" in capsys.readouterr().err and not (tmp_path / "a.json").exists()


def test_no_switch_is_predicted_for_an_unreachable_posture(capsys):
    assert main(["solve", "tau", "--pose", "5000", "-750", "-1900", "0", "0", "0", "--switch", "0", "1"]) == 0
    out = capsys.readouterr().out
    assert "unreachable at this pose; no switch to predict" in out and "jump" not in out


def test_a_t6_that_is_not_rigid_is_refused(capsys):
    assert main(["solve", "tau", "--t6", *"1 0 0 0 0 2 0 0 0 0 1 0 -1200 -750 -1900 1".split()]) == 2
    assert "not a rigid transform" in capsys.readouterr().err


# --- 8. messages that name the real path, checked before the work

def test_an_output_folder_under_a_file_is_refused_before_the_work(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["analyze", "ceart", "-o", str(blocker / "analysis")]) == 2
    error = capsys.readouterr().err
    assert str(blocker) in error and "is not a folder" in error


def test_a_full_disk_names_the_file_and_leaves_no_folders(tmp_path):
    require_root()
    done = in_private_mounts(
        'mount -t tmpfs -o size=16k tmpfs "$MNT" && head -c 12000 /dev/zero > "$MNT/filler" || true; '
        '"$PY" -m kingen.cli analyze tau -o "$MNT/deep/er" && echo "exit 0" || echo "exit $?"; ls -A "$MNT"',
        tmp_path)
    assert "exit 2" in done.stdout, done.stdout + done.stderr
    error = done.stderr.strip()
    assert len(error.splitlines()) == 1 and "No space left on device" in error and "/deep/er/" in error
    assert "deep" not in done.stdout.split("exit 2")[-1]  # the folders made for the file are gone


def test_a_full_tmpdir_says_so_when_building(tmp_path):
    """The compiler's messages travel through a pipe, not a file in the full $TMPDIR."""
    require_root()
    done = in_private_mounts(
        'mount -t tmpfs -o size=64k tmpfs "$MNT" && head -c 60000 /dev/zero > "$MNT/filler" || true; '
        'TMPDIR="$MNT" "$PY" -m kingen.cli build tau -o "$MNT/../out" && echo "exit 0" || echo "exit $?"', tmp_path)
    assert "exit 2" in done.stdout, done.stdout + done.stderr
    error = done.stderr.strip()
    assert len(error.splitlines()) == 1 and "No space left on device" in error, error


def test_a_key_that_is_a_collection_is_bad_input(tmp_path, capsys):
    """Found by the fuzz test: '? pair_angles: [...]' made ruamel hash a mapping (exit 3)."""
    robot = tmp_path / "complex_key.yaml"
    robot.write_text("name: k\ndescription: d\n? pair_angles: [0, 120]\n")
    assert main(["build", str(robot), "-o", str(tmp_path / "out")]) == 2
    assert "a key must be text" in capsys.readouterr().err
