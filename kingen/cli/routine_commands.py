"""The commands that make and check a routine for a host: render, build, package, verify,
bench, golden record, info."""

import contextlib
import functools
import json
import sys
from pathlib import Path

import click

from ..defaults import MAX_PROCESSES, TARGETS
from ..runtime.executors import checked_scheduler
from ..runtime.text import counted
from .common import (EXIT_FAILED, HOST, OUT_DIR, ROBOT, TIMEOUT, _output_file, cli, host_target, in_child,
                     load_model, output_width, plugin_options, processes_text, routine_to_check, say,
                     say_fitted, calibration_options)

MAX_BENCH_CALLS = 100_000_000


@cli.command()
@ROBOT
@OUT_DIR
@HOST
def render(robot, out_dir, host):
    """Write the routine's source (kin_<name>.c for DELMIA) into the output folder."""
    model = load_model(robot)
    path = host.write_source(model, out_dir or host.out_dir(model))
    say(str(path))


@cli.command()
@ROBOT
@OUT_DIR
@click.option("--debug", is_flag=True, help="Compile with KINGEN_DEBUG (DELMIA-style printing; slow).")
@click.option("--target", type=click.Choice(TARGETS), default="linux", show_default=True,
              help="linux: lib<name>.so with $CC; windows: lib<name>.dll cross-compiled with mingw-w64.")
@HOST
@TIMEOUT
def build(robot, out_dir, debug, target, host, timeout):
    """Render and compile the plugin, host symbols left to the host, as for DELMIA."""
    target = host_target(host, target, "build")
    model = load_model(robot)
    result = host.build(model, out_dir, target=target, defines=("KINGEN_DEBUG",) if debug else (), timeout=timeout)
    state = "compiled" if result.compiled else "up to date"
    say(f"{result.library} ({state}; routine {result.routine}, source {result.source})")


@cli.command()
@ROBOT
@OUT_DIR
@click.option("--target", type=click.Choice(TARGETS), default="windows", show_default=True,
              help="windows: source, nmake makefile, .def, BUILD.txt; linux: source and lib<name>.so.")
@HOST
@TIMEOUT
def package(robot, out_dir, target, host, timeout):
    """A folder ready for the simulator, with SETUP.md: what to type into each dialog tab.

    The folder is written whole or not at all; an existing folder is replaced only when
    kingen wrote it."""
    from ..kinematics.home import check_size

    target = host_target(host, target, "package")
    model = load_model(robot)
    check_size(model, "a package")
    paths = host.package(model, out_dir or host.package_dir(model, target), target=target, timeout=timeout)
    for path in paths:
        say(str(path))
    for notice in getattr(paths, "notices", ()):
        say(f"notice: {notice}", err=True)


@cli.command()
@ROBOT
@OUT_DIR
@plugin_options
@click.option("--samples", type=click.IntRange(min=1), default=10000, show_default=True,
              help="Poses drawn in the robot's verification region (memory does not grow with it).")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True, help="Seed of the pose generator.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write the report as JSON to this file (null: not a finite number).")
@click.option("--junit", "junit_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write the report as JUnit XML (one test case per check) to this file.")
@click.option("--golden", "snapshot_path", type=click.Path(dir_okay=False, exists=True, path_type=Path), default=None,
              help="Also check the routine against this recorded snapshot (kingen golden record).")
@click.option("--processes", type=click.IntRange(min=1, max=MAX_PROCESSES), default=None,
              help="Processes comparing the poses (the same report whatever the number)  "
                   "[default: one per core].")
@click.option("--scheduler", default=None, metavar="ADDRESS", callback=checked_scheduler,
              help="Compare the poses on a Dask cluster (its scheduler's address, e.g. tcp://host:8786) instead of "
                   "local processes (the same report); needs the 'distributed' package.")
