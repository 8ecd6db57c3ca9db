"""kingen: a robot's YAML definition to verified inverse-kinematics C routines for DELMIA V5 /
IGRIP and LinuxCNC, with forward kinematics, workspace analysis and design optimisation.

This is the public face, for a notebook or a script:

    import kingen
    robot = kingen.load_robot("hexapod")
    solution = kingen.solve(robot, [[0, 0, 800, 0, 0, 0]])
    report = kingen.verify_library(robot)

Every function here imports what it needs when it is called, so ``import kingen`` is
cheap. The packages below are kingen's own (docs/developer/architecture.md): ``kingen.robot``
(reading a robot file, the ``Robot``, limb models), ``kingen.kinematics`` (the reference,
singularities, forward kinematics), ``kingen.verify``, ``kingen.hosts`` (DELMIA, LinuxCNC
and the host interface), ``kingen.design`` (analysis and optimisation), ``kingen.runtime``
(compiler, child processes, files) and ``kingen.cli``. Units: mm for lengths, degrees for
the angles of a pose (x y z roll pitch yaw, R = Rz(yaw) Ry(pitch) Rx(roll)), radians for
revolute joints.
"""

from .defaults import (AZIMUTH_STEP_DEG, DEFAULT_HOST, LOAD_RATE_MAX, LOAD_WRENCH_MAX, MAX_MM, TILT_MAX_DEG, TILT_STEP_DEG,
                       VERSION)

__version__ = VERSION
__all__ = ["analyze", "assembly_modes", "build", "load_robot", "loads", "shipped_robots", "solve", "verify_library"]


def shipped_robots():
    """The names of the robots kingen ships (``robots/*.yaml``).

    Returns
    -------
    list of str
        Sorted names, each accepted by :func:`load_robot`.
    """
    from .robot.model import shipped_robots as names

    return names()


def load_robot(robot):
    """Read and validate a robot definition.

    Parameters
    ----------
    robot : str or os.PathLike
        A YAML file's path, or the name of a shipped robot (:func:`shipped_robots`).

    Returns
    -------
    kingen.robot.model.Robot
        The validated robot, in mm and radians whatever units its file uses: ``dof``
        joints (one per limb), ``postures`` solutions per pose, ``joint_names``, ``limbs``.

    Raises
    ------
    kingen.errors.KingenError
        The file cannot be read or breaks the schema: one line, ``file:line: field: problem``.
    """
    from . import hosts  # noqa: F401  (every host's check of the names it makes from the robot's)
    from .robot.model import load_robot as load

    return load(robot)


def solve(robot, poses, link_lengths=None, link_offsets=None):
    """Every posture's joints for each pose, from kingen's numpy reference.

    Parameters
    ----------
    robot : kingen.robot.model.Robot
        From :func:`load_robot`.
    poses : array_like, shape (n, 6)
        Platform poses in the base frame: x, y, z in mm, roll, pitch, yaw in degrees,
        R = Rz(yaw) Ry(pitch) Rx(roll).
    link_lengths, link_offsets : array_like, shape (6,), optional
        DELMIA's dialog fields Length 1..6 and Offset 1..6, applied to the parameters the
        robot file marks as calibrated (zero leaves a parameter as built).

    Returns
    -------
    kingen.kinematics.reference.Solution
        ``joints`` (n, dof, postures): mm for prismatic, radians for revolute joints;
        ``warnings`` (n, postures): status codes (``kingen.kinematics.routine.WARNINGS``:
        0 good, 2 unreachable, ...); ``radicands`` (n, dof).

    Raises
    ------
    kingen.errors.KingenError
        What ``kingen solve`` refuses: poses not of six finite numbers each, x y z beyond
        +/-1,000,000 mm or angles beyond +/-720 degrees; dialog fields not six finite numbers
        within +/-1,000,000 mm.
    """
    from .conventions import t6_from_pose
    from .kinematics.reference import solve as reference

    poses = _poses("solve: poses", poses, 1.0)
    fields = [None if values is None else _numbers(f"solve: {name}", values, (6,), [(MAX_MM, "mm")] * 6)
              for name, values in (("link_lengths", link_lengths), ("link_offsets", link_offsets))]
    return reference(robot, t6_from_pose(poses), *fields)


