"""The check of a whole program: its moves read one at a time and cut into pieces of at most
CHUNK regular samples (at most ``chord`` mm and degrees apart); pieces are gathered into
batches of about CHUNK samples (many short moves share one), each batch sampled, refined and
bisected between its samples (:mod:`.refinement`), solved at once by the numpy reference,
judged (:mod:`.judging`), and forgotten: memory does not grow with the program.

Joint speeds and accelerations are judged at the regular samples (finite differences along
the path, :mod:`.timing`, with the path's speed as LinuxCNC's planner moves a G-code program,
:mod:`.planner`); the boundaries of travel, reach, the singular bands, the direct
index and the assembly mode at every sample, refined ones included.
"""

import time
from dataclasses import dataclass

import numpy as np

from ..conventions import t6_from_pose
from ..defaults import DEFAULT_TIMEOUT, INTERPRETER_SECONDS, MAX_SAMPLES
from ..kinematics.routine import WARNINGS
from .evaluation import Evaluator
from .findings import Findings
from .five_axis import FiveAxis
from ..errors import located
from .ini import load_ini
from .interpreter import Reading, Setup, gcode_moves
from .judging import has_accelerations, judge_margins, judge_power, judge_rates, record, sample_numbers
from .limits import ini_files, ini_keys, ini_subroutine_path, limits_for
from .manifold import Manifold
from .planner import Plan, Stack, planned
from .power import actuator_power, platform_motion, power_limited
from .program import csv_moves, is_gcode, source_lines
from .refinement import refined
from .routine import RoutineSolver
from .sampling import lengths, poses_and_t6, sample_count
from .timing import Profile, joint_rates, path_rates, profile

CHUNK = 20000
"""Regular samples solved at once (a move longer than that is cut into pieces)."""
DEFAULT_CHORD = 0.1
"""mm and degrees between regular samples."""


@dataclass(frozen=True)
class Settings:
    """What a check is run with: the host whose interpolation is followed ('linuxcnc' or
    'delmia'), the posture (None: the robot's working posture), the chord (mm and degrees),
    the LinuxCNC .ini (None: the robot file's limits only), whether the regular samples' joints
    come from the robot's routine for the host (:mod:`.routine`) rather than the reference,
    the routine's build folder (None: build/<name>) and timeout (s), and for a machine with task
    coordinates whether a CSV's rows off its manifold are read as their task coordinates
    (a notice) rather than failed (:mod:`.manifold`); for G-code, the work offset to place the
    program with (x y z mm, a b c degrees; None: the ``.ini``'s parameter file's), the CPU
    seconds each interpreter may take, and the regular samples the program may ask for."""

    host: str = "linuxcnc"
    posture: int = None
    chord: float = DEFAULT_CHORD
    ini: object = None
    routine: bool = False
    out_dir: object = None
    timeout: float = DEFAULT_TIMEOUT
    task_only: bool = False
    offset: tuple = None
    interpreter_seconds: float = INTERPRETER_SECONDS
    max_samples: int = MAX_SAMPLES


@dataclass
class Outcome:
    """A finished check: the robot, program, settings, limits, the evaluator (its checks), the
    findings, the source text of every line named, the seconds it took, and (with the routine)
    how its answers agreed with the reference's (routine.Agreement; None: not used), for a
    machine with task coordinates its manifold.Manifold and for one with a wrist its
    five_axis.FiveAxis (None for other robots, a three-axis wrist's included), and for G-code
    what reading it showed (interpreter.Reading: the motions emitted, the work offset; None
    for a CSV)."""

    robot: object
    program: str
    settings: Settings
    posture: int
    limits: object
    evaluator: object
    findings: Findings
    sources: dict
    seconds: float
    agreement: object = None
    manifold: object = None
    five_axis: object = None
    reading: object = None


@dataclass
class Piece:
    """Regular samples ``begin`` .. ``end`` of a move cut into ``count`` intervals (the samples
    ``low`` .. ``high`` around them are solved too, for the finite differences); ``index`` the
    move's place in the program, ``timing`` its Profile (None: not timed), ``length`` its path
    length (mm or degrees)."""

    index: int
    move: object
    count: int
    begin: int
    end: int
    timing: object
    length: float

    @property
    def low(self):
        return max(0, self.begin - 1)

    @property
    def high(self):
        return min(self.count, self.end + 1)

    @property
    def straight(self):
        return self.move.arc is None


