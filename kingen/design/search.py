"""The design search: the thesis's constriction particle swarm (pymoo's PSO with w = K,
c1' = K c1, c2' = K c2, no adaptation, no perturbation of the best), then scipy's
trust-constr from the swarm's best, over a robot file's design problem (:mod:`kingen.design.problem`).

Particles are evaluated through :func:`kingen.runtime.executors.executor` (a process pool, or Dask's
distributed executor for a cluster); the swarm's random numbers come only from the seed, so
a search gives the same result for any number of workers. After every iteration the whole
state is written to a checkpoint, from which ``resume`` continues to the same result as an
uninterrupted run. The checkpoint is plain data (:mod:`kingen.design.checkpoint`), from which the
swarm is rebuilt: no code is ever loaded from it.
"""

import copy
import json
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from . import checkpoint
from .checkpoint import CHECKPOINT  # noqa: F401  (where optimize's output folder keeps it)
from .problem import evaluate, settings_of
from ..errors import KingenError
from ..runtime.files import digest


@dataclass
class SearchState:
    """Everything a search needs to continue: the pymoo algorithm (swarm, velocities, its
    random state), the best design so far, the history of the best objective per iteration,
    and the counts."""

    algorithm: "pymoo.algorithms.soo.nonconvex.pso.PSO"
    seed: int
    fingerprint: str
    iteration: int = 0
    evaluations: int = 0
    poses: int = 0
    best_x: np.ndarray = None
    best_objective: float = -1.0
    best_table: list = None
    history: list = field(default_factory=list)
    since_improvement: int = 0
    seconds: float = 0.0


def fingerprint(problem):
    """What a checkpoint must have been made for: the robot file's data with its design
    problem, but for the number of iterations (a resumed run may go further)."""
    data = copy.deepcopy(problem.data)
    data["optimize"].get("search", {}).pop("iterations", None)
    return digest(json.dumps(data, sort_keys=True, default=str))


def new_state(problem, seed, fingerprint):
    """A swarm of ``search.swarm`` particles for ``problem``, seeded. pymoo never ends it (its
    own termination criteria would finish the algorithm, which a swarm rebuilt from a checkpoint
    cannot do: run_swarm alone decides when the search stops)."""
    from pymoo.algorithms.soo.nonconvex.pso import PSO
    from pymoo.core.problem import Problem as PymooProblem
    from pymoo.core.termination import NoTermination

    search = problem.section.search
    k = search.constriction
    algorithm = PSO(pop_size=search.swarm, w=k, c1=k * search.c1, c2=k * search.c2, adaptive=False,
                    pertube_best=False, max_velocity_rate=1.0, termination=NoTermination())
    bounds = PymooProblem(n_var=len(problem.names), n_obj=1, xl=problem.lower, xu=problem.upper)
    algorithm.setup(bounds, seed=seed, verbose=False)
    return SearchState(algorithm=algorithm, seed=seed, fingerprint=fingerprint)


def save(state, folder):
    """Checkpoint ``state`` into ``folder`` (atomically, as plain data: kingen.design.checkpoint)."""
    algorithm = state.algorithm
    particles, bests = algorithm.particles, algorithm.pop
    generator = algorithm.random_state.bit_generator.state
    swarm = checkpoint.Swarm(
        iteration=algorithm.n_iter, x=particles.get("X").tolist(), v=particles.get("V").tolist(),
        f=particles.get("F")[:, 0].tolist(), best_x=bests.get("X").tolist(), best_f=bests.get("F")[:, 0].tolist(),
        random_state=generator["state"]["state"], random_increment=generator["state"]["inc"],
        random_has_uint32=generator["has_uint32"], random_uinteger=generator["uinteger"])
    checkpoint.write(folder, checkpoint.Checkpoint(
        format=checkpoint.FORMAT, version=checkpoint.VERSION, fingerprint=state.fingerprint, seed=state.seed,
        iteration=state.iteration, evaluations=state.evaluations, poses=state.poses,
        best_x=None if state.best_x is None else [float(value) for value in state.best_x],
        best_objective=state.best_objective, best_table=state.best_table, history=state.history,
        since_improvement=state.since_improvement, seconds=state.seconds, swarm=swarm))