def assembly_modes(robot, joints, near=None, search=2.0):
    """Forward kinematics: every platform pose the joints admit (a robot with a wrist: every
    tool pose).

    Parameters
    ----------
    robot : kingen.robot.model.Robot
    joints : array_like, shape (joint_count,)
        Joint values (the limbs', then a wrist's): mm for prismatic, radians for revolute joints.
    near : array_like, shape (6,), optional
        A pose (mm and radians) that orders the answers and gives the coordinates the
        robot does not move; the robot's home pose by default.
    search : float, optional
        How far a multi-start search reaches around ``near``, in multiples of the robot's
        verification range (where no exhaustive method applies).

    Returns
    -------
    kingen.kinematics.forward.AssemblyModes
        ``found``: Assembly poses (6,) in mm and radians, nearest ``near`` first, each with
        its ``residual_mm``; ``exhaustive``: whether they are all of them; ``method``: how
        that is known, in one line.

    Raises
    ------
    kingen.errors.KingenError
        What ``kingen fk`` refuses: not ``joint_count`` finite joints (prismatic within
        +/-1,000,000 mm, revolute within +/-720 degrees), ``near`` not six finite numbers
        within the geometry range, ``search`` not within 0.1 to 1000, a robot without free
        pose coordinates.
    """
    import numpy as np

    from .errors import KingenError
    from .kinematics.forward import assemblies

    if not robot.has_forward:
        raise KingenError(f"assembly_modes: forward kinematics needs free pose coordinates for a robot with "
                          f"{robot.dof} limbs (declare them in its file, for example forward: {{free: [x, y, z]}})")
    joints = _numbers("assembly_modes: joints", joints, (robot.joint_count,), _joint_bounds(robot))
    if near is None:
        home = np.asarray(robot.verification.home, dtype=float)
        near = np.concatenate([home[:3], np.radians(home[3:])])
    near = _poses("assembly_modes: near", near, np.radians(1.0))[0]
    return assemblies(robot, joints, near, _number("assembly_modes: search", search, 0.1, 1000.0, ""))


def build(robot, host=DEFAULT_HOST, out_dir=None):
    """Render and compile the robot's routine for a host (skipped when up to date).

    Parameters
    ----------
    robot : kingen.robot.model.Robot
    host : str, optional
        ``"delmia"`` (a DELMIA V5 / IGRIP plugin) or ``"linuxcnc"`` (a kinematics module),
        or any host registered in ``kingen.hosts``.
    out_dir : str or os.PathLike, optional
        The output folder; ``build/<name>`` (DELMIA) or the host's default.

    Returns
    -------
    kingen.hosts.base.BuildResult
        ``library`` (the compiled file's path), ``routine`` (its entry point's name) and
        ``source``.

    Raises
    ------
    kingen.errors.KingenError
        What ``kingen build`` refuses: an unknown host, an output folder kingen could not
        write or reached through another user's symbolic link.
    """
    from pathlib import Path

    from .hosts import get_host
    from .runtime.files import writable_folder

    chosen = get_host(host)
    if out_dir is not None:
        writable_folder(out_dir)
    return chosen.build(robot, None if out_dir is None else Path(out_dir))


def verify_library(robot, library=None, routine=None, host=DEFAULT_HOST, samples=10000, seed=0):
    """Check a compiled routine against the reference, its golden values and its host's
    contract; the routine runs in a child process, never in this one.

    Parameters
    ----------
    robot : kingen.robot.model.Robot
    library : str or os.PathLike, optional
        A compiled library; kingen's own build for ``host`` by default.
    routine : str, optional
        The routine's name in ``library``; the host's name for the robot by default.
    host : str, optional
        A registered host's name: ``"delmia"``, ``"linuxcnc"``, ``"c"`` or ``"wasm"``.
    samples, seed : int, optional
        How many seeded poses of the robot's verification region are compared.

    Returns
    -------
    kingen.verify.report.Report
        ``passed``, ``checks`` (each with ``name``, ``passed``, ``detail``), the largest
        errors (``max_abs_error_mm``, ``max_abs_error_rad``) and ``as_json()``, the
        contract of ``kingen verify --json``.

    Raises
    ------
    kingen.errors.KingenError
        What ``kingen verify`` refuses: an unknown host, ``samples`` not a whole number of at
        least 1, ``seed`` not one of at least 0.
    """
    from pathlib import Path

    from .hosts import get_host
    from .verify import VerifyOptions, verify_library as verify

    samples, seed = _count("verify_library: samples", samples, 1), _count("verify_library: seed", seed, 0)
    chosen = get_host(host)
    if library is None:
        built = chosen.build(robot)
        library, routine = built.library, built.routine
    return verify(chosen.as_seen(robot), Path(library), routine or chosen.routine_name(robot),
                          VerifyOptions(samples=samples, seed=seed), host=chosen)