class _Checker:
    def __init__(self, robot, settings, sink, progress, csv):
        self.robot, self.settings, self.sink, self.progress = robot, settings, sink, progress
        self.manifold = Manifold(robot, settings.task_only, csv) if robot.task else None
        # A three-axis wrist's world is the tool pose, X Y Z A B C read as a hexapod's (roll, pitch, yaw).
        self.five_axis = FiveAxis(robot) if robot.wrist is not None and not robot.wrist.whole_pose else None
        self.world = self.five_axis is not None and not csv
        self.interpolation = "linuxcnc" if self.world else settings.host  # a five-axis world moves linearly
        self.posture = robot.working_posture if settings.posture is None else settings.posture
        read = load_ini(settings.ini, ini_keys(robot.joint_count)) if settings.ini is not None else None
        self.limits = limits_for(robot, settings.ini, read)
        self.setup = self._setup(read)
        self.total_samples = 0
        self.evaluator = Evaluator(robot, self.posture, self.limits)
        self.findings = Findings(robot.joint_names, np.where(robot.revolute, 180.0 / np.pi, 1.0))
        self.pieces, self.samples, self.move_sign = [], 0, 1.0
        self.routine = RoutineSolver(robot, settings.host, self.posture, settings.out_dir,
                                     settings.timeout) if settings.routine else None

    def _setup(self, read):
        """What LinuxCNC's interpreter starts with: the ``.ini``'s tool table, parameter file,
        length unit and subroutine path, the settings' offset and time."""
        files = ini_files(read) if read is not None else {}
        return Setup(files.get(("EMCIO", "TOOL_TABLE")), files.get(("RS274NGC", "PARAMETER_FILE")),
                     self.settings.offset, self.limits.machine.unit if read is not None else 1.0,
                     self.settings.interpreter_seconds, ini_subroutine_path(read) if read is not None else ())

    def add(self, index, move, timing, program):
        """Cut a move, timed by ``timing`` (a timing.Profile, planner.Plan or None), into pieces
        and check them when a batch is full; KingenError at the move's line when the program asks
        for more regular samples than the settings allow."""
        count = sample_count(move, self.settings.chord)
        self.total_samples += count
        if self.total_samples > self.settings.max_samples:
            raise located(move.file or program, move.line, "samples",
                          f"the program asks for more than {self.settings.max_samples} samples at chord "
                          f"{self.settings.chord:g} mm/deg by this line (--max-samples)")
        self.findings.moves += 1
        self.findings.timed_moves += timing is not None
        self.findings.accelerated_moves += has_accelerations(move, timing)
        length = timing.length if timing is not None else max(lengths(move))
        for begin in range(0, count, CHUNK):
            end = min(count, begin + CHUNK)
            self.pieces.append(Piece(index, move, count, begin, end, timing, length))
            self.samples += end - begin + 3
            if self.samples >= CHUNK:
                self.flush()

    def _tabulate(self):
        """The gathered pieces' moves as arrays, for evaluate: which are straight lines in the
        host's interpolation, their start and end poses, their assembly signs, which have stretches
        on a blend arc (planner.Plan.blended)."""
        host = self.interpolation
        self.simple = np.array([p.straight and (host == "linuxcnc" or np.array_equal(p.move.start[3:], p.move.end[3:]))
                                for p in self.pieces])
        self.starts = np.array([p.move.start for p in self.pieces])
        self.ends = np.array([p.move.end for p in self.pieces])
        self.signs = np.ones(len(self.pieces))
        planned_pieces = [number for number, p in enumerate(self.pieces) if isinstance(p.timing, Plan)]
        self.stack = Stack([self.pieces[number].timing for number in planned_pieces])
        self.plan_of = np.full(len(self.pieces), -1)
        self.plan_of[planned_pieces] = np.arange(len(planned_pieces))
        self.blended = np.array([isinstance(p.timing, Plan) and p.timing.arcs for p in self.pieces])
        self.lengths = np.array([p.length for p in self.pieces])

    def evaluate(self, piece, u):
        """The Batch of pieces ``piece`` (indices into self.pieces) at their moves' parameters ``u``."""
        poses, t6 = np.empty((len(u), 6)), np.empty((len(u), 4, 4))
        simple = self.simple[piece]
        if np.any(simple):
            starts, ends = self.starts[piece[simple]], self.ends[piece[simple]]
            poses[simple] = starts + u[simple, None] * (ends - starts)
            t6[simple] = t6_from_pose(poses[simple])
        for number in np.unique(piece[~simple]):
            rows = np.flatnonzero(piece == number)
            poses[rows], t6[rows] = poses_and_t6(self.pieces[number].move, u[rows], self.interpolation)
        rows = np.flatnonzero(self.blended[piece])
        if len(rows):
            on, xyz = self.stack.blended(self.plan_of[piece[rows]], u[rows] * self.lengths[piece[rows]])
            rows = rows[on]
            poses[rows, :3] = xyz
            t6[rows] = t6_from_pose(poses[rows])
        batch = self.evaluator.evaluate(piece, u, *self._commanded(poses, t6))
        column = self.evaluator.assembly_column()
        if column is not None:
            batch.margins[:, column] *= self.signs[piece]
        return batch

    def flush(self):
        """Check the gathered pieces as one batch."""
        if not self.pieces:
            return
        pieces = self.pieces
        grid_piece = np.concatenate([np.full(p.high - p.low + 1, number) for number, p in enumerate(pieces)])
        grid_u = np.concatenate([np.arange(p.low, p.high + 1) / p.count for p in pieces])
        self._tabulate()
        self._sign_starts()
        grid = self.evaluate(grid_piece, grid_u)
        if self.routine is not None:
            self._routine_joints(grid)
        starts = np.concatenate([[0], np.cumsum([p.high - p.low + 1 for p in pieces])])
        regions, owned = [], []
        for number, piece in enumerate(pieces):
            first = starts[number] - piece.low
            regions.append(np.arange(first + piece.begin, first + piece.end + 1))
            owned.append(np.arange(first + piece.begin + (piece.index > 0 and piece.begin == 0),
                                   first + piece.end + (piece.end == piece.count)))
        path = self._path_rates(grid)
        speeds, accelerations = self._rates(grid, path)
        batch, _ = refined(grid.take(np.concatenate(regions)), self.evaluate)
        ends = np.array([p.end / p.count if p.end < p.count else np.inf for p in pieces])[batch.piece]
        keep = batch.u < ends
        keep &= ~((batch.u == 0.0) & np.array([p.index > 0 and p.begin == 0 for p in pieces])[batch.piece])
        batch = batch.take(keep)
        if self.manifold is not None:
            self.manifold.observe(batch.poses, batch.warnings != WARNINGS["WARN_UNREACHABLE"])
        owned = np.concatenate(owned)
        lines = np.array([p.move.line for p in pieces])
        owned_grid = grid.take(owned)
        judge_margins(self.findings, self.evaluator, batch, pieces, lines, sample_numbers(self.findings, owned_grid, batch))
        judge_rates(self.findings, self.limits, owned_grid, speeds[owned], accelerations[owned], pieces, lines)
        if power_limited(self.robot):
            t6 = self.five_axis.t6(grid.poses) if self.world else t6_from_pose(grid.poses)
            power = actuator_power(self.evaluator.robot, t6, platform_motion(t6, *path), speeds)
            judge_power(self.findings, self.robot, owned_grid, *(part[owned] for part in power), pieces, lines)
        record(self.findings, batch, owned_grid, speeds[owned], accelerations[owned], pieces, lines, self.sink)
        if self.progress is not None:
            self.progress(self.findings)
        self.pieces, self.samples = [], 0

    def _routine_joints(self, grid):
        """The regular samples' joints and warnings from the routine, compared with the
        reference's; out of reach (the reference's warning) the reference's joints are kept."""
        joints, warnings = self.routine(self.five_axis.t6(grid.poses) if self.world else t6_from_pose(grid.poses))
        reachable = grid.warnings != WARNINGS["WARN_UNREACHABLE"]
        self.routine.compare(joints, warnings, grid.joints, grid.warnings, reachable, self.findings.display_scale)
        grid.joints = np.where(reachable[:, None], joints, grid.joints)
        grid.warnings = warnings

    def _sign_starts(self):
        """Each piece's assembly sign: the determinant's sign at its move's start, found for a
        move's first piece and kept by its later ones (the pieces of a move come in order)."""
        column = self.evaluator.assembly_column()
        if column is None:
            return
        firsts = np.array([number for number, piece in enumerate(self.pieces) if piece.begin == 0], dtype=int)
        determinant = self.evaluate(firsts, np.zeros(len(firsts))).margins[:, column] if len(firsts) else []
        signs = dict(zip(firsts.tolist(), determinant))
        for number, piece in enumerate(self.pieces):
            self.signs[number] = (1.0 if signs[number] >= 0 else -1.0) if number in signs else self.move_sign
            self.move_sign = self.signs[number]

    def _path_rates(self, grid):
        """(s, runs, rate, change) (n,) at every grid sample: the path coordinate (mm or degrees),
        the runs of samples differenced together, the path's speed ds/dt and its change d2s/dt2
        (NaN for moves not timed)."""
        s = grid.u * self.lengths[grid.piece]
        profiles = [piece.timing if isinstance(piece.timing, Profile) else None for piece in self.pieces]
        length, speed, acceleration = (np.array([np.nan if timing is None or getattr(timing, name) is None
                                                 else getattr(timing, name) for timing in profiles])[grid.piece]
                                       for name in ("length", "speed", "acceleration"))
        rate, change = path_rates(s, length, speed, acceleration)
        rate = np.where(np.isfinite(speed), rate, np.nan)
        runs = grid.piece * 1024  # a move's samples differenced within each planner segment it follows
        planned = np.flatnonzero(self.plan_of[grid.piece] >= 0)
        if len(planned):
            rate[planned], change[planned], part = self.stack.rates(self.plan_of[grid.piece[planned]], s[planned])
            runs[planned] += part
        return s, runs, rate, change

    def _rates(self, grid, path):
        """(speeds, accelerations) (n, dof) at every grid sample (NaN for moves not timed), from
        its _path_rates ``path``."""
        s, runs, rate, change = path
        bounds = np.searchsorted(grid.piece, np.arange(len(self.pieces) + 1))
        speeds, accelerations = joint_rates(grid.joints, s, runs, self.robot.revolute, rate, change)
        for number, piece in enumerate(self.pieces):
            if getattr(piece.timing, "tail", None) is not None:
                rows = slice(bounds[number], bounds[number + 1])
                speeds[rows] += piece.timing.overlap(s[rows])[:, None] * self._slope(piece.timing.following)
        timed = np.isfinite(rate)
        speeds[~timed], accelerations[~timed] = np.nan, np.nan
        return speeds, accelerations


    def _commanded(self, poses, t6):
        """(poses, T6) the machine is commanded to for path samples ``poses`` (n, 6) and their T6: a
        constrained machine's on its manifold, a wrist machine's five-axis world read as its tool's."""
        if self.manifold is not None:
            poses, t6 = self.manifold.samples(poses)
        if self.world:
            t6 = self.five_axis.t6(poses)
        return poses, t6

    def _slope(self, move):
        """(dof,) the joints' derivative along ``move``'s path at its start (per mm), the reference's
        joints 0.01 mm apart (the routine is not asked)."""
        length = lengths(move)[0]
        u = np.array([0.0, min(1.0, 0.01 / length)])
        joints = self.evaluator.evaluate(np.zeros(2, dtype=int), u,
                                         *self._commanded(*poses_and_t6(move, u, self.interpolation))).joints
        step = np.where(self.robot.revolute, np.angle(np.exp(1j * (joints[1] - joints[0]))), joints[1] - joints[0])
        return step / (u[1] * length)