@calibration_options
@HOST
@TIMEOUT
def verify(robot, out_dir, library, source, routine, samples, seed, json_path, junit_path, snapshot_path, processes,
           scheduler, link_lengths, link_offsets, host, timeout):
    """Compare a routine with the reference: exit 0 when all agree, 1 when not.

    By default builds ROBOT's plugin (if needed); --plugin or --source verify any routine
    that follows the DELMIA interface, hand-written ones included. Plugin code runs in a
    child process, so a routine that crashes, exits or hangs becomes a failed check.
    """
    from ..runtime.files import write_atomic
    from ..verify.snapshot import load as load_snapshot
    from ..verify import VerifyOptions, verify_library

    if processes is not None and scheduler is not None:
        raise click.UsageError("give at most one of --processes and --scheduler")
    model = load_model(robot)
    snapshot = load_snapshot(snapshot_path, model) if snapshot_path is not None else None
    library, routine = routine_to_check(model, host, out_dir, library, source, routine, timeout)
    model = host.as_seen(model)
    options = VerifyOptions(samples=samples, seed=seed, link_lengths=link_lengths, link_offsets=link_offsets,
                            timeout=timeout, snapshot=snapshot, processes=processes, scheduler=scheduler)
    with _progress(samples, model) as progress:
        report = verify_library(model, library, routine, options, progress, host=host)
    print_report(report, library)
    if json_path is not None:
        from ..verify.report import json_text

        write_atomic(json_path, json_text(report, options))
    if junit_path is not None:
        from ..verify.report import junit_xml

        write_atomic(junit_path, junit_xml(report))
    return 0 if report.passed else EXIT_FAILED


@cli.command()
@ROBOT
@OUT_DIR
@plugin_options
@click.option("--calls", type=click.IntRange(min=1, max=MAX_BENCH_CALLS), default=200000, show_default=True,
              help="Routine calls per timing (the per-call path uses at most 20000).")
@click.option("--floor", "floor_source", type=click.Path(dir_okay=False, exists=True, path_type=Path), default=None,
              help="A hand-written C routine for ROBOT (benchmarks/floors/): time it against the routine, "
                   "in turns, and print the ratio.")
@click.option("--json", "json_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              callback=_output_file, help="Write the figures as JSON to this file.")
@HOST
@TIMEOUT
def bench(robot, out_dir, library, source, routine, calls, floor_source, json_path, host, timeout):
    """Print ns per routine call (C batch driver, per-call cffi or wasmtime) and poses per second.

    A --floor is verified first (on a few thousand poses, as verify --source would) and refused
    when it fails a check: only a correct floor gives a meaningful ratio."""
    from ..verify.bench import Figures, verify_floor
    from ..runtime.files import write_atomic
    from ..runtime.wire import typed

    model = load_model(robot)
    seen = host.as_seen(model)
    floor = None
    if floor_source is not None:
        floor = host.build_source(floor_source, (out_dir or host.out_dir(seen)) / "floor", timeout=timeout)
        verify_floor(seen, host, floor, floor_source, timeout)
    library, routine = routine_to_check(model, host, out_dir, library, source, routine, timeout)
    model = seen
    figures = in_child(_bench_job, (model, host, library, routine, calls, floor), timeout, host,
                       {"result": functools.partial(typed, Figures)})
    say(f"bench {model.name} ({routine}, {counted(model.postures, 'posture')}, {counted(figures['calls'], 'call')})")
    say(f"  routine via C batch driver: {figures['batch_ns_per_call']:10.1f} ns/call")
    say(f"  {f'routine via {host.per_call} per call:':<28}{figures['cffi_ns_per_call']:10.1f} ns/call")
    if "worst_call_ns" in figures:
        say(f"  each call timed singly:     {figures['median_call_ns']:10.1f} ns median, "
            f"{figures['worst_call_ns']:.1f} ns worst of {figures['single_calls']:,} calls")
    say(f"  numpy reference:            {figures['reference_poses_per_second']:10,.0f} poses/s")
    say(f"  verify (everything):        {figures['verify_poses_per_second']:10,.0f} poses/s "
         f"({processes_text(figures['verify_processes'])})")
    if floor is not None:
        against = figures["against_floor"]
        say(f"  against the floor {floor_source} ({against['rounds']} rounds in turns, ns/call):")
        for label in ("floor", "routine"):
            say(f"    {label + ':':9} min {against[label]['min']:9.1f}, median {against[label]['median']:9.1f}")
        say(f"    ratio:    min {against['ratio_min']:9.3f}, median {against['ratio_median']:9.3f}")
    if json_path is not None:
        write_atomic(json_path, json.dumps(figures, indent=2, allow_nan=False) + "\n")


@cli.group()
def golden():
    """Recorded snapshots of poses, joints and warnings (checked by verify --golden)."""


@golden.command("record")
@ROBOT
@plugin_options
@click.option("--samples", type=click.IntRange(min=1, max=100000), default=100, show_default=True,
              help="Poses to record (at most what fits in the 64 MB verify --golden reads).")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True, help="Seed of the poses.")
