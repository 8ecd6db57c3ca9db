"""Rendering, shared by every host: robot -> the view-model its C templates substitute.
Pure: nothing here touches the file system except reading templates (through
:mod:`kingen.runtime.templates`, which keeps jinja2's compiled templates in kingen's cache);
the build layer writes files.

All decisions are made here in a Python view-model; the templates only loop and
substitute. Numbers are written with Python's shortest round-trip repr, so the
C tables hold exactly the doubles the reference uses. Templates are found in the host's
own folder first, then in the shared ``templates/`` (limb model partials from the registry).
"""

import math
import textwrap

from ..defaults import VERSION
from ..errors import KingenError
from ..runtime import templates
from ..runtime.library_info import BUILD_INFO_MARKER
from ..robot.limbs import MODELS, c_double, c_vector, partial_path
from ..robot.schema import calibration_index
from ..kinematics.hybrid.parasitic import MANIFOLD_TOLERANCE_RAD, home_yaw, manifold_tolerance_mm
from ..kinematics.singularity import PACKED, partial_sum_split
from ..kinematics.hybrid.parasitic_axes import home_axes
from ..robot.constraints import axes_table, constraint_table, family
from .wrist import whole_view


NEWTON_STEP, NEWTON_STEP_RELATIVE = 1e-10, 1e-12
"""A generated forward's Newton stops when no step is longer than NEWTON_STEP (mm and radians),
or than NEWTON_STEP_RELATIVE of the machine's size where that is larger: rounding leaves steps of
about 1e-16 of the size times the pose's conditioning, which a machine of metres keeps above
1e-10 mm; the step after which Newton stops leaves an error of about its square."""


NEWTON_STALL_RELATIVE = 1e-9
"""A generated forward's Newton also stops when a step is no shorter than half the step before
it and at most NEWTON_STALL_RELATIVE of the machine's size: quadratic convergence is over and the
steps are rounding's (about 1e-16 of the size over the pose's conditioning, which verify keeps
above 1e-4); the pose returned is then within about that step of the root."""


def newton_stops(robot, unit_mm=1.0):
    """The C texts (step, stall) a generated forward's Newton stops at, for ``robot`` in mm as
    loaded, in the routine's length unit of ``unit_mm`` mm (25.4 for an inch machine), radians
    alike: the longest step (NEWTON_STEP) and the longest step that no longer halves the one
    before it (NEWTON_STALL_RELATIVE of the machine's size)."""
    step = max(NEWTON_STEP, NEWTON_STEP_RELATIVE * robot.size_mm)
    return c_double(step / unit_mm), c_double(NEWTON_STALL_RELATIVE * robot.size_mm / unit_mm)


def _partial_source(name):
    """Limb model partials ('limbs/<model>.c.j2') from the registry, wherever they live."""
    model = name[len("limbs/"):-len(".c.j2")] if name.startswith("limbs/") and name.endswith(".c.j2") else None
    if model not in MODELS:
        return None
    path = partial_path(MODELS[model])
    return path.read_text(), str(path), lambda: True


def template(name, folder=None):
    """The jinja2 template ``name`` from ``folder`` (a host's templates) or the shared
    templates/, with the limb models' partials from the registry
    (:func:`kingen.runtime.templates.template`)."""
    return templates.template(name, folder, _partial_source)


def refuse(robot, problem):
    """Raise a problem ('field: text', a host's robot_problem) as the robot file's located
    KingenError; nothing when ``problem`` is None."""
    if problem is not None:
        field, _, text = problem.partition(": ")
        raise KingenError(f"{robot.path}:{robot.line_of(field)}: {field}: {text}")


def calibration_line(robot, host, joint, parameter, field, built_in):
    """'<field> -> leg3.reference_length (mm, built-in 803.887)' for sheets and banners: one
    entry of ``robot.calibration()``, the field named as ``host`` labels it."""
    unit = robot.limbs[joint].calibratable[parameter]
    return (f"{host.calibration_label(field)} -> {robot.joint_names[joint]}.{parameter} "
            f"({unit}, built-in {built_in:.10g})")


def build_info(robot, routine, postures=None, extra=()):
    """What the library says about itself, compiled in as data (read back by kingen info):
    the robot, the ``routine``'s name, its joints and postures (default the robot's), the
    definition's sha256, kingen's version, then any ``extra`` (key, value) pairs."""
    text = (f"{BUILD_INFO_MARKER} robot={robot.name} routine={routine} dof={robot.joint_count} "
            f"postures={robot.postures if postures is None else postures} sha256={robot.sha256} kingen={VERSION}")
    return text + "".join(f" {key}={value}" for key, value in extra)


def _model_tables(robot):
    """Per limb model used, in first-use order: its name, partial, column words and rows."""
    tables = {}
    for index, limb in enumerate(robot.limbs):
        cls = type(limb)
        table = tables.setdefault(cls, {"name": limb.model, "partial": f"limbs/{limb.model}.c.j2",
                                        "columns": f"Columns: {cls.c_columns}.", "rows": []})
        row = {"joint": index, "name": robot.joint_names[index], **limb.c_row()}
        row.update({f"{parameter}_field": calibration_index(limb.calibrate[parameter]) if parameter in limb.calibrate
                    else -1 for parameter in cls.calibratable})
        table["rows"].append(row)
    return list(tables.values())


