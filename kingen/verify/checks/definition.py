"""``definition``: whether the library was built from this robot file (the sha256 its build
information carries; :mod:`kingen.library_info`), read from its bytes, never loaded."""

from ...library_info import build_info
from ...report import not_exercised
from .base import Check, VerifyCheck


def definition_check(robot, library):
    """``definition``: whether the library was built from this robot file (the sha256 it
    carries), from another one, or not by kingen (then the check passes, saying so)."""
    info = build_info(library)
    if info is None:
        return not_exercised("definition", "the library carries no kingen build information (not built by "
                                           "kingen): its definition cannot be traced")
    if info.get("sha256") == robot.sha256:
        return Check("definition", True, f"built by kingen {info.get('kingen', '?')} from this robot file "
                                         f"(sha256 {robot.sha256[:16]})")
    return Check("definition", False, f"built by kingen {info.get('kingen', '?')} from another definition of "
                                      f"'{info.get('robot', '?')}': the library says sha256 "
                                      f"{info.get('sha256', '?')[:16]}, {robot.path.name} has {robot.sha256[:16]}: "
                                      "rebuild it from the reviewed file")


class Definition(VerifyCheck):
    name = "definition"
    needs = "library"
    item = "build"

    def run(self, context):
        return [definition_check(context.robot, context.library)]