@click.option("-o", "--output", "output", type=click.Path(dir_okay=False, path_type=Path), required=True,
              callback=_output_file, help="The snapshot file to write (rewritten whole).")
@HOST
@TIMEOUT
def golden_record(robot, library, source, routine, samples, seed, output, host, timeout):
    """Record a snapshot from the reference, or from a trusted plugin (--plugin/--source).

    A count whose file verify --golden would refuse as too large is refused before anything
    is computed. The entries are written as they are computed, a chunk at a time (memory
    does not grow with --samples); OUTPUT is replaced only by the complete file."""
    from ..verify.snapshot import check_fits, recording, t6_chunks
    from ..verify import chunk_size

    model = load_model(robot)
    chunk = chunk_size(model)
    if library is None and source is None:
        if routine is not None:
            raise click.UsageError("--routine needs --plugin or --source")
        from ..kinematics.reference import solve as reference_solve

        recorded_from = "the reference"
        check_fits(model, samples, recorded_from, seed)
        with recording(output, model, recorded_from, samples, seed) as snapshot:
            for t6 in t6_chunks(model, samples, seed, chunk):
                expected = reference_solve(model, t6)
                snapshot.add(t6, expected.joints, expected.warnings)
    else:
        library, routine = routine_to_check(model, host, None, library, source, routine, timeout)
        recorded_from = f"plugin {Path(library).name} ({routine})"
        check_fits(model, samples, recorded_from, seed)
        with recording(output, model, recorded_from, samples, seed) as snapshot:
            in_child(_record_job, (host, model, library, routine, samples, seed, chunk), timeout, host,
                     {"chunk": _chunk_decoder(t6_chunks(model, samples, seed, chunk))},
                     lambda kind, chunk: snapshot.add(chunk[0], chunk[1].solutions, chunk[1].warnings))
    say(f"{output}: {counted(samples, 'pose')} x {counted(model.postures, 'posture')} recorded from {recorded_from}")


@cli.command()
@click.argument("library", type=click.Path(dir_okay=False, exists=True, path_type=Path))
def info(library):
    """What a compiled library says about itself (read from its bytes, never loaded).

    Its build information is a label the library carries, not a proof of who built it."""
    from ..runtime.library_info import binary_format, build_info

    details = build_info(library)
    say(f"library: {library}")
    say(f"format: {binary_format(library)}")
    if details is None:
        say("kingen build information: none (the library carries no kingen build-info string)")
        return 0
    say(f"robot: {details.get('robot', '?')}")
    say(f"routine: {details.get('routine', '?')}")
    say(f"dof: {details.get('dof', '?')}, postures: {details.get('postures', '?')}")
    say(f"definition sha256: {details.get('sha256', '?')}")
    say(f"says it was built by: kingen {details.get('kingen', '?')}")
    if "host" in details:
        say(f"host: {details['host']}" + (f", the robot file's posture {details['posture']}" if "posture" in details else ""))
    say("note: the lines above are the library's build information, a label it carries, not a proof "
        "that kingen built it")
    return 0


