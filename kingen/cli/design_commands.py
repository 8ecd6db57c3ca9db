"""The command that designs: optimize (the robot file's optimize: section searched by a
particle swarm and refined, on this machine's cores or a Dask cluster)."""

import contextlib
import json
import sys
import time
from pathlib import Path

import click

from ..errors import KingenError
from ..runtime.executors import checked_scheduler
from ..runtime.text import counted
from .common import ROBOT, _out_folder, _output_file, cli, finite, load_model_and_data, say


@cli.command()
@ROBOT
@click.option("-o", "--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None, callback=_out_folder,
              help="Output and checkpoint folder [default: build/<name>/optimize].")
@click.option("--seed", type=click.IntRange(min=0), default=1, show_default=True,
              help="The swarm's seed: the same seed gives the same search on any number of workers.")
@click.option("--iterations", type=click.IntRange(min=1, max=100000), default=None,
              help="Most swarm iterations [default: the robot file's optimize.search.iterations].")
@click.option("--swarm", type=click.IntRange(min=2, max=1000), default=None,
              help="Particles [default: the robot file's optimize.search.swarm].")
@click.option("--workers", type=click.IntRange(min=1, max=256), default=None,
              help="Processes evaluating particles [default: the usable cores].")
@click.option("--scheduler", default=None, metavar="ADDRESS", callback=checked_scheduler,
              help="Evaluate on a Dask cluster (its scheduler's address, e.g. tcp://host:8786) instead of "
                   "local processes; needs the 'distributed' package.")
@click.option("--resume", is_flag=True, help="Continue the search from the checkpoint in the output folder.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Also write optimization.json to this file.")
def optimize(robot, out_dir, seed, iterations, swarm, workers, scheduler, resume, json_path):
    """Search the robot file's design space (its optimize: section) for the largest tilt
    reached in every direction: a particle swarm, then scipy's trust-constr. Writes
    <name>_optimized.yaml (the name cut to fit 63 characters), optimization.json and
    report.html; checkpoints every iteration.

    Exit 0 with a design, 2 bad input, 130 when stopped (the checkpoint continues it: --resume)."""
    from ..design import search
    from ..runtime.executors import executor
    from ..design.problem import Problem, design_yaml, optimized_name
    from ..design.report import convergence, polar_comparison, report_html
    from ..runtime.files import default_out_dir, write_files

    model, data, lines = load_model_and_data(robot)
    if not data.get("optimize"):
        raise KingenError(f"{model.path}: optimize: no design problem in this robot file (see docs/how-to/optimize.md)")
    overrides = {key: value for key, value in (("iterations", iterations), ("swarm", swarm)) if value is not None}
    data["optimize"] = {**data["optimize"], "search": {**data["optimize"].get("search", {}), **overrides}}
    problem = Problem(data, model.path, lines)
    out_dir = out_dir or default_out_dir(model) / "optimize"
    fingerprint = search.fingerprint(problem)
    if resume:
        state = search.load(out_dir, problem, fingerprint)
        say(f"resuming at iteration {state.iteration} (best {state.best_objective:g} deg) from {out_dir}")
    else:
        state = search.new_state(problem, seed, fingerprint)
    with executor(workers, scheduler) as opened:
        pool, described = opened.pool, opened.description
        with _progress(problem.section.search.iterations, state) as progress:
            try:
                search.run_swarm(problem, state, pool, out_dir, progress)
            except (KeyboardInterrupt, SystemExit) as stop:  # Ctrl-C; SIGTERM (kingen.cli raises SystemExit)
                say(_stopped(state, out_dir), err=True)
                if isinstance(stop, SystemExit):
                    raise
                return 130
        started = time.perf_counter()
        best = search.refine(problem, state, pool)
    seconds = state.seconds + time.perf_counter() - started
    choice = search.choose(problem, best[:3])
    outcome = search.result(problem, state, choice, best[3], described, seconds)
    text = json.dumps(finite(outcome), indent=1, allow_nan=False) + "\n"
    name = optimized_name(outcome["robot"])
    found = _found(outcome)
    header = [f"kingen optimize {model.name} --seed {state.seed}: {found}, {outcome['evaluations']} designs evaluated."]
    pngs = {"polar.png": polar_comparison(outcome), "convergence.png": convergence(outcome)}
    outputs = {f"{name}.yaml": design_yaml(problem, choice.design, outcome["objective_deg"], header),
               "optimization.json": text, **pngs, "report.html": report_html(outcome, pngs)}
    write_files({**{out_dir / file_name: content for file_name, content in outputs.items()},
                 **({} if json_path is None else {json_path: text})})
    say(f"optimize {model.name}: {found}; {counted(outcome['iterations'], 'iteration')} "
        f"({outcome['stopped_by']}) and {counted(outcome['evaluations'], 'design')}, {seconds:.1f} s with {described}")
    for file_name in outputs:
        say(str(out_dir / file_name))
    return 0


def _stopped(state, out_dir):
    """What a search stopped by Ctrl-C or SIGTERM leaves, in one line: the iteration its
    checkpoint on disk holds (what --resume continues from: a signal during an iteration's
    bookkeeping leaves the checkpoint one iteration behind ``state``) and how to continue, or that
    it has none."""
    from ..design.checkpoint import read

    try:
        saved = read(out_dir)
        iteration, best = saved.iteration, saved.best_objective
    except KingenError:
        iteration, best = 0, state.best_objective
    if not state.iteration or not iteration:
        return "kingen: stopped before the first iteration ended: no checkpoint to resume from"
    return f"kingen: stopped at iteration {iteration} (best {best:g} deg); continue with --resume from {out_dir}"


def _found(outcome):
    """What the search found, in words: the written design's least tilt against the file's own,
    or that no design beat the file's own and the written design is the file's."""
    if outcome["start_kept"]:
        return (f"no design beat the file's own ({outcome['start_objective_deg']:g} deg): "
                f"the written design is the file's")
    return f"least tilt {outcome['objective_deg']:g} deg (the file's design {outcome['start_objective_deg']:g} deg)"


def _progress(iterations, state):
    """A progress bar over the iterations on a terminal (best objective, designs per second);
    a no-op otherwise."""
    if sys.stderr is None or not sys.stderr.isatty():
        return contextlib.nullcontext(lambda current: None)
    bar = click.progressbar(length=iterations, label="optimising", file=sys.stderr, show_eta=True,
                            item_show_func=lambda current: current)

    @contextlib.contextmanager
    def running():
        with bar:
            bar.update(state.iteration)

            def step(current):
                rate = current.evaluations / current.seconds if current.seconds else 0.0
                bar.update(1, f"best {current.best_objective:g} deg, {rate:.0f} designs/s")
            yield step

    return running()
