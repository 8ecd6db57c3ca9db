"""The Python API checks what the command line checks: every argument kingen's commands refuse
is refused by the function too, at once, as one KingenError line naming the function, the
argument and the bound (never an IndexError, a MemoryError or a search over NaN)."""

import time

import numpy as np
import pytest

import kingen
from kingen.errors import KingenError

NAN = float("nan")
REFUSED = {
    "a tilt step of 1e-12 (655 TiB of poses)": (lambda robot: kingen.analyze(robot, tilt_step=1e-12),
                                                "analyze: tilt_step: 1e-12 is not within 0.001 to 90 degrees"),
    "posture 99": (lambda robot: kingen.analyze(robot, posture=99),
                   "analyze: posture: 99 is not a whole number from 0 to 0"),
    "posture True": (lambda robot: kingen.analyze(robot, posture=True),
                     "analyze: posture: True is not a whole number from 0 to 0"),
    "an azimuth step of NaN": (lambda robot: kingen.analyze(robot, azimuth_step=NAN),
                               "analyze: azimuth_step: nan is not within 0.5 to 180 degrees"),
    "a largest tilt of 1000": (lambda robot: kingen.analyze(robot, tilt_max=1000),
                               "analyze: tilt_max: 1000 is not within 0.1 to 180 degrees"),
    "five joints for six": (lambda robot: kingen.assembly_modes(robot, [300.0] * 5),
                            "assembly_modes: joints: (5,) numbers, expected (6,)"),
    "a joint of 1e308": (lambda robot: kingen.assembly_modes(robot, [300.0] * 5 + [1e308]),
                         "assembly_modes: joints[5]: 1e+308 is not a finite number within +/-1e+06 mm"),
    "a search of NaN": (lambda robot: kingen.assembly_modes(robot, [300.0] * 6, search=NAN),
                        "assembly_modes: search: nan is not within 0.1 to 1000"),
    "a near pose of 1e9 mm": (lambda robot: kingen.assembly_modes(robot, [300.0] * 6, near=[0, 0, 1e9, 0, 0, 0]),
                              "assembly_modes: near[0, 2]: 1e+09 is not a finite number within +/-1e+06 mm"),
    "a pose of seven numbers": (lambda robot: kingen.solve(robot, np.zeros((2, 7))),
                                "solve: poses: (2, 7) numbers, expected (6,) or (n, 6)"),
    "a yaw of 721 degrees": (lambda robot: kingen.solve(robot, [[0, 0, 800, 0, 0, 0], [0, 0, 800, 0, 0, 721]]),
                             "solve: poses[1, 5]: 721 is not a finite number within +/-720 degrees"),
    "a pose of text": (lambda robot: kingen.solve(robot, "abc"), "solve: poses: () numbers, expected (6,) or (n, 6)"),
    "ragged poses": (lambda robot: kingen.solve(robot, [[0, 0, 800, 0, 0, 0], [1, 2]]),
                     "solve: poses: not an array of numbers"),
    "five dialog fields": (lambda robot: kingen.solve(robot, [0, 0, 800, 0, 0, 0], link_offsets=[1.0] * 5),
                           "solve: link_offsets: (5,) numbers, expected (6,)"),
    "no samples": (lambda robot: kingen.verify_library(robot, samples=0),
                   "verify_library: samples: 0 is not a whole number from 1"),
    "a negative seed": (lambda robot: kingen.verify_library(robot, seed=-1),
                        "verify_library: seed: -1 is not a whole number from 0"),
    "an unknown host": (lambda robot: kingen.build(robot, host="nope"), "unknown host 'nope' (known: "),
}


@pytest.fixture(scope="module")
def hexapod():
    return kingen.load_robot("hexapod")


@pytest.mark.parametrize("case", REFUSED)
def test_what_the_command_line_refuses_the_api_refuses_at_once(hexapod, case):
    call, message = REFUSED[case]
    started = time.monotonic()
    with pytest.raises(KingenError) as raised:
        call(hexapod)
    assert str(raised.value).startswith(message) and "\n" not in str(raised.value)
    assert time.monotonic() - started < 2.0


def test_the_api_still_answers_within_the_bounds(hexapod):
    """A pose given as six numbers is one pose; the joints solved there give it back among
    the assembly modes (searched around the home, the default ``near``)."""
    pose = [10.0, -5.0, 790.0, 2.0, -1.0, 3.0]
    solution = kingen.solve(hexapod, pose)
    assert solution.joints.shape == (1, 6, 1) and solution.warnings[0, 0] == 0
    modes = kingen.assembly_modes(hexapod, solution.joints[0, :, 0])
    found = [mode.pose for mode in modes.found]
    expected = np.array(pose[:3] + list(np.radians(pose[3:])))
    assert min(np.max(np.abs(np.asarray(mode) - expected)) for mode in found) < 1e-6