def load(folder, problem, expected):
    """The SearchState checkpointed in ``folder`` for ``problem``: its swarm rebuilt from the
    checkpoint's data, so that the search continues as if never stopped. KingenError when there
    is none, it is not a checkpoint kingen accepts (kingen.design.checkpoint.read), or it was made for
    another problem (fingerprint ``expected``) or does not fit this one's swarm and variables."""
    data = checkpoint.read(folder)
    path = folder / CHECKPOINT
    if data.fingerprint != expected:
        raise KingenError(f"{path}: the checkpoint is of another design problem (the robot file or its "
                          "optimize: section changed)")
    swarm, particles, variables = data.swarm, problem.section.search.swarm, len(problem.names)
    for name in ("x", "v", "best_x"):
        rows = getattr(swarm, name)
        if len(rows) != particles or any(len(row) != variables for row in rows):
            raise KingenError(f"{path}: swarm.{name}: not {particles} particles of {variables} variables")
    for name in ("f", "best_f"):
        if len(getattr(swarm, name)) != particles:
            raise KingenError(f"{path}: swarm.{name}: not {particles} particles")
    if data.best_x is not None and len(data.best_x) != variables:
        raise KingenError(f"{path}: best_x: not {variables} variables")
    problem_found = _out_of_range(data, problem)
    if problem_found is not None:
        raise KingenError(f"{path}: {problem_found}, which no search of this problem writes")
    state = new_state(problem, data.seed, expected)
    _restore_swarm(state.algorithm, swarm)
    best_x = None if data.best_x is None else np.array(data.best_x)
    best_table = None if data.best_table is None else [tuple(row) for row in data.best_table]
    return SearchState(algorithm=state.algorithm, seed=data.seed, fingerprint=expected, iteration=data.iteration,
                       evaluations=data.evaluations, poses=data.poses, best_x=best_x,
                       best_objective=data.best_objective, best_table=best_table, history=list(data.history),
                       since_improvement=data.since_improvement, seconds=data.seconds)


GENERATOR_RANGES = {"random_state": 1 << 128, "random_increment": 1 << 128, "random_has_uint32": 2,
                    "random_uinteger": 1 << 32}
"""PCG64's state fields: each from 0 to below these."""
COUNTERS = ("iteration", "evaluations", "poses", "since_improvement")


def _out_of_range(data, problem):
    """What in the checkpoint ``data`` (of the right shapes) lies outside what a search of
    ``problem`` writes, or None: positions (swarm.x, swarm.best_x, best_x) within the variables'
    bounds, velocities within +/- their widths (pymoo's velocity cap), objective values (swarm.f,
    swarm.best_f negated; best_objective, history, best_table's tilts) within 0 to the
    objective's tilt_max degrees (-1: none yet), the tilt table one row per azimuth with a cause
    analyze names, counters from 0 and the history one entry per iteration, the random
    generator's state within PCG64's ranges. A checkpoint so changed could steer the search
    out of its problem or break it (exit 3) rather than continue it."""
    from .analysis import CAUSES

    swarm, lower, upper = data.swarm, problem.lower, problem.upper
    most = problem.section.objective.tilt_max
    bounds, widths, tilts = "the variables' bounds", "+/- the variables' widths", f"-1 to {most:g} degrees"
    checks = [("swarm.x", swarm.x, lower, upper, bounds), ("swarm.best_x", swarm.best_x, lower, upper, bounds),
              ("swarm.v", swarm.v, lower - upper, upper - lower, widths),
              ("swarm.f", swarm.f, -most, 0.0, f"-{most:g} to 0"), ("swarm.best_f", swarm.best_f, -most, 0.0,
                                                                  f"-{most:g} to 0"),
              ("history", data.history, -1.0, most, tilts), ("best_objective", data.best_objective, -1.0, most, tilts),
              ("seconds", data.seconds, 0.0, np.inf, "0 s or more")]
    if data.best_x is not None:
        checks.append(("best_x", data.best_x, lower, upper, bounds))
    for name, values, low, high, words in checks:
        if not np.all((low <= np.array(values)) & (np.array(values) <= high)):
            return f"{name}: a value outside {words}"
    azimuths = len(settings_of(problem.section.objective).azimuths)
    if data.best_table is not None and (len(data.best_table) != azimuths or any(
            not 0.0 <= tilt <= most or cause not in (*CAUSES, "invalid") for tilt, cause in data.best_table)):
        return f"best_table: not {azimuths} rows of a tilt from 0 to {most:g} degrees and a cause"
    for name in COUNTERS:
        if getattr(data, name) < 0:
            return f"{name}: {getattr(data, name)} below 0"
    if len(data.history) != data.iteration:
        return f"history: {len(data.history)} entries for {data.iteration} iterations"
    for name, end in GENERATOR_RANGES.items():
        if not 0 <= getattr(swarm, name) < end:
            return f"swarm.{name}: not within 0 to {end - 1}"
    return None


