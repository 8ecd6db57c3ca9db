"""``buffers``: no call wrote outside its output buffers or changed its inputs, as the host
emulator's guarded driver reports per call (:data:`kingen.hosts.delmia.abi.GUARD_FAULTS`)."""

from ....verify.checks.base import Check, VerifyCheck
from .. import abi


class Buffers(VerifyCheck, name="buffers", needs="sampled calls", item="interface"):
    """No call wrote outside solutions/warnings (each placed against an inaccessible page by
    the host emulator's guarded driver) or changed its inputs."""

    def run(self, context):
        return [buffers_check(context.tally.faulty_calls, context.tally.fault_bits)]


def buffers_check(faulty_calls, fault_bits):
    """The ``buffers`` check from the guarded driver's per-call fault bits."""
    if not faulty_calls:
        return Check("buffers", True, "no call wrote outside solutions/warnings (each against an "
                                      "inaccessible page) and inputs stayed untouched")
    what = "; ".join(text for bit, text in abi.GUARD_FAULTS.items() if fault_bits & bit)
    return Check("buffers", False, f"{faulty_calls} calls: the routine {what}")
