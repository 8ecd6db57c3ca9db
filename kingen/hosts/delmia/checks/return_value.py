"""``return value``: a DELMIA routine returns 1 when no posture is reachable, 0 otherwise
(counted over the sampled poses by :mod:`kingen.verify.tally`)."""

from ....verify.checks.base import STOPPED_CALLS, Check, VerifyCheck


class ReturnValue(VerifyCheck, name="return value", needs="compared poses", item="interface",
                  uncompared=STOPPED_CALLS):
    """The routine returns 1 when no posture is reachable, 0 otherwise (counted by the tally)."""

    def run(self, context):
        wrong = context.tally.returns_wrong
        return [Check("return value", wrong == 0,
                      f"{wrong} calls return other than 1 when no posture is reachable, 0 otherwise")]
