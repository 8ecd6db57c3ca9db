"""kingen.runtime.wire: what a child sends its parent is plain data in frames only kingen's child can
make; whatever else arrives is refused in one line, never run, never waited on forever."""

import json
import os
import struct

import numpy as np
import pytest

from kingen.runtime import wire
from kingen.verify.report import Check, GoldenResult, Report
from kingen.kinematics.routine import calls_decoder

KEY = bytes(range(32))


def _received(frame, key=KEY, timeout=5.0):
    reading, writing = os.pipe()
    os.write(writing, frame)
    os.close(writing)
    receiver = wire.Receiver(reading, key)
    try:
        return receiver.receive(timeout)
    finally:
        receiver.close()


def test_a_report_travels_whole_and_is_rebuilt_field_by_field():
    report = Report(robot="tau", routine="kin_tau", samples=10, seed=3, postures=8, max_abs_error_mm=float("inf"),
                    golden=[GoldenResult("a table", [0.0] * 6, 1, [1.5], [1.5], [1.5], 1e-9, True)],
                    checks=[Check("values", True, "10 poses", judged=10), Check("golden", False, "1 of 2", ["why"])],
                    notices=["n"], boundary_poses={"poses": 4, "boundaries_found": {"WARN_UNREACHABLE": 2}},
                    interface_checks=("buffers",), posture_statistics=[{"posture": 0, "right": 9, "worst_error_mm": None}])
    kind, value = _received(wire.encode(KEY, "result", report))
    rebuilt = wire.typed(Report, value)
    assert kind == "result" and rebuilt == report and not rebuilt.passed
    assert type(rebuilt.posture_statistics[0]["right"]) is int


def test_arrays_travel_as_their_bytes():
    solutions = np.arange(24, dtype=float).reshape(2, 3, 4)
    value = {"returned": np.zeros(2, np.intc), "solutions": solutions, "warnings": np.ones((2, 4), np.intc),
             "faults": np.zeros(2, np.intc), "branch_values": None, "repeats": None}
    kind, plain = _received(wire.encode(KEY, "result", value))
    calls = calls_decoder(2)(plain)
    assert np.array_equal(calls.solutions, solutions) and calls.warnings.dtype == np.intc
    with pytest.raises(wire.WireError, match=r"returned: not 3 poses' numbers"):
        calls_decoder(3)(plain)


def test_python_objects_do_not_travel():
    with pytest.raises(TypeError, match="object cannot travel"):
        wire.encode(KEY, "result", object())
    with pytest.raises(TypeError, match="ndarray cannot travel"):
        wire.encode(KEY, "result", np.array([object()]))


def _frame(body, key=KEY):
    import hashlib
    import hmac

    return wire.HEADER.pack(wire.MAGIC, len(body), hmac.digest(key, body, hashlib.sha256)) + body


def _body(tree, tail=b""):
    text = json.dumps(tree).encode()
    return struct.pack(">I", len(text)) + text + tail


REFUSED = {
    "another key": (wire.encode(bytes(32), "result", 1), "its check failed"),
    "not a frame": (b"\x00\x00\x00\x10" + b"\x80\x04K\x01." * 8, "bytes that are not kingen's message"),
    "a length past the limit": (wire.HEADER.pack(wire.MAGIC, 1 << 40, bytes(32)), "larger than any kingen sends"),
    "cut short": (wire.encode(KEY, "result", [1, 2, 3])[:-2], "a message cut short"),
    "an object array": (_frame(_body({"kind": "result", "value": {"$array": ["|O", [1]]}}, bytes(8))),
                        "an array kingen cannot read"),
    "arrays cut short": (_frame(_body({"kind": "result", "value": {"$array": ["<f8", [4]]}}, bytes(8))),
                         "arrays are cut short"),
    "bytes beyond": (_frame(_body({"kind": "result", "value": 1}, b"x")), "bytes beyond its arrays"),
    "deep nesting": (_frame(struct.pack(">I", 10000) + b"[" * 5000 + b"]" * 5000),
                     "cannot read (RecursionError)"),
    "more fields": (_frame(_body({"kind": "result", "value": 1, "code": "x"})), "cannot read (its kind)"),
}


@pytest.mark.parametrize("case", REFUSED)
def test_what_is_not_kingens_message_is_refused(case):
    frame, words = REFUSED[case]
    with pytest.raises(wire.WireError, match=words.replace("(", r"\(").replace(")", r"\)")):
        _received(frame)


def test_a_frame_that_stops_coming_is_a_timeout_not_a_hang():
    reading, writing = os.pipe()
    os.write(writing, wire.encode(KEY, "result", 1)[:20])
    receiver = wire.Receiver(reading, KEY)
    try:
        with pytest.raises(TimeoutError):
            receiver.receive(0.2)
    finally:
        receiver.close()
        os.close(writing)


def test_a_field_of_another_type_is_named():
    with pytest.raises(wire.WireError, match=r"a Report kingen cannot read \(checks.0.passed: Input should be a valid "
                                             r"boolean"):
        wire.typed(Report, {"robot": "r", "routine": "k", "samples": 1, "seed": 0, "postures": 1,
                            "checks": [{"name": "values", "passed": "maybe"}]})