def program_moves(path, start, setup=Setup(), reading=None):
    """The moves of the program at ``path``: a G-code file through LinuxCNC's interpreter, the
    machine at world position ``start`` (mm, degrees) when it begins, with ``setup`` (its
    Reading filled into ``reading``); any other file as a CSV of poses (which starts at its
    first row)."""
    return gcode_moves(path, start, setup, reading) if is_gcode(path) else csv_moves(path)


def check_program(robot, program, settings=Settings(), sink=None, progress=None):
    """Check ``program`` (a G-code file or a CSV of poses, :mod:`.program`) on ``robot`` with
    ``settings``: the Outcome. ``sink(lines, batch, rates)`` receives every sample as it is
    judged (lines (n,) their program lines; rates (n, 2, dof): speeds and accelerations, NaN
    off the regular samples); ``progress(findings)`` is called after each batch. KingenError on
    bad input. A machine with task coordinates is followed along its manifold (:mod:`.manifold`):
    every sample is the machine's pose at its task coordinates; a G-code program for a machine
    with a wrist commands its five-axis world (:mod:`.five_axis`)."""
    started = time.perf_counter()
    csv = not is_gcode(program)
    checker = _Checker(robot, settings, sink, progress, csv)
    reading = None if csv else Reading()
    if reading is not None and settings.offset is not None:
        reading.offset_from = "--offset"
    elif reading is not None and checker.setup.parameter_file is not None:
        reading.offset_from = f"{checker.setup.parameter_file}"
    moves = program_moves(program, checker.five_axis.start() if checker.world else robot.verification.home,
                          checker.setup, reading)
    if checker.manifold is not None and csv:
        moves = checker.manifold.moves(moves, checker.findings)
    timed = ((move, profile(move, checker.limits)) for move in moves) if csv else planned(moves, checker.limits)
    for index, (move, timing) in enumerate(timed):
        checker.add(index, move, timing, program)
    checker.flush()
    findings = checker.findings
    return Outcome(robot, str(program), settings, checker.posture, checker.limits, checker.evaluator, findings,
                   _sources(program, findings), time.perf_counter() - started,
                   None if checker.routine is None else checker.routine.agreement, checker.manifold, checker.five_axis,
                   reading)


def _sources(program, findings):
    """{(file, line): its text} of every place the findings name (file None: the program)."""
    places = list(findings.problems.values()) + list(findings.first.values()) + list(findings.worst.values())
    sources = {}
    for file in {place.file for place in places}:
        texts = source_lines(file or program, {place.line for place in places if place.file == file})
        sources.update({(file, line): text for line, text in texts.items()})
    return sources