def closed_form_model(robot):
    """The table (as the view's ``models`` holds it) of the one limb model of ``robot`` whose
    forward a translating platform solves in closed form, its three limbs' spheres intersected
    (:attr:`kingen.robot.limbs.LimbModel.closed_form_forward`), or None: Newton's method."""
    if robot.dof != 3 or len(robot.models) != 1 or not type(robot.limbs[0]).closed_form_forward:
        return None
    return _model_tables(robot)[0]


def schur_test_lines(entry):
    """Straight-line C89 (declarations first) that sets ``double margin``: positive exactly when
    M - KINGEN_DIRECT_MIN^2 diag(0, 0, 0, 1, 1, 1) is positive definite (the direct index lies
    above the threshold), else zero, negative or NaN. ``entry`` formats M's packed entry k
    (lower triangle, row by row) as a C expression, e.g. ``"first[{k}] + second[{k}]"``.

    Division-free and branch-free, so a loop over postures vectorises: with M's force block
    A, mixed block B (moment rows) and moment block C, the test holds exactly when A's
    leading minors a00, j22 = a00 a11 - a10^2 and det A are positive and so are the leading
    minors of X = det(A) (C - d^2 I) - B adj(A) B^T, which is det(A) times the Schur
    complement minus d^2 I (docs/explanation/conventions.md, 'Force lines and the direct index').
    margin is their minimum; det X, taken last, involves every entry, so a NaN anywhere in M
    reaches margin."""
    names = {(r, c): f"a{r}{c}" for r in range(3) for c in range(r + 1)}
    names.update({(3 + r, c): f"b{r}{c}" for r in range(3) for c in range(3)})
    names.update({(3 + r, 3 + c): f"c{r}{c}" for r in range(3) for c in range(r + 1)})
    declarations = [f"double {names[pair]} = {entry.format(k=k)};" for k, pair in enumerate(PACKED)]
    adjugate = {(0, 0): "a11 * a22 - a21 * a21", (1, 1): "a00 * a22 - a20 * a20", (2, 2): "a00 * a11 - a10 * a10",
                (1, 0): "a20 * a21 - a10 * a22", (2, 0): "a10 * a21 - a11 * a20", (2, 1): "a10 * a20 - a00 * a21"}
    declarations += [f"double j{r}{c} = {value};" for (r, c), value in adjugate.items()]
    declarations.append("double det = a00 * j00 + a10 * j10 + a20 * j20, shift = det * KINGEN_DIRECT_MIN * KINGEN_DIRECT_MIN;")

    def adj(r, c):
        return f"j{max(r, c)}{min(r, c)}"

    declarations += [f"double p{r}{c} = {' + '.join(f'b{r}{k} * {adj(k, c)}' for k in range(3))};"
                     for r in range(3) for c in range(3)]
    declarations += [f"double x{r}{c} = det * c{r}{c}{' - shift' if r == c else ''}"
                     f" - ({' + '.join(f'p{r}{k} * b{c}{k}' for k in range(3))});" for r in range(3) for c in range(r + 1)]
    declarations += ["double y11 = x00 * x11 - x10 * x10;",
                     "double y22 = x00 * (x11 * x22 - x21 * x21) - x10 * (x10 * x22 - x21 * x20)"
                     " + x20 * (x10 * x21 - x11 * x20);",
                     "double margin = a00;"]
    return declarations + [f"margin = margin < {minor} ? margin : {minor};"
                           for minor in ("j22", "det", "x00", "y11", "y22")]


def gram_lines(accumulate):
    """C statements that fill gram[21] with the packed lower triangle of w w^T (from w0 .. w5),
    or add it to gram[21] when ``accumulate``: a routine with one posture sums its lines
    straight into M, without a table of lines."""
    operator = "+=" if accumulate else "="
    return [f"gram[{k}] {operator} w{r} * w{c};" for k, (r, c) in enumerate(PACKED)]


def partial_sums(robot):
    """The C sums (over grams[limb][branch][k]) of the two partial Gram tables of
    singularity.partial_sum_split: 'low' per combination of the low posture digits (their
    limbs), 'high' per combination of the other digits (with every one-branch limb)."""
    low_bits, low_limbs, high_limbs = partial_sum_split(robot)

    def sums(limbs, postures):
        return [" + ".join(f"grams[{i}][{robot.posture_branches(k)[i]}][k]" for i in limbs) or "0.0"
                for k in postures]

    return {"low": sums(low_limbs, range(1 << low_bits)),
            "high": sums(high_limbs, range(0, robot.postures, 1 << low_bits))}


def joint_sum(robot):
    """The terms, one per joint, of the C sum of every joint value the routine computed (both
    branches of two-branch limbs): finite exactly when all of them are, unless the sum
    itself overflows."""
    return [" + ".join(f"joints[{index}].value[{branch}]" for branch in ((0, 1) if bit >= 0 else (0,)))
            for index, bit in enumerate(robot.branch_bits)]


