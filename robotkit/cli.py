"""The robotkit command line.  Each command loads its input, calls one function,
and maps a RobotkitError to one line per problem and exit status 2.

Heavy libraries (trimesh, numpy, pydantic, doit, jinja2) are imported inside
the commands, so ``robotkit --help`` and argument errors stay instant.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # usage errors: exit 2 with one line, like every bad input
        self.print_usage(sys.stderr)
        print(f"robotkit: error: {message}", file=sys.stderr)
        raise SystemExit(2)


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="robotkit", description="Declarative build system for robot description assets.")
    p.add_argument("--version", action="store_true", help="print the version and exit")
    sub = p.add_subparsers(dest="command", parser_class=_Parser)

    _add_build(sub)

    w = sub.add_parser("world", help="turn a ROS map_server occupancy map into a Gazebo world and MuJoCo scene",
                       description="Write OUT/<name>/ with model.config, model.sdf, meshes/<name>.stl, "
                                   "<name>.world and scene.xml.")
    w.add_argument("map", metavar="MAP.yaml", help="map_server YAML file")
    w.add_argument("--out", "-o", default="build", metavar="DIR", help="output folder (default: build)")
    w.add_argument("--name", help="world name (default: the YAML file's stem)")
    w.add_argument("--height", type=float, default=2.0, metavar="H", help="wall height in metres (default: 2.0)")
    w.add_argument("--unknown-as-wall", action="store_true", help="treat unknown cells as walls")
    _add_root_option(w)

    k = sub.add_parser("catalogue", help="turn a folder of object meshes into simulation-ready objects",
                       description="Build every STL/OBJ/DAE mesh below DIR (or listed in a text file, one path "
                                   "a line) into OUT/<object>/ (URDF, SDF, MJCF, collision decomposition, mass "
                                   "properties) and write OUT/catalogue.json and OUT/catalogue.csv. A bad mesh is "
                                   "reported and skipped; a rerun builds only what is missing or changed. Exit 0 "
                                   "when every object was made, 1 when some failed, 2 for bad input.")
    k.add_argument("source", metavar="DIR", help="folder of meshes (searched recursively) or a list file")
    k.add_argument("--out", "-o", default="build", metavar="DIR", help="output folder (default: build)")
    k.add_argument("--density", type=float, default=1000.0, metavar="KG_M3",
                   help="density for objects without a mass in the table (default: 1000)")
    k.add_argument("--masses", metavar="CSV", help="table with columns name (object name or relative path), "
                                                   "mass (kg) and optionally units (m, cm, mm, in)")
    k.add_argument("--units", choices=["m", "cm", "mm", "in"],
                   help="units of every mesh (default: guessed from each mesh's size and reported)")
    k.add_argument("--collision", choices=["decompose", "hull", "box", "cylinder", "sphere", "capsule", "none"],
                   default="decompose", help="collision geometry (default: decompose, CoACD)")
    k.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                   help="parallel processes (default: the cores; with --scheduler, the cluster's threads)")
    k.add_argument("--scheduler", metavar="ADDRESS",
                   help="send the mesh work to this Dask scheduler (default: $DASK_SCHEDULER_ADDRESS); "
                        "'local' starts one worker per core")

    c = sub.add_parser("check", help="validate recipes, build folders, or URDF/SDF/MJCF files",
                       description="Run the validators, the URDF/SDF/MJCF equivalence check and a MuJoCo "
                                   "smoke test. Exit 0 when clean, 1 when problems are found, 2 for bad input "
                                   "(reported in every format too).")
    c.add_argument("paths", nargs="+", metavar="PATH",
                   help="recipe .yaml, build folder, or .urdf/.xacro/.sdf/.xml file")
    c.add_argument("--format", choices=["text", "json", "junit", "github"], default="text",
                   help="report format: text for people, json, junit (CI test reporters), github (annotations)")
    c.add_argument("--package-path", action="append", default=[], metavar="PKG=DIR",
                   help="folder of ROS package PKG: package://PKG/ meshes of a URDF, $(find PKG) in a xacro "
                        "file (repeatable)")
    c.add_argument("--fail-on", choices=["error", "warning"], default="error",
                   help="lowest severity that makes the exit status 1 (default: error)")
    c.add_argument("--junit", metavar="FILE", help="also write the JUnit report to FILE (whatever --format says)")
    out = c.add_mutually_exclusive_group()
    out.add_argument("--out", "-o", default="build", metavar="DIR", help="where a recipe is built (default: build)")
    out.add_argument("--temp-out", action="store_true",
                     help="build recipes in a temporary folder, removed afterwards (pre-commit: never the user's tree)")
    _add_arg_option(c)
    _add_root_option(c)

    e = sub.add_parser("expand", help="print the flat recipe that a recipe's arguments, expressions, units, "
                                      "parts, conditions and variants expand to",
                       description="Print RECIPE expanded (one YAML document per variant).")
    e.add_argument("recipe", metavar="RECIPE", help="recipe YAML file")
    e.add_argument("--variant", metavar="NAME", help="print only this variant")
    _add_arg_option(e)
    _add_root_option(e)

    from robotkit.importer.cli import add_parser as add_import

    add_import(sub)

    r = sub.add_parser("report", help="write a picture report (report.html and its pictures) of a robot",
                       description="Render the robot offscreen (sides, collision, inertia boxes, frames, "
                                   "joints at their limits) and write DIR/report.html with the pictures "
                                   "beside it and a table per link and joint.")
    r.add_argument("path", metavar="PATH", help="recipe .yaml, build folder, or .urdf/.sdf/.xml file")
    r.add_argument("-o", "--output", metavar="DIR",
                   help="folder for report.html and its pictures (default: <build folder>/report)")
    r.add_argument("--out", default="build", metavar="DIR", help="where a recipe is built (default: build)")
    _add_root_option(r)
    r.add_argument("--package-path", action="append", default=[], metavar="PKG=DIR",
                   help="folder of ROS package PKG: package://PKG/ meshes of a URDF, $(find PKG) in a xacro "
                        "file (repeatable)")

    v = sub.add_parser("view", help="show the robot in the browser, rebuilt live as its recipe changes",
                       description="Serve a 3D view of the robot (joint sliders, visual/collision/inertia/"
                                   "frame toggles); a recipe is rebuilt on every save.")
    v.add_argument("path", metavar="PATH", help="recipe .yaml, build folder, or .urdf file")
    v.add_argument("--port", type=int, default=8080, metavar="N", help="port to serve on (default: 8080)")
    v.add_argument("--no-browser", action="store_true", help="do not open a web browser")
    v.add_argument("--out", default="build", metavar="DIR", help="where a recipe is built (default: build)")
    _add_root_option(v)

    n = sub.add_parser("new", help="write a starter recipe (a link, a joint and a mesh) that builds as written",
                       description="Write NAME.yaml, meshes/NAME/arm.stl and recipe.schema.json (for the editor "
                                   "modeline) into DIR; no existing file is overwritten.")
    n.add_argument("name", metavar="NAME", help="the robot's name (letters, digits, '_', '.', '-')")
    n.add_argument("--dir", "-C", default=".", metavar="DIR", help="folder to write into (default: .)")

    s = sub.add_parser("schema", help="print the recipe JSON Schema (for editors)")
    s.add_argument("--markdown", action="store_true", help="print the recipe reference as Markdown instead")
    s.add_argument("--part", action="store_true", help="print the JSON Schema of a part file instead")
    return p


def _recipe_arg(text: str) -> tuple[str, str]:
    name, sep, value = text.partition(":=")
    if not sep or not name:
        raise argparse.ArgumentTypeError(f"'{text}' is not NAME:=VALUE")
    return name, value


def _add_arg_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--arg", action="append", type=_recipe_arg, default=[], metavar="NAME:=VALUE",
                   help="set a recipe argument (repeatable; see the recipe's args:)")


ROOT_ENV = "ROBOTKIT_ROOT"  # robotkit.paths.ROOT_ENV, not imported: the no-op build stays light


def _add_root_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--root", action="append", default=[], metavar="DIR",
                   help="also read files below DIR (repeatable; default: only the recipe's repository and "
                        "ROBOTKIT_ROOT)")


def _widen_roots(roots: list[str]) -> None:
    """``--root DIR``: widen the reads on purpose (robotkit.paths), also for worker processes."""
    if roots:
        old = [p for p in os.environ.get(ROOT_ENV, "").split(os.pathsep) if p]
        os.environ[ROOT_ENV] = os.pathsep.join(dict.fromkeys([os.path.abspath(r) for r in roots] + old))


def _add_build(sub) -> None:
    b = sub.add_parser("build", help="build recipes into URDF, Gazebo model folders and meshes",
                       description="Build each RECIPE into OUT/<robot>/ (incremental: only what changed reruns).")
    b.add_argument("recipes", nargs="+", metavar="RECIPE", help="recipe YAML file(s)")
    b.add_argument("--out", "-o", default="build", metavar="DIR", help="output folder (default: build)")
    b.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                   help=f"run N tasks in parallel processes (default: the {_cores()} cores this process may use; "
                        "with --scheduler, the cluster's threads)")
    b.add_argument("--scheduler", metavar="ADDRESS",
                   help="send the expensive mesh work (CoACD, hulls, decimation) to this Dask scheduler "
                        "(default: $DASK_SCHEDULER_ADDRESS); 'local' starts one worker per core")
    b.add_argument("-v", "--verbose", action="store_true", help="name every task that runs")
    b.add_argument("--ros", choices=["ros1", "ros2"], help="build the ROS package for this ROS (overrides the "
                                                           "recipes' `ros` key)")
    b.add_argument("--no-report", action="store_true",
                   help="do not write the picture report (<robot>/report/report.html)")
    _add_arg_option(b)
    _add_root_option(b)


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0)) or 1
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _build_parser() -> argparse.ArgumentParser:
    """Only ``build``: a no-op build does not import the other commands' modules."""
    p = _Parser(prog="robotkit", description="Declarative build system for robot description assets.")
    p.add_argument("--version", action="store_true", help="print the version and exit")
    _add_build(p.add_subparsers(dest="command", parser_class=_Parser))
    return p


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = (_build_parser() if argv[:1] == ["build"] else _parser()).parse_args(argv)
    if args.version:
        from robotkit import __version__

        print(f"robotkit {__version__}")
        return 0
    if args.command is None:
        _parser().print_help()
        return 2
    _widen_roots(getattr(args, "root", []))
    try:
        return {"build": _build, "world": _world, "schema": _schema, "check": _check,
                "import": _import, "report": _report, "catalogue": _catalogue, "view": _view, "expand": _expand,
                "new": _new}[args.command](args)
    except Exception as exc:
        from robotkit.errors import RobotkitError  # imported late: dataclasses costs a no-op build 10 ms

        if not isinstance(exc, RobotkitError):
            raise
        for line in exc.lines():
            print(line, file=sys.stderr)
        return exc.exit_status
    except KeyboardInterrupt:
        print("robotkit: interrupted", file=sys.stderr)
        return 130


