"""``definition``: whether the library says it was built from this robot file (the sha256 its
build information carries; :mod:`kingen.runtime.library_info`), read from its bytes, never loaded.
That information is a label the library carries, not a proof: the check catches a stale
build, not a forged one, and says so."""

from ...runtime.library_info import build_info
from ..report import not_exercised
from .base import Check, VerifyCheck


def definition_check(robot, library):
    """``definition``: passes when the library's build information names this robot file's
    sha256, fails when it names another; not exercised when it carries none. Its text says
    what the library claims, never that kingen built it."""
    info = build_info(library)
    if info is None:
        return not_exercised("definition", "the library carries no kingen build information: its definition "
                                           "cannot be traced")
    says = f"the library says it was built by kingen {info.get('kingen', '?')}"
    if info.get("sha256") == robot.sha256:
        return Check("definition", True, f"{says} from this robot file (sha256 {robot.sha256[:16]}; a label it "
                                         "carries, not a proof)")
    return Check("definition", False, f"{says} from another definition of '{info.get('robot', '?')}' (sha256 "
                                      f"{info.get('sha256', '?')[:16]}), {robot.path.name} has {robot.sha256[:16]}: "
                                      "rebuild it from the reviewed file")


class Definition(VerifyCheck, name="definition", needs="library", item="build"):
    def run(self, context):
        return [definition_check(context.robot, context.library)]
