"""``robotkit build RECIPE...``: the no-op fast path (stamp), else load, tasks, doit, publish
(:func:`robotkit.pipeline.runner.build`), then the warnings and the collision summary.

Heavy libraries are imported only past the stamp check: a no-op build stays instant."""

from __future__ import annotations

import contextlib
import os
import sys
import time

from robotkit.pipeline import stamp


def cores() -> int:
    """The cores this process may use (the default of ``-j``)."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def run(args) -> int:
    if args.jobs is not None and args.jobs < 1:
        print("robotkit: error: -j must be at least 1", file=sys.stderr)
        return 2
    start = time.perf_counter()
    if args.package_path and not _package_paths_valid(args.package_path):
        return 2
    opts = stamp.build_options(args.recipes, args.out, args.ros, not args.no_report, args.moveit, dict(args.arg),
                               args.variant)
    done = stamp.up_to_date(args.out, opts)  # nothing changed since the last successful build?
    if done is not None:
        return _up_to_date(args, done, start)
    from robotkit.pipeline.runner import build  # past the stamp: the no-op path imports only robotkit.pipeline.stamp

    echo = (lambda line: print(line, file=sys.stderr)) if args.verbose else None
    with scheduler(args) as jobs, cache_messages():
        result = build(args.recipes, args.out, jobs=jobs, echo=echo, progress=sys.stderr, ros=args.ros,
                       report=not args.no_report, stamp_options=opts, args=dict(args.arg),
                       moveit=args.moveit, variant=args.variant)
    if result.ran or args.verbose:
        for w in result.warning_lines:
            print(w, file=sys.stderr)  # file:line: key: warning: ...
    elif result.warning_lines:  # unchanged since they were shown; keep a no-op build quiet
        _warnings_unchanged(len(result.warning_lines))
    if result.errors:
        for name, msg in result.errors:
            print(f"robotkit: internal error in task {name}:\n{msg}", file=sys.stderr)
        return 1
    if result.ran:
        collision_summary(args.out, result.robots)
    elapsed = time.perf_counter() - start
    names = _names(args.out, result.robots)
    if result.ran:
        print(f"built {names}: {len(result.ran)} tasks run, {len(result.uptodate)} up to date ({elapsed:.2f} s)")
    else:
        print(f"{names}: up to date ({len(result.uptodate)} tasks, {elapsed:.2f} s)")
    return 0


def _package_paths_valid(items: list[str]) -> bool:
    """``--package-path``: a recipe names its files by path and reads none, but a malformed one is
    still bad input, as on every command (imported only when given: the no-op build stays light)."""
    from robotkit.commands.inputs import package_paths

    return package_paths(items) is not None


def _names(out: str, robots: list[str]) -> str:
    rel = os.path.relpath(os.path.abspath(out))
    return ", ".join(f"{rel}/{r}" for r in robots)


def _warnings_unchanged(count: int) -> None:
    print(f"{count} warnings, unchanged since the last build (-v shows them; "
          "report.json lists what each format could not express)", file=sys.stderr)


def _up_to_date(args, done: dict, start: float) -> int:
    """What a build that runs no task prints, from the stamp (:mod:`robotkit.pipeline.stamp`)."""
    warnings = done.get("warnings", [])
    if args.verbose:
        for w in warnings:
            print(w, file=sys.stderr)  # file:line: key: warning: ...
    elif warnings:
        _warnings_unchanged(len(warnings))
    print(f"{_names(args.out, done['robots'])}: up to date ({done['tasks']} tasks, "
          f"{time.perf_counter() - start:.2f} s)")
    return 0


@contextlib.contextmanager
def cache_messages():
    """A shared cache that failed in any task process is told once, after the build (task
    output is captured by doit)."""
    if "://" not in os.environ.get("ROBOTKIT_CACHE", ""):
        yield
        return
    import tempfile

    from robotkit.ioutil import environ  # past the stamp, as every import of this module but stamp
    from robotkit.mesh.cache import REPORT_ENV

    fd, path = tempfile.mkstemp(prefix="robotkit-cache-", suffix=".log")
    os.close(fd)
    with environ({REPORT_ENV: path}):
        try:
            yield
        finally:
            try:
                with open(path, encoding="utf-8") as f:
                    lines = [line.rstrip("\n") for line in f if line.strip()]
                os.unlink(path)
            except OSError:
                lines = []
            if lines:
                print(lines[0], file=sys.stderr)


@contextlib.contextmanager
def scheduler(args):
    """The number of doit jobs, with the Dask scheduler (``--scheduler``, ``local`` or
    $DASK_SCHEDULER_ADDRESS) exported to the task processes (robotkit.pipeline.distributed)."""
    from robotkit.ioutil import environ  # past the stamp, as every import of this module but stamp
    from robotkit.pipeline import distributed

    address = args.scheduler or os.environ.get(distributed.DASK_ENV)
    if not address:
        yield args.jobs or cores()
        return
    with (distributed.LocalCluster() if address == "local" else contextlib.nullcontext()) as cluster:
        address = cluster.address if cluster is not None else address
        # every doit process waits on the cluster: as many as it has threads
        jobs = args.jobs or min(64, cluster.workers if cluster is not None else distributed.cluster_threads(address))
        with environ({distributed.ENV: address}):
            yield jobs


def collision_summary(out: str, robots: list[str]) -> None:
    """One line per collision proxy: strategy, pieces, volume against the visual, distance."""
    import json

    from robotkit.emit.layout import robot_layout  # past the stamp (it loads the emitters)

    for name in robots:
        try:
            summary = json.loads(robot_layout(os.path.join(out, name)).report_json.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        for entry in summary.get("collision", {}).values():
            print(_proxy_line(name, entry), file=sys.stderr)


def _proxy_line(name: str, entry: dict) -> str:
    f = entry["fidelity"]
    ratio = f"{f['volume_ratio']:.3g}x the visual volume" if f.get("volume_ratio") else "visual not closed"
    dist = f.get("distance") or {}
    far = f", surface within {dist['max'] * 1000:.3g} mm" if dist.get("max") is not None else ""
    largest = f", largest {f['largest_piece_vertices']} vertices" if f.get("largest_piece_vertices") else ""
    return (f"collision {name}/{entry['source']}: {entry['strategy']}, {f['pieces']} piece"
            f"{'s' * (f['pieces'] != 1)}{largest}, {ratio}{far}")