def _build(args) -> int:
    from robotkit import stamp

    if args.jobs is not None and args.jobs < 1:
        print("robotkit: error: -j must be at least 1", file=sys.stderr)
        return 2
    start = time.perf_counter()
    extra = {**({"ros": args.ros} if args.ros else {}), **({"no_report": True} if args.no_report else {}),
             **({"args": dict(args.arg)} if args.arg else {})}
    opts = stamp.options(args.recipes, args.out, extra or None)
    done = stamp.up_to_date(args.out, opts)  # nothing changed since the last successful build?
    if done is not None:
        return _report_up_to_date(args, done, start)
    from robotkit.build import build

    echo = (lambda line: print(line, file=sys.stderr)) if args.verbose else None
    with _scheduler(args) as jobs, _cache_report():
        result = build(args.recipes, args.out, jobs=jobs, echo=echo, progress=sys.stderr, ros=args.ros,
                       report=not args.no_report, stamp_options=opts, args=dict(args.arg))
    if result.ran or args.verbose:
        for w in result.warning_lines:
            print(w, file=sys.stderr)  # file:line: key: warning: ...
    elif result.warning_lines:  # unchanged since they were shown; keep a no-op build quiet
        print(f"{len(result.warning_lines)} warnings, unchanged since the last build (-v shows them; "
              "report.json lists what each format could not express)", file=sys.stderr)
    if result.errors:
        for name, msg in result.errors:
            print(f"robotkit: internal error in task {name}:\n{msg}", file=sys.stderr)
        return 1
    if result.ran:
        _collision_summary(args.out, result.robots)
    elapsed = time.perf_counter() - start
    out = os.path.relpath(os.path.abspath(args.out))
    names = ", ".join(f"{out}/{r}" for r in result.robots)
    if result.ran:
        print(f"built {names}: {len(result.ran)} tasks run, {len(result.uptodate)} up to date ({elapsed:.2f} s)")
    else:
        print(f"{names}: up to date ({len(result.uptodate)} tasks, {elapsed:.2f} s)")
    return 0