def analyze(robot, posture=None, tilt_step=0.1, azimuth_step=15.0, tilt_max=90.0):
    """How far the platform tilts in every direction from home before something stops it.

    Parameters
    ----------
    robot : kingen.robot.model.Robot
    posture : int, optional
        The posture judged; the robot's working posture by default.
    tilt_step, azimuth_step, tilt_max : float, optional
        The grid, in degrees (the bounds of ``kingen analyze``'s options).

    Returns
    -------
    list of dict
        One per azimuth: ``azimuth_deg``, ``max_tilt_deg`` (degrees), ``cause`` (what stops
        it: a singularity, a joint's travel, unreachability, or ``none``) and
        ``min_direct_index_mm``; empty when the platform cannot tilt.

    Raises
    ------
    kingen.errors.KingenError
        What ``kingen analyze`` refuses: a posture the robot does not have, a step or largest
        tilt beyond the options' bounds (tilt step 0.001 to 90, azimuth step 0.5 to 180,
        largest tilt 0.1 to 180 degrees).
    """
    from .design.analysis import Settings, tilt_limits

    chosen = robot.working_posture if posture is None else _count("analyze: posture", posture, 0,
                                                                   robot.postures - 1)
    steps = [_number(f"analyze: {name}", value, *bounds, " degrees") for name, value, bounds in
             (("tilt_step", tilt_step, TILT_STEP_DEG), ("azimuth_step", azimuth_step, AZIMUTH_STEP_DEG),
              ("tilt_max", tilt_max, TILT_MAX_DEG))]
    return tilt_limits(robot, chosen, Settings(tilt_step_deg=steps[0], azimuth_step_deg=steps[1],
                                               tilt_max_deg=steps[2]))


def loads(robot, poses, wrench=None, velocity=None, acceleration=None, postures=None):
    """What it takes to hold or move the payload at each pose: actuator forces and torques, what
    the constraints carry, passive-joint angles and the deflection (docs/explanation/loads.md).

    Parameters
    ----------
    robot : kingen.robot.model.Robot
        From :func:`load_robot`; its ``payload`` and ``gravity`` are the robot file's (with a serial
        wrist the payload, the poses, the motion and the wrench are the tool's).
    poses : array_like, shape (n, 6)
        Platform poses (mm, degrees); a constrained machine takes its own pose for their task
        coordinates.
    wrench : array_like, shape (6,), optional
        An external wrench at the platform origin: N, N m, base frame.
    velocity, acceleration : array_like, shape (6,), optional
        The platform origin's velocity (mm/s, deg/s) and acceleration (mm/s^2, deg/s^2), base
        frame; absent: at rest.
    postures : sequence of int, optional
        The postures to compute; every posture by default.

    Returns
    -------
    kingen.kinematics.loads.Loads
        ``forces`` (n, postures, dof): N (prismatic) or N m (revolute), positive where the
        actuator pushes its joint to increase; ``constraint`` (n, postures, 6): N and N m about
        the platform origin; ``base_angles``, ``platform_angles`` (n, postures, dof) in radians;
        ``deflection`` (n, postures, 6) mm and radians, or None; ``machine`` the T6 poses taken.

    Raises
    ------
    kingen.errors.KingenError
        Poses or vectors of the wrong shape or not finite, a posture that does not exist.
    """
    import numpy as np

    from .kinematics.loads import Motion, loads as compute, machine_t6

    poses = _poses("loads: poses", poses, 1.0)
    rates, forces = [(LOAD_RATE_MAX, "mm or deg per s or s^2")] * 6, [(LOAD_WRENCH_MAX, "N or N m")] * 6
    vectors = {name: None if value is None else _numbers(f"loads: {name}", value, (6,), bounds)
               for name, value, bounds in (("wrench", wrench, forces), ("velocity", velocity, rates),
                                           ("acceleration", acceleration, rates))}
    chosen = None if postures is None else [_count("loads: postures", k, 0, robot.postures - 1) for k in postures]
    motion = None
    if velocity is not None or acceleration is not None:
        internal = [np.zeros(6) if v is None else np.r_[v[:3], np.radians(v[3:])]
                    for v in (vectors["velocity"], vectors["acceleration"])]
        motion = Motion(velocity=internal[0], acceleration=internal[1])
    return compute(robot, machine_t6(robot, poses), wrench=vectors["wrench"], motion=motion, postures=chosen)