def constraint_view(robot):
    """The constraint table of a machine with task coordinates as C text (templates/routine_helpers.c.j2,
    ``parasitic``), or None."""
    if not robot.task:
        return None
    if family(robot) == "axes":
        return axes_view(robot)
    if family(robot) == "tube":
        leg = robot.passive_leg
        return {"family": "tube", "base": c_vector(leg.base_point), "first": c_vector(leg.first_axis),
                "frame": [c_vector(row) for row in leg.frame], "tolerance_rad": c_double(MANIFOLD_TOLERANCE_RAD)}
    table = constraint_table(robot)
    home_cos, home_sin = home_yaw(robot)
    return {"family": "planes", "axes": [c_vector(row) for row in table.axes], "points": [c_vector(row) for row in table.points],
            "offsets": c_vector(table.offsets), "null": c_vector(table.null),
            "inverse": [c_vector(row) for row in table.pseudo_inverse], "home_cos": c_double(home_cos),
            "home_sin": c_double(home_sin), "tolerance_mm": c_double(manifold_tolerance_mm(robot)),
            "tolerance_rad": c_double(MANIFOLD_TOLERANCE_RAD)}


def axes_view(robot):
    """constraint_view of a machine whose revolute axes are fixed in the platform
    (templates/routine_helpers.c.j2, ``parasitic_axes``)."""
    table = axes_table(robot)
    home_v, home_u = home_axes(robot, table)
    return {"family": "axes", "base": c_vector(table.base), "third_base": c_vector(table.third_base),
            "difference": c_vector(table.difference), "pair_difference": c_double(table.pair_rhs[0]),
            "pair_rhs": c_double(table.pair_rhs[1]), "third_rhs": c_double(table.third_rhs),
            "cosine": c_double(table.cosine), "home_v": c_vector(home_v), "home_u": c_vector(home_u),
            "frame": [c_vector(row) for row in table.frame], "tolerance_rad": c_double(MANIFOLD_TOLERANCE_RAD)}


def robot_view(robot, host):
    """What every host's routine template substitutes about the robot, already formatted as C:
    names (the routine's and library's as ``host`` names them), joints, limb model tables,
    singularity tests, the calibration fields (in ``host``'s words) and the build information;
    a robot with a wrist: its parallel part's, with the whole machine's joints (kingen.hosts.wrist)."""
    if robot.wrist is not None:
        return whole_view(robot, robot_view(robot.parallel, host), build_info(robot, host.routine_name(robot)))
    lower, upper = robot.travel_limits()
    joints = []
    for index, (limb, bit) in enumerate(zip(robot.limbs, robot.branch_bits)):
        limited = limb.travel is not None
        joints.append({
            "index": index,
            "name": robot.joint_names[index],
            "model": limb.model,
            "units": limb.joint_type.c_units,
            "bit": bit,
            "limited": int(limited),
            "lower": c_double(lower[index] if limited else 0.0),
            "upper": c_double(upper[index] if limited else 0.0),
            "travel_text": f"[{limb.travel[0]:.10g}, {limb.travel[1]:.10g}] {limb.joint_type.yaml_unit}"
            if limited else "",
        })
    return {
        "version": VERSION,
        "source_name": robot.path.name,
        "source_hash": robot.sha256,
        "name": robot.name,
        "description_lines": textwrap.wrap(" ".join(robot.description.split()), 88) or [""],
        "library": host.library_name(robot),
        "routine": host.routine_name(robot),
        "dof": robot.dof,
        "postures": robot.postures,
        "two_branch_count": sum(1 for bit in robot.branch_bits if bit >= 0),
        "joint_sum": joint_sum(robot),
        "joints": joints,
        "any_limits": any(limb.travel is not None for limb in robot.limbs),
        "any_revolute": any(limb.joint_type.wraps for limb in robot.limbs),
        "has_radicand": any(limb.has_radicand for limb in robot.limbs) or bool(robot.task),
        "constraint": constraint_view(robot),
        "models": _model_tables(robot),
        "limb_part": "all",
        "direct_index": robot.direct_index_min is not None,
        "direct_test": robot.direct_index_min is not None,
        "jacobian": False,
        "low_bits": partial_sum_split(robot)[0],
        "split_sums": bool(partial_sum_split(robot)[1]),
        "schur_lines": schur_test_lines("high[{k} * KINGEN_HIGH + h] + low[{k} * KINGEN_LOW + l]"
                                     if partial_sum_split(robot)[1] else "high[{k} * KINGEN_HIGH + h]"),
        "gram_lines": gram_lines(accumulate=robot.postures == 1),
        "partial_sums": partial_sums(robot),
        "direct_index_min": c_double(robot.direct_index_min or 0.0),
        "degree": c_double(math.pi / 180.0),
        "calibration": [calibration_line(robot, host, *entry) for entry in robot.calibration()],
        "build_info": build_info(robot, host.routine_name(robot)),
        "wrist": None,
    }