@contextlib.contextmanager
def _cache_report():
    """A shared cache that failed in any task process is told once, after the build (task
    output is captured by doit)."""
    if "://" not in os.environ.get("ROBOTKIT_CACHE", ""):
        yield
        return
    import tempfile

    from robotkit.mesh.cache import REPORT_ENV

    fd, path = tempfile.mkstemp(prefix="robotkit-cache-", suffix=".log")
    os.close(fd)
    old = os.environ.get(REPORT_ENV)
    os.environ[REPORT_ENV] = path
    try:
        yield
    finally:
        if old is None:
            os.environ.pop(REPORT_ENV, None)
        else:
            os.environ[REPORT_ENV] = old
        try:
            with open(path, encoding="utf-8") as f:
                lines = [line.rstrip("\n") for line in f if line.strip()]
            os.unlink(path)
        except OSError:
            lines = []
        if lines:
            print(lines[0], file=sys.stderr)


@contextlib.contextmanager
def _scheduler(args):
    """The number of doit jobs, with the Dask scheduler (``--scheduler``, ``local`` or
    $DASK_SCHEDULER_ADDRESS) exported to the task processes (robotkit.distributed)."""
    from robotkit import distributed

    address = args.scheduler or os.environ.get(distributed.DASK_ENV)
    if not address:
        yield args.jobs or _cores()
        return
    old = os.environ.get(distributed.ENV)
    with (distributed.LocalCluster() if address == "local" else contextlib.nullcontext()) as cluster:
        address = cluster.address if cluster is not None else address
        # every doit process waits on the cluster: as many as it has threads
        jobs = args.jobs or min(64, cluster.workers if cluster is not None else distributed.cluster_threads(address))
        os.environ[distributed.ENV] = address
        try:
            yield jobs
        finally:
            if old is None:
                os.environ.pop(distributed.ENV, None)
            else:
                os.environ[distributed.ENV] = old


