"""kingen view: the scene's drawing against the limb models and the reference; the command's page
(self-contained, under 5 MB, bad input refused in one line); and the page in headless Chromium
(a missing Chromium or WebAssembly toolchain skips, or fails under KINGEN_REQUIRE_TOOLCHAINS=1):
for a pose of the reference's sample given in the address, the joints its WebAssembly routine
writes into #kingen-joints equal `kingen solve`'s within 1e-9, the machine it draws is the
reference's, and a screenshot shows a drawing."""

import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest
from kingen.conventions import t6_from_pose, wrap_difference
from kingen.kinematics.poses import sample_poses
from kingen.kinematics.reference import solve
from kingen.kinematics.routine import WARNINGS
from kingen.robot.model import load_robot
from kingen.view import machine_at, scene, view_fragment

from conftest import require_tool, skip_or_fail

FAMILIES = ("hexapod", "tau", "ceart", "exechon_wrist", "tricept_wrist3")
"""Six legs, three rails (Gantry-Tau), six cranks, an Exechon with a two-axis wrist, a Tricept with a spherical wrist."""
CHROMIUM = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader", "--disable-quic", "--no-first-run", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--window-size=1000,700", "--virtual-time-budget=8000",
            "--proxy-server=127.0.0.1:9", "--proxy-bypass-list=<-loopback>"]  # offline: any fetch would fail
BACKGROUND = (0xF4, 0xF5, 0xF7)
"""The 3D stage's clear colour (view.js)."""
MAX_BYTES = 5_000_000