def _record_job(channel, host, model, library, routine, samples, seed, chunk):
    """In a child process: the routine's (solutions, warnings) for a snapshot's poses, sent
    chunk by chunk as they are computed."""
    from ..verify.snapshot import t6_chunks

    plugin = host.load(library, routine, model)
    channel.stage("the routine's calls")
    for t6 in t6_chunks(model, samples, seed, chunk):
        channel.send("chunk", plugin.call(t6, None, None))


def _chunk_decoder(poses):
    """Decodes each chunk _record_job sends into (its poses, their Calls), the poses drawn
    here again from the iterator ``poses``; WireError for a chunk of another length or one
    more than was drawn."""
    from ..kinematics.routine import calls_decoder
    from ..runtime.wire import WireError

    def decode(value):
        t6 = next(poses, None)
        if t6 is None:
            raise WireError("more chunks than the snapshot has poses")
        return t6, calls_decoder(len(t6))(value)
    return decode


def _bench_job(channel, model, host, library, routine, calls, floor):
    from ..verify.bench import ROUNDS, benchmark, compare
    from ..runtime.isolation import keep_freed_memory

    keep_freed_memory()  # as verify's child does, so that its poses per second are verify's
    plugin = host.load(library, routine, model)
    channel.stage("the timings")
    tick = lambda: channel.send("progress", None)  # noqa: E731
    figures = benchmark(model, plugin, calls=calls, tick=tick)
    if floor is not None:
        channel.stage("the timings against the floor")
        timings = compare(model, {"floor": host.load(floor, host.routine_name(model), model), "routine": plugin}, calls=calls, tick=tick)
        figures["against_floor"] = {
            **timings, "rounds": ROUNDS,
            "ratio_min": timings["routine"]["min"] / timings["floor"]["min"],
            "ratio_median": timings["routine"]["median"] / timings["floor"]["median"],
        }
    return figures


def _progress(total, robot):
    """A progress bar on stderr for runs of several of verify's chunks of ``robot`` at a
    terminal; otherwise nothing (and the chunk size, which probes the reference, is left to
    verify's child)."""
    from ..verify import chunk_size

    if sys.stderr is None or not sys.stderr.isatty() or total <= chunk_size(robot):
        return contextlib.nullcontext(None)
    bar = click.progressbar(length=total, label="verifying", file=sys.stderr)

    @contextlib.contextmanager
    def running():
        with bar:
            yield lambda done: bar.update(done - bar.pos)

    return running()


def print_report(report, library):
    """The report as text, each line fitted to output_width() with continuation lines
    indented, so every check's line still starts ``  ok     NAME:`` or ``  FAILED NAME:``."""
    width = output_width()
    say_fitted(f"verify {report.robot}: {counted(report.samples, 'pose')} x {counted(report.postures, 'posture')}, "
               f"{library} ({report.routine})", width)
    for check in report.checks:
        say_fitted(f"  {check.status:6} {check.name}: {check.detail}" if check.exercised or not check.passed
                   else f"  {check.name}: not exercised: {check.detail}", width, " " * 9)
        for diagnosis in check.diagnoses:
            say_fitted(f"         diagnosis: {diagnosis}", width, " " * 11)
    from ..verify.report import statistics_lines

    for line in statistics_lines(report):
        say_fitted(f"  {line}", width, "    ")
    for notice in report.notices:
        say_fitted(f"  notice: {notice}", width, "    ")
    if report.isolation:
        say_fitted(f"  isolation: {report.isolation}", width, "    ")
    verdict = "PASSED" if report.passed else f"FAILED ({len(report.failures)} of {len(report.checks)} checks)"
    speed = (f"; the sampled poses compared in {report.seconds:.2f} s ({report.poses_per_second:,.0f} poses/s, "
             f"{processes_text(report.processes)})" if report.seconds > 0 else "")
    say_fitted(verdict + speed, width)