def _restore_swarm(algorithm, swarm):
    """Put a checkpoint's Swarm into a freshly set-up pymoo PSO: what its ask and tell read."""
    from pymoo.core.population import Population

    algorithm.particles = Population.new(X=np.array(swarm.x), V=np.array(swarm.v), F=np.array(swarm.f)[:, None])
    algorithm.pop = Population.new(X=np.array(swarm.best_x), F=np.array(swarm.best_f)[:, None])
    algorithm.n_iter = swarm.iteration
    algorithm.is_initialized = True
    algorithm._set_optimum()
    generator = algorithm.random_state.bit_generator.state
    generator.update(state={"state": swarm.random_state, "inc": swarm.random_increment},
                     has_uint32=swarm.random_has_uint32, uinteger=swarm.random_uinteger)
    algorithm.random_state.bit_generator.state = generator


def run_swarm(problem, state, executor, folder=None, progress=None, stop=None):
    """Iterate the swarm until ``search.iterations`` or ``search.patience`` iterations without
    improvement; checkpoint into ``folder`` after each iteration; ``progress(state)`` after
    each. Returns the state."""
    search = problem.section.search
    started = time.perf_counter() - state.seconds
    while state.iteration < search.iterations and state.since_improvement < search.patience:
        if stop is not None and stop():
            break
        offspring = state.algorithm.ask()
        designs = offspring.get("X")
        results = list(executor.map(evaluate, [problem] * len(designs), designs))
        objectives = np.array([result[0] for result in results])
        offspring.set("F", -objectives[:, None])
        state.algorithm.tell(infills=offspring)
        state.iteration += 1
        state.evaluations += len(designs)
        state.poses += sum(result[2] for result in results)
        best = int(np.argmax(objectives))
        if objectives[best] > state.best_objective:
            state.best_objective, state.best_x, state.best_table = float(objectives[best]), designs[best].copy(), \
                results[best][1]
            state.since_improvement = 0
        else:
            state.since_improvement += 1
        state.history.append(state.best_objective)
        state.seconds = time.perf_counter() - started
        if folder is not None:
            save(state, folder)
        if progress is not None:
            progress(state)
    return state