def _number(name, value, low, high, unit):
    """``value`` as a float, finite and within ``low`` to ``high`` (``unit``); KingenError
    naming the argument ``name`` otherwise (the bounds of the command line's option)."""
    import math

    from .errors import KingenError

    try:
        number = float(value)
    except (TypeError, ValueError):
        raise KingenError(f"{name}: {value!r} is not a number") from None
    if not (math.isfinite(number) and low <= number <= high):
        raise KingenError(f"{name}: {number:g} is not within {low:g} to {high:g}{unit}")
    return number


def _count(name, value, least, most=None):
    """``value``, a whole number (not a bool) from ``least`` to ``most`` (None: no most);
    KingenError naming the argument ``name`` otherwise."""
    import numbers

    from .errors import KingenError

    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < least or (
            most is not None and value > most):
        span = f"from {least}" + ("" if most is None else f" to {most}")
        raise KingenError(f"{name}: {value!r} is not a whole number {span}")
    return int(value)


def _numbers(name, values, shape, bounds):
    """``values`` as a float array of ``shape``, its entry i along the last axis finite and
    within +/- ``bounds[i][0]`` (unit ``bounds[i][1]``); KingenError naming the argument
    ``name`` (and the entry) otherwise."""
    import numpy as np

    from .errors import KingenError

    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise KingenError(f"{name}: not an array of numbers") from None
    if array.shape != tuple(shape):
        raise KingenError(f"{name}: {array.shape} numbers, expected {tuple(shape)}")
    limits = np.array([limit for limit, _ in bounds])
    bad = np.argwhere(~(np.abs(array) <= limits))
    if len(bad):
        where = tuple(int(index) for index in bad[0])
        limit, unit = bounds[where[-1]]
        raise KingenError(f"{name}{list(where)}: {array[where]:g} is not a finite number within +/-{limit:g} {unit}")
    return array


def _poses(name, poses, angle_unit):
    """``poses`` ((6,) or (n, 6): x y z mm, three angles in degrees times ``angle_unit``, 1 for
    degrees, pi/180 for radians) as an (n, 6) array within the geometry range (_numbers)."""
    import numpy as np

    from .errors import KingenError
    from .robot.schema import MAX_DEGREES

    try:
        shape = np.shape(poses)
    except ValueError:  # ragged
        raise KingenError(f"{name}: not an array of numbers") from None
    if shape != (6,) and (len(shape) != 2 or shape[1] != 6):
        raise KingenError(f"{name}: {shape} numbers, expected (6,) or (n, 6)")
    rows = (1, 6) if shape == (6,) else shape
    bounds = [(MAX_MM, "mm")] * 3 + [(MAX_DEGREES * angle_unit, "radians" if angle_unit != 1.0 else "degrees")] * 3
    return _numbers(name, np.reshape(poses, rows) if shape == (6,) else poses, rows, bounds)


def _joint_bounds(robot):
    """Per joint of ``robot`` (mm, radians): the geometry range, +/-MAX_MM mm for a prismatic
    joint, +/-720 degrees for a revolute one, as _numbers takes it."""
    import math

    from .robot.schema import MAX_DEGREES

    return [(math.radians(MAX_DEGREES), "radians") if revolute else (MAX_MM, "mm") for revolute in robot.revolute]