def _catalogue(args) -> int:
    if args.jobs is not None and args.jobs < 1:
        print("robotkit: error: -j must be at least 1", file=sys.stderr)
        return 2
    from robotkit.catalogue import catalogue

    start = time.perf_counter()
    with _scheduler(args) as jobs, _cache_report():
        made = catalogue(args.source, args.out, density=args.density, units=args.units, masses=args.masses,
                         collision=args.collision, jobs=jobs)
    index = made.index
    for obj in index["objects"]:
        if obj["status"] != "ok":
            for line in obj["errors"] or ["failed"]:
                print(f"{obj['source']}: {line}", file=sys.stderr)
    guessed = sum(o["units_from"] == "guessed" for o in index["objects"])
    out = os.path.relpath(os.path.abspath(args.out))
    print(f"catalogue {out}: {index['ok']} objects made, {index['failed']} failed"
          f"{f', units guessed for {guessed}' if guessed else ''} ({out}/catalogue.json; "
          f"{len(made.ran)} tasks run, {len(made.uptodate)} up to date, {time.perf_counter() - start:.1f} s)")
    return 1 if index["failed"] else 0


def _report_up_to_date(args, done: dict, start: float) -> int:
    """What a build that runs no task prints, from the stamp (:mod:`robotkit.stamp`)."""
    warnings = done.get("warnings", [])
    if args.verbose:
        for w in warnings:
            print(w, file=sys.stderr)  # file:line: key: warning: ...
    elif warnings:
        print(f"{len(warnings)} warnings, unchanged since the last build (-v shows them; "
              "report.json lists what each format could not express)", file=sys.stderr)
    out = os.path.relpath(os.path.abspath(args.out))
    names = ", ".join(f"{out}/{r}" for r in done["robots"])
    print(f"{names}: up to date ({done['tasks']} tasks, {time.perf_counter() - start:.2f} s)")
    return 0


def _collision_summary(out: str, robots: list[str]) -> None:
    """One line per collision proxy: strategy, pieces, volume against the visual, distance."""
    import json

    for name in robots:
        try:
            report = json.loads(open(os.path.join(out, name, "report.json"), encoding="utf-8").read())
        except (OSError, ValueError):
            continue
        for entry in report.get("collision", {}).values():
            f = entry["fidelity"]
            ratio = f"{f['volume_ratio']:.3g}x the visual volume" if f.get("volume_ratio") else "visual not closed"
            dist = f.get("distance") or {}
            far = f", surface within {dist['max'] * 1000:.3g} mm" if dist.get("max") is not None else ""
            largest = f", largest {f['largest_piece_vertices']} vertices" if f.get("largest_piece_vertices") else ""
            print(f"collision {name}/{entry['source']}: {entry['strategy']}, {f['pieces']} piece"
                  f"{'s' * (f['pieces'] != 1)}{largest}, {ratio}{far}", file=sys.stderr)


def _world(args) -> int:
    from robotkit.world import build_world

    if not args.height > 0:
        print("robotkit: error: --height must be > 0", file=sys.stderr)
        return 2
    paths = build_world(args.map, args.out, name=args.name, height=args.height,
                        unknown_as_wall=args.unknown_as_wall)
    for p in paths:
        print(os.path.relpath(p))
    return 0