def kingen(*arguments):
    return subprocess.run([sys.executable, "-m", "kingen.cli", *arguments], capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("name", ("hexapod", "tau", "ceart", "rotary_delta", "exechon_wrist"))
def test_the_drawing_forms_are_the_limb_models(name):
    """B(q) = c + q a + cos(q) u + sin(q) v and l0 + l1 q, as the scene gives them, are each limb
    model's base-side point and passive length at joints the fit never saw."""
    robot = load_robot(name)
    drawn = scene(robot)["model"]["limbs"]
    joints = np.random.default_rng(51).uniform(-3.0, 3.0, 7)
    for limb, form in zip(robot.parallel.limbs, drawn):
        assert form["exact"], (name, form["name"])
        f = {key: np.asarray(value) for key, value in form["base_side"].items()}
        fitted = f["c"] + joints[:, None] * f["a"] + np.cos(joints)[:, None] * f["u"] + np.sin(joints)[:, None] * f["v"]
        expected = np.asarray(limb.base_side_point(np.zeros((len(joints), 3)), joints))
        np.testing.assert_allclose(fitted, expected, atol=1e-9 * robot.size_mm, err_msg=f"{name} {form['name']}")
        np.testing.assert_allclose(form["passive"][0] + form["passive"][1] * joints, limb.passive_length(joints),
                                   atol=1e-9 * robot.size_mm)


@pytest.mark.parametrize("name", FAMILIES)
def test_the_scene_is_the_reference_at_its_pose(name):
    """The scene's joints and warning are the reference's; each drawn limb closes (its platform
    point its passive length from its base side); a wrist's tool frame is the pose asked."""
    robot = load_robot(name)
    pose = sample_poses(robot, 1, seed=7)[0]
    shown = json.loads(json.dumps(scene(robot, pose, robot.working_posture), allow_nan=False))
    expected = solve(robot, t6_from_pose(pose)[None])
    np.testing.assert_allclose(shown["joints"], expected.joints[0, :, robot.working_posture], atol=1e-12)
    assert WARNINGS[shown["warning"]] == expected.warnings[0, robot.working_posture]
    for limb, drawn, q in zip(robot.parallel.limbs, shown["machine"]["limbs"], shown["joints"]):
        gap = np.linalg.norm(np.subtract(drawn["platform_point"], drawn["base_side"]))
        if drawn["status"] != "unreachable":
            assert gap == pytest.approx(float(limb.passive_length(np.array([q]))[0]), abs=1e-6)
    if robot.wrist is not None and shown["warning"] != "WARN_UNREACHABLE":
        tool = np.asarray(shown["machine"]["tool"])
        asked = t6_from_pose(pose)
        np.testing.assert_allclose(tool[:3, 3], asked[3, :3], atol=1e-6)
        np.testing.assert_allclose(tool[:3, 2], asked[2, :3], atol=1e-9)


def test_the_command_writes_one_page_and_refuses_bad_input(tmp_path):
    done = kingen("view", "tau", "--pose", "-1150", "-700", "-1850", "0", "0", "0", "-o", str(tmp_path))
    assert done.returncode == 0, done.stderr
    page = (tmp_path / "tau.html").read_text()
    assert len(page.encode()) < MAX_BYTES
    assert not re.search(r"""(src|href)=["']?(https?:)?//""", page)  # nothing fetched: the page holds all it needs
    data = json.loads(re.search(r'<script type="application/json" class="kingen-scene">(.*?)</script>', page).group(1))
    assert data["pose"] == [-1150, -700, -1850, 0, 0, 0] and data["robot"] == "tau"
    for arguments, field in ((("--posture", "9"), "--posture"), (("--pose", "0", "0", "nan", "0", "0", "0"), "--pose")):
        refused = kingen("view", "tau", *arguments, "-o", str(tmp_path / "no"))
        assert refused.returncode == 2 and field in refused.stderr and "Traceback" not in refused.stderr
        assert not (tmp_path / "no").exists()


def test_a_scene_refuses_a_pose_or_posture_it_cannot_show():
    from kingen.errors import KingenError

    robot = load_robot("tau")
    for pose, posture, words in (([0, 0, float("nan"), 0, 0, 0], None, "six finite numbers"), ([1, 2, 3], None, "six"),
                                 (None, 8, "posture 8 does not exist")):
        with pytest.raises(KingenError, match=words):
            scene(robot, pose, posture)


def test_the_fragment_holds_the_page_apart():
    robot = load_robot("tau")
    fragment = view_fragment(robot, scene(robot), title="tau <view>", routine=False)
    assert fragment.startswith("<iframe") and fragment.endswith("</iframe>") and "<script" not in fragment
    assert "&lt;script" in fragment and 'title="tau &lt;view&gt;"' in fragment


@pytest.fixture(scope="module")
def page_of(tmp_path_factory):
    """``kingen view NAME``'s page (a real process), made once per robot in this module."""
    made = {}

    def page(name):
        if name not in made:
            folder = tmp_path_factory.mktemp(f"view-{name}")
            done = kingen("view", name, "-o", str(folder))
            assert done.returncode == 0, done.stderr
            made[name] = folder / f"{name}.html"
        return made[name]
    return page


def require_browser():
    require_tool("chromium", "chromium")
    from kingen.hosts.wasm.build import wasm_toolchain

    toolchain = wasm_toolchain()
    if not toolchain.ready:
        skip_or_fail(toolchain.problem)


def sample_pose(robot):
    """A pose of the reference's sample (seeded) that the working posture reaches, and that posture."""
    poses = sample_poses(robot, 50, seed=51)
    warnings = solve(robot, t6_from_pose(poses)).warnings[:, robot.working_posture]
    return poses[int(np.flatnonzero(warnings != WARNINGS["WARN_UNREACHABLE"])[0])], robot.working_posture


def open_page(page, fragment, shot, profile):
    """The page's DOM after it ran, opened with ``fragment`` in headless Chromium, and its
    screenshot; the page's script wrote nothing on the console (WebGL's driver notes aside)."""
    done = subprocess.run([*CHROMIUM, f"--user-data-dir={profile}", f"--screenshot={shot}", "--enable-logging=stderr",
                           "--v=0", "--dump-dom", page.as_uri() + fragment], capture_output=True, text=True, timeout=120)
    said = [line for line in done.stderr.splitlines() if ":CONSOLE" in line and "GL Driver Message" not in line]
    assert said == [], said
    return {key: json.loads(value) for key, value in
            re.findall(r'<pre id="kingen-(joints|drawing)" hidden="">([^<]*)</pre>', done.stdout) if value}


def drawn_pixels(shot):
    """The fraction of the 3D stage's pixels that are not its background, and of bluish ones (limbs)."""
    from matplotlib.image import imread

    pixels = np.round(imread(shot)[:, :, :3] * 255)
    stage = pixels[80:680, 20:580]  # the canvas, left of the side panel, below the title
    return np.mean(np.any(stage != BACKGROUND, axis=-1)), np.mean(stage[:, :, 2] - stage[:, :, 0] > 40)


@pytest.mark.parametrize("name", FAMILIES)
def test_the_page_in_a_real_browser_answers_as_kingen_solve(name, page_of, tmp_path):
    """`kingen view` then the page opened at a sampled pose (#pose=...&posture=K): #kingen-joints
    holds what the WebAssembly routine computed, equal to `kingen solve`'s (the C library and the
    reference it is held to) within 1e-9; the drawing's platform is the reference's; the
    screenshot shows the machine on the stage."""
    require_browser()
    robot = load_robot(name)
    pose, posture = sample_pose(robot)
    page = page_of(name)
    assert page.stat().st_size < MAX_BYTES
    shot = tmp_path / "shot.png"
    found = open_page(page, f"#pose={','.join(repr(float(v)) for v in pose)}&posture={posture}", shot, tmp_path / "profile")
    answer = found["joints"]
    assert answer["by"] == "wasm", answer
    solved = kingen("solve", name, "--pose", *map(repr, map(float, pose)), "--host", "c", "-o", str(tmp_path / "c"),
                    "--json", str(tmp_path / "solve.json"))
    assert solved.returncode == 0, solved.stderr
    expected = json.loads((tmp_path / "solve.json").read_text())["postures"][posture]
    revolute = robot.revolute
    for reference in (expected["joints"], expected["reference_joints"]):
        difference = np.subtract(answer["joints"], reference)
        difference[revolute] = wrap_difference(difference[revolute])
        assert np.max(np.abs(difference)) <= 1e-9, (name, pose, posture, answer, reference)
    assert answer["warning"] == expected["warning"]
    drawing, _, _ = machine_at(robot, t6_from_pose(pose), posture)
    for drawn, limb in zip(found["drawing"]["limbs"], drawing["limbs"]):
        np.testing.assert_allclose(drawn["platform_point"], limb["platform_point"], atol=1e-6 * robot.size_mm)
        np.testing.assert_allclose(drawn["base_side"], limb["base_side"], atol=1e-6 * robot.size_mm)
    covered, bluish = drawn_pixels(shot)
    assert 0.02 < covered < 0.9 and bluish > 0.002, (covered, bluish)



def test_without_a_webassembly_toolchain_the_page_draws_kingens_pose_and_says_why(tmp_path):
    """With the WebAssembly compiler missing ($KINGEN_WASM_CC naming none), `kingen view` still
    writes the page: it shows the joints kingen computed, its sliders greyed, and names what is
    missing."""
    require_tool("chromium", "chromium")
    environment = {**os.environ, "KINGEN_WASM_CC": str(tmp_path / "no-clang")}
    done = subprocess.run([sys.executable, "-m", "kingen.cli", "view", "tau", "-o", str(tmp_path)], capture_output=True,
                          text=True, timeout=300, env=environment)
    assert done.returncode == 0, done.stderr
    assert "sliders need the routine compiled to WebAssembly" in done.stdout and "no-clang is not installed" in done.stdout
    page = tmp_path / "tau.html"
    assert "KingenWasm" not in page.read_text() and "no-clang is not installed" in page.read_text()
    dom = subprocess.run([*CHROMIUM, f"--user-data-dir={tmp_path / 'profile'}", "--dump-dom", page.as_uri()],
                         capture_output=True, text=True, timeout=120).stdout
    answer = json.loads(re.search(r'<pre id="kingen-joints" hidden="">([^<]*)</pre>', dom).group(1))
    robot = load_robot("tau")
    expected = solve(robot, t6_from_pose(np.array([robot.verification.home])))
    assert answer["by"] == "kingen"
    np.testing.assert_allclose(answer["joints"], expected.joints[0, :, robot.working_posture], atol=1e-12)
    assert re.search(r'<input type="range"[^>]*disabled', dom) and "The sliders need the routine" in dom


def test_a_slider_change_joints_and_a_machine_with_task_coordinates_in_a_real_browser(page_of, tmp_path):
    """tau: three input events on its first slider (#bench=3), as a drag makes them: the answer
    written is the reference's at the pose the page then shows. tricept (task x, y, z): the pose
    given in the address becomes the machine's pose for its x, y, z (the module's machine pose),
    and the joints are the reference's there. hexapod: joints given in the address (#joints=)
    move the machine to the pose they were solved at (the routine's forward kinematics)."""
    require_browser()
    from kingen.conventions import pose_from_t6
    from kingen.kinematics.hybrid.parasitic import solve_parasitic

    hexapod_pose = np.array([12.0, -8.0, 490.0, 3.0, -2.0, 5.0])
    hexapod_joints = solve(load_robot("hexapod"), t6_from_pose(hexapod_pose[None])).joints[0, :, 0]
    for name, fragment in (("tau", "#pose=-1150,-700,-1850,0,0,0&posture=1&bench=3"),
                           ("tricept", "#pose=40,-30,-1050,3,-2,9&posture=0"),
                           ("hexapod", f"#joints={','.join(map(repr, map(float, hexapod_joints)))}&posture=0")):
        robot = load_robot(name)
        answer = open_page(page_of(name), fragment, tmp_path / f"{name}.png",
                           tmp_path / f"profile-{name}")["joints"]
        assert answer["by"] == "wasm" and answer["posture"] == int(fragment.split("posture=")[1][0])
        if name == "tau":
            assert answer["pose"][0] != -1150.0 and answer["pose"][1:] == [-700, -1850, 0, 0, 0]  # the first slider moved
        elif name == "hexapod":
            np.testing.assert_allclose(answer["pose"], hexapod_pose, atol=1e-6)
            np.testing.assert_allclose(answer["joints"], hexapod_joints, atol=1e-9)
        else:
            machine = pose_from_t6(solve_parasitic(robot, t6_from_pose(np.array([[40.0, -30, -1050, 3, -2, 9]]))).t6)[0]
            np.testing.assert_allclose(answer["pose"], machine, atol=1e-9)
        expected = solve(robot, t6_from_pose(np.array([answer["pose"]])))
        np.testing.assert_allclose(answer["joints"], expected.joints[0, :, answer["posture"]], atol=1e-9)
        assert WARNINGS[answer["warning"]] == expected.warnings[0, answer["posture"]]


@pytest.mark.parametrize("name, pose", [
    ("tau", [-1945.831, -1223.741, -1357.706, 2.465, -12.176, -2.006]),  # two carriages' links cannot reach
    ("tau", [-1324.87, -593.763, -1471.892, 13.688, -6.474, 4.456]),  # two carriages beyond their travel
    ("exechon_wrist", [-372.916, -186.871, -1088.471, 184.93, -24.352, -4.012]),  # leg2 beyond its travel
    ("tau", [-1587.2588745805463, -750.0, -1900.0, 0.0, 0.0, 0.0]),  # carriage1's link square to its rail
])
def test_the_limbs_colours_in_a_real_browser_are_the_references_statuses(name, pose, page_of, tmp_path):
    """Each limb's colour key the page draws (unreachable, beyond its travel, singular, good) is
    the one kingen.view.scene gives from the reference's radicands and the robot file's travel."""
    require_browser()
    robot = load_robot(name)
    fragment = f"#pose={','.join(map(str, pose))}&posture={robot.working_posture}"
    found = open_page(page_of(name), fragment, tmp_path / "shot.png", tmp_path / "profile")
    expected, _, warning = machine_at(robot, t6_from_pose(np.array(pose)), robot.working_posture)
    assert found["joints"]["warning"] == warning != "WARN_GOOD_SOLUTION"
    assert [limb["status"] for limb in found["drawing"]["limbs"]] == [limb["status"] for limb in expected["limbs"]]


def test_a_registered_limb_model_is_drawn_from_the_forms_its_methods_give(tmp_path):
    """The toy Plumb (tests/test_limb_registry.py: its base side follows the platform point, its
    link's length is |q|) is drawn without naming it: its forms marked not exact (the page does
    not judge its closure), a leg's exact; the scene is JSON and the page is written."""
    from kingen.robot import limbs
    from kingen.view import page_html

    from test_limb_registry import ROBOT, Plumb

    limbs.register(Plumb)
    try:
        path = tmp_path / "toy.yaml"
        path.write_text(ROBOT)
        robot = load_robot(path)
        shown = json.loads(json.dumps(scene(robot), allow_nan=False))
        assert [limb["exact"] for limb in shown["model"]["limbs"]] == [False, True, False]
        assert shown["joints"] == pytest.approx(solve(robot, t6_from_pose(np.zeros((1, 6)))).joints[0, :, 0].tolist())
        assert "kingen-scene" in page_html(robot, shown, title="toy", routine=False)
    finally:
        limbs.unregister(Plumb)


def test_every_overlay_is_drawn_in_a_real_browser(tmp_path):
    """A scene with every overlay (a path's frames with markers, arrows, a ghost, a surface,
    points) opens without a word on the console: the timeline holds one button per marker, the
    legend names the ghost with its factor and the surface, each arrow and point is labelled, and
    the page opens at start_frame with that frame's joints."""
    require_tool("chromium", "chromium")
    from kingen.view import page_html

    robot = load_robot("hexapod")
    shown = scene(robot)
    frames = []
    for t in np.linspace(0.0, 2.0, 21):
        pose = np.array(shown["pose"]) + [30 * np.sin(3 * t), 30 * np.cos(3 * t) - 30, 20 * t, 4 * np.sin(2 * t), 0, 10 * t]
        _, joints, warning = machine_at(robot, t6_from_pose(pose), shown["posture"])
        frames.append({"t": float(t), "pose": pose.tolist(), "joints": joints.tolist(), "warning": warning})
    ghost, _, _ = machine_at(robot, t6_from_pose(np.array(shown["pose"]) + [0, 0, 40, 0, 6, 0]), shown["posture"])
    shown.update(frames=frames, start_frame=5, markers=[{"frame": 5, "label": "line 8"}, {"frame": 15, "label": "line 12"},
                                                   {"frame": 15, "label": "line 12 too"}],
                 arrows=[{"origin": [200.0, 0.0, 0.0], "vector": [0.0, 0.0, 150.0], "label": "residual x1000"}],
                 points=[{"position": [0.0, 0.0, 600.0], "label": "tilt limit"}],
                 surface={"vertices": [[-300, -300, 700], [300, -300, 700], [0, 300, 700]], "triangles": [[0, 1, 2]],
                          "label": "tilt limits"},
                 ghost=dict(ghost, label="identified changes", scale=100))
    page = tmp_path / "overlays.html"
    page.write_text(page_html(robot, shown, title="overlays", routine=False))
    done = subprocess.run([*CHROMIUM, f"--user-data-dir={tmp_path / 'profile'}", "--enable-logging=stderr", "--v=0",
                           "--dump-dom", page.as_uri()], capture_output=True, text=True, timeout=120)
    assert [line for line in done.stderr.splitlines() if ":CONSOLE" in line and "GL Driver Message" not in line] == []
    dom = done.stdout
    buttons = re.findall(r'<button class="kingen-marker" title="([^"]*)"[^>]*>([^<]*)</button>', dom)
    assert buttons == [("1: line 8", "1"), ("2: line 12\n3: line 12 too", "2-3")]  # one button per place
    assert "identified changes (changes shown ×100)" in dom and "tilt limits" in dom
    assert "residual x1000" in dom and "tilt limit" in dom
    answer = json.loads(re.search(r'<pre id="kingen-joints" hidden="">([^<]*)</pre>', dom).group(1))
    assert answer["by"] == "kingen" and answer["joints"] == pytest.approx(frames[5]["joints"], abs=1e-12)


def test_the_postures_are_named_by_their_branches_as_solve_prints_them():
    from kingen.view.scene import posture_branches

    ceart = posture_branches(load_robot("ceart"))
    assert len(ceart) == 64 and ceart[0] == "000000" and ceart[1] == "000001" and ceart[62] == "111110"
    assert posture_branches(load_robot("exechon_wrist")) == ["0", "1"]  # legs of one branch, the wrist's last
    assert posture_branches(load_robot("hexapod")) == ["-"]
    tau = load_robot("tau")
    assert posture_branches(tau) == [f"{k:03b}" for k in range(8)]
    for posture, branches in enumerate(posture_branches(tau)):  # the digit is the limb's branch in that posture
        assert tau.posture_branches(posture) == tuple(int(digit) for digit in branches)


def test_an_address_the_page_cannot_read_is_said_and_the_rest_shown_in_a_real_browser(page_of, tmp_path):
    """hexapod (one posture): an address that is not six numbers, or names a posture the robot has
    not, leaves the page at what it can read (the home pose, or the address's pose in the working
    posture) with the reference's joints there; #kingen-joints carries ``address_warning`` naming
    each part left out (the note says the same), and nothing is written on the console."""
    require_browser()
    robot = load_robot("hexapod")
    home = np.asarray(robot.verification.home, dtype=float)
    one = "is not a posture (the robot has posture 0 only)"
    for fragment, pose, words in (("#pose=1,2,3&posture=banana", home, ["pose=1,2,3 is not 6 numbers", f"posture=banana {one}"]),
                                  ("#pose=0,0,400,0,0,0&posture=7", [0.0, 0, 400, 0, 0, 0], [f"posture=7 {one}"])):
        answer = open_page(page_of("hexapod"), fragment, tmp_path / "shot.png", tmp_path / "profile")["joints"]
        assert answer["by"] == "wasm" and answer["posture"] == 0 and answer["pose"] == pytest.approx(pose)
        expected = solve(robot, t6_from_pose(np.array([pose])))
        np.testing.assert_allclose(answer["joints"], expected.joints[0, :, 0], atol=1e-9)
        assert all(word in answer["address_warning"] for word in words), answer


@pytest.mark.parametrize("name", ("linear_delta", "tau"))
def test_the_view_opens_with_the_whole_machine_in_sight(name, page_of, tmp_path):
    """The rails are framed with the rest (a linear delta's towers rise far above its platform):
    in the screenshot at load, the 3D stage's outer 12 px are its background on every side
    (nothing of the machine cut off by the stage's edge) and the machine is drawn."""
    require_browser()
    from matplotlib.image import imread

    shot = tmp_path / "shot.png"
    open_page(page_of(name), "", shot, tmp_path / "profile")
    pixels = np.round(imread(shot)[:, :, :3] * 255)
    drawn = np.any(pixels[60:695, 2:605] != BACKGROUND, axis=-1)  # the stage, below the title, left of the side panel
    edges = {"top": drawn[:12], "bottom": drawn[-12:], "left": drawn[:, :12], "right": drawn[:, -12:]}
    assert {side: float(band.mean()) for side, band in edges.items()} == dict.fromkeys(edges, 0.0)
    assert drawn.mean() > 0.02