def refine(problem, state, executor):
    """scipy's trust-constr from the swarm's best, maximising the objective within the
    bounds with central differences of the refine section's absolute steps; returns
    (design, objective, table, evaluations). Keeps the swarm's best unless it finds better."""
    from scipy.optimize import Bounds, minimize

    settings = problem.section.refine
    if settings.method == "none" or state.best_x is None:
        return state.best_x, state.best_objective, state.best_table, 0
    steps = np.where(problem.angles, settings.angle_step, settings.length_step)
    count = [0]
    best = [state.best_x.copy(), state.best_objective, state.best_table]

    def value(x):
        objective, table, _ = evaluate(problem, x)
        count[0] += 1
        if objective > best[1]:
            best[:] = [np.array(x, dtype=float), objective, table]
        return -objective

    def gradient(x):
        plus = [np.clip(x + step * unit, problem.lower, problem.upper) for unit, step in zip(np.eye(len(x)), steps)]
        minus = [np.clip(x - step * unit, problem.lower, problem.upper) for unit, step in zip(np.eye(len(x)), steps)]
        points = plus + minus
        results = list(executor.map(evaluate, [problem] * len(points), points))
        count[0] += len(points)
        for point, result in zip(points, results):
            if result[0] > best[1]:
                best[:] = [np.array(point, dtype=float), result[0], result[1]]
        values = np.array([-result[0] for result in results])
        widths = np.array([high[i] - low[i] for i, (high, low) in enumerate(zip(plus, minus))])
        return (values[:len(x)] - values[len(x):]) / np.where(widths > 0, widths, 1.0)

    with warnings.catch_warnings():  # a piecewise-constant objective: quasi-Newton warns of flat steps
        warnings.simplefilter("ignore")
        minimize(value, state.best_x, jac=gradient, method="trust-constr",
                 bounds=Bounds(problem.lower, problem.upper), options={"maxiter": settings.iterations, "verbose": 0})
    return best[0], best[1], best[2], count[0]


@dataclass
class Choice:
    """The design optimize writes: the search's best (after refinement) when it beats the robot
    file's own design, else the file's own (``start_kept``); the start's objective (degrees) and
    tilt table beside it."""

    design: np.ndarray
    objective: float
    table: list
    start: np.ndarray
    start_objective: float
    start_table: list
    start_kept: bool


def choose(problem, best):
    """The robot file's own design is a candidate too: ``best`` (design, objective, table) is
    chosen only if its objective is strictly larger than the start's, so the chosen objective is
    never below the start's."""
    design, objective, table = best
    start = problem.start()
    start_objective, start_table, _ = evaluate(problem, start)
    kept = design is None or not objective > start_objective
    if kept:
        design, objective, table = start, start_objective, start_table
    return Choice(design, objective, table, start, start_objective, start_table, kept)


def result(problem, state, choice, refined_evaluations, workers, seconds):
    """optimization.json's data for the search ``state`` and the ``choice`` (:func:`choose`)."""
    design, objective, table, start = choice.design, choice.objective, choice.table, choice.start
    start_objective, start_table = choice.start_objective, choice.start_table
    azimuths = settings_of(problem.section.objective).azimuths
    robot = problem.robot(design)
    search = problem.section.search
    return {
        "robot": robot.name, "posture": problem.posture(robot),
        "objective_deg": objective, "start_objective_deg": start_objective, "start_kept": choice.start_kept,
        "variables": [{"name": name, "value": float(value), "start": float(first), "lower": float(low),
                       "upper": float(high)} for name, value, first, low, high in
                      zip(problem.names, design, start, problem.lower, problem.upper)],
        "tilt_table": _rows(azimuths, table), "start_tilt_table": _rows(azimuths, start_table),
        "history": list(state.history), "iterations": state.iteration,
        "stopped_by": "iterations" if state.iteration >= search.iterations else (
            "patience" if state.since_improvement >= search.patience else "interrupted"),
        "swarm_objective_deg": state.best_objective, "refinement_evaluations": refined_evaluations,
        "evaluations": state.evaluations + refined_evaluations, "poses": state.poses, "seconds": seconds,
        "seed": state.seed, "workers": workers,
        "settings": {"objective": problem.section.objective.model_dump(), "search": {
            **search.model_dump(), "constriction": search.constriction}, "refine": problem.section.refine.model_dump()},
    }


def _rows(azimuths, table):
    return [{"azimuth_deg": float(azimuth), "max_tilt_deg": tilt, "cause": cause}
            for azimuth, (tilt, cause) in zip(azimuths, table)]