def _check(args) -> int:
    packages = _package_paths(args.package_path)
    if packages is None:
        return 2
    if args.temp_out:
        import tempfile

        with tempfile.TemporaryDirectory(prefix="robotkit-check-") as out:
            args.out = out
            return _check_paths(args, packages)
    return _check_paths(args, packages)


def _check_paths(args, packages: dict[str, str]) -> int:
    """Every PATH in turn; bad input (exit 2) is reported in the chosen format too, so a CI
    report never comes out empty, and its lines go to stderr as always."""
    from robotkit.check import cases, check, render
    from robotkit.check.findings import input_findings
    from robotkit.errors import RobotkitError

    findings, status, ran = [], 0, []
    for path in args.paths:
        try:  # github: the job summary points at the picture report, so a recipe's build writes it
            findings += check(path, args.out, packages, args=dict(args.arg),
                              report=args.format == "github" and not args.temp_out)
            ran += cases(path, args.out, dict(args.arg))
        except RobotkitError as exc:
            for line in exc.lines():
                print(line, file=sys.stderr)
            findings += input_findings(exc.problems, path)
            status = max(status, exc.exit_status)
    source = " ".join(args.paths)
    if args.format != "text" or not status:
        sys.stdout.write(render(findings, args.format, source, args.fail_on, ran))
    elif any(f.check != "input" for f in findings):  # the paths that could be checked
        sys.stdout.write(render([f for f in findings if f.check != "input"], "text", source, args.fail_on))
    if args.junit:
        from pathlib import Path

        Path(args.junit).parent.mkdir(parents=True, exist_ok=True)
        Path(args.junit).write_text(render(findings, "junit", source, args.fail_on, ran), encoding="utf-8")
    if args.format == "github" and os.environ.get("GITHUB_STEP_SUMMARY"):
        # a temporary build folder is gone when the summary is read: no report to point at
        _job_summary(os.environ["GITHUB_STEP_SUMMARY"], findings, args.paths, None if args.temp_out else args.out)
    return status or (1 if any(f.fails(args.fail_on) for f in findings) else 0)


def _package_paths(items: list[str]) -> dict[str, str] | None:
    packages = {}
    for item in items:
        pkg, sep, folder = item.partition("=")
        if not sep or not pkg or not folder:
            print(f"robotkit: error: --package-path takes PKG=DIR (got '{item}')", file=sys.stderr)
            return None
        packages[pkg] = folder
    return packages


def _report(args) -> int:
    from robotkit.picture import write_report

    packages = _package_paths(args.package_path)
    if packages is None:
        return 2
    start = time.perf_counter()
    page = write_report(args.path, args.output, args.out, packages)
    print(f"wrote {os.path.relpath(page)} ({time.perf_counter() - start:.2f} s)")
    return 0


def _view(args) -> int:
    from robotkit.picture.viewer import serve

    return serve(args.path, args.port, open_browser=not args.no_browser, build_out=args.out)


def _job_summary(summary_file: str, findings, paths: list[str], out: str | None) -> None:
    """Append the check's summary, pointing at the picture report, to GitHub's job summary."""
    from pathlib import Path

    from robotkit.check.report import job_summary
    from robotkit.errors import RobotkitError
    from robotkit.tasks import REPORT

    folders = []
    for path in map(Path, paths):
        if path.suffix.lower() in (".yaml", ".yml") and out is not None:
            from robotkit.recipe.load import load_recipe

            try:
                folders.append(Path(out) / load_recipe(path).recipe.robot)
            except RobotkitError:
                pass  # a recipe that does not load has no report; its findings say why
        elif path.is_dir():
            folders += [path] if (path / "model.sdf").is_file() else sorted(
                d for d in path.iterdir() if (d / "model.sdf").is_file())
    pages = [os.path.relpath(f / REPORT) for f in folders if (f / REPORT).is_file()]
    with open(summary_file, "a", encoding="utf-8") as f:
        f.write(job_summary(findings, " ".join(paths), pages))


def _import(args) -> int:
    from robotkit.importer.cli import run

    return run(args)


def _expand(args) -> int:
    from robotkit.recipe.flat import flat_yaml

    sys.stdout.write(flat_yaml(args.recipe, dict(args.arg), args.variant))
    return 0


def _new(args) -> int:
    from robotkit.starter import new

    for path in new(args.name, args.dir):
        print(os.path.relpath(path))
    print(f"build it: robotkit build {os.path.relpath(os.path.join(args.dir, args.name + '.yaml'))}")
    return 0


def _schema(args) -> int:
    from robotkit.recipe.reference import json_schema, markdown

    print(markdown() if args.markdown else json_schema(part=args.part), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
