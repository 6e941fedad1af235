"""The robotkit command line.  Each command loads its input, calls one function,
and maps a RobotkitError to one line per problem and exit status 2.

Heavy libraries (trimesh, numpy, pydantic, doit, jinja2) are imported inside
the commands, so ``robotkit --help`` and argument errors stay instant.
"""

from __future__ import annotations

import argparse
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

    c = sub.add_parser("check", help="validate a recipe, a build folder, or a URDF/SDF/MJCF file",
                       description="Run the validators, the URDF/SDF/MJCF equivalence check and a MuJoCo "
                                   "smoke test. Exit 0 when clean, 1 when problems are found, 2 for bad input.")
    c.add_argument("path", metavar="PATH", help="recipe .yaml, build folder, or .urdf/.sdf/.xml file")
    c.add_argument("--format", choices=["text", "json", "junit", "github"], default="text",
                   help="report format: text for people, json, junit (CI test reporters), github (annotations)")
    c.add_argument("--package-path", action="append", default=[], metavar="PKG=DIR",
                   help="where package://PKG/ meshes of a URDF are (repeatable)")
    c.add_argument("--fail-on", choices=["error", "warning"], default="error",
                   help="lowest severity that makes the exit status 1 (default: error)")
    c.add_argument("--out", "-o", default="build", metavar="DIR", help="where a recipe is built (default: build)")
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
                   help="where package://PKG/ meshes of a URDF are (repeatable)")

    v = sub.add_parser("view", help="show the robot in the browser, rebuilt live as its recipe changes",
                       description="Serve a 3D view of the robot (joint sliders, visual/collision/inertia/"
                                   "frame toggles); a recipe is rebuilt on every save.")
    v.add_argument("path", metavar="PATH", help="recipe .yaml, build folder, or .urdf file")
    v.add_argument("--port", type=int, default=8080, metavar="N", help="port to serve on (default: 8080)")
    v.add_argument("--no-browser", action="store_true", help="do not open a web browser")
    v.add_argument("--out", default="build", metavar="DIR", help="where a recipe is built (default: build)")
    _add_root_option(v)

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
    b.add_argument("-j", "--jobs", type=int, default=_cores(), metavar="N",
                   help=f"run N tasks in parallel processes (default: the {_cores()} cores this process may use)")
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
                "import": _import, "report": _report, "view": _view, "expand": _expand}[args.command](args)
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

    if args.jobs < 1:
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
    result = build(args.recipes, args.out, jobs=args.jobs, echo=echo, progress=sys.stderr, ros=args.ros,
                   report=not args.no_report, stamp_options=opts, args=dict(args.arg))
    if result.ran or args.verbose:
        for w in result.warnings:
            print(f"warning: {w}", file=sys.stderr)
    elif result.warnings:  # unchanged since they were shown; keep a no-op build quiet
        print(f"{len(result.warnings)} warnings, unchanged since the last build (-v shows them; "
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


def _report_up_to_date(args, done: dict, start: float) -> int:
    """What a build that runs no task prints, from the stamp (:mod:`robotkit.stamp`)."""
    warnings = done.get("warnings", [])
    if args.verbose:
        for w in warnings:
            print(f"warning: {w}", file=sys.stderr)
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
    from robotkit.check import check, render

    packages = {}
    for item in args.package_path:
        pkg, sep, folder = item.partition("=")
        if not sep or not pkg or not folder:
            print(f"robotkit: error: --package-path takes PKG=DIR (got '{item}')", file=sys.stderr)
            return 2
        packages[pkg] = folder
    # github: the job summary points at the picture report, so a recipe's build writes it
    findings = check(args.path, args.out, packages, args=dict(args.arg), report=args.format == "github")
    sys.stdout.write(render(findings, args.format, args.path))
    if args.format == "github" and os.environ.get("GITHUB_STEP_SUMMARY"):
        _job_summary(os.environ["GITHUB_STEP_SUMMARY"], findings, args.path, args.out)
    levels = ("error",) if args.fail_on == "error" else ("error", "warning")
    return 1 if any(f.severity in levels for f in findings) else 0


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


def _job_summary(summary_file: str, findings, path: str, out: str) -> None:
    """Append the check's summary, pointing at the picture report, to GitHub's job summary."""
    from pathlib import Path

    from robotkit.check.report import job_summary
    from robotkit.tasks import REPORT

    p = Path(path)
    if p.suffix.lower() in (".yaml", ".yml"):
        from robotkit.recipe.load import load_recipe

        folders = [Path(out) / load_recipe(p).recipe.robot]
    elif p.is_dir():
        folders = [p] if (p / "model.sdf").is_file() else sorted(d for d in p.iterdir() if (d / "model.sdf").is_file())
    else:
        folders = []
    pages = [os.path.relpath(f / REPORT) for f in folders if (f / REPORT).is_file()]
    with open(summary_file, "a", encoding="utf-8") as f:
        f.write(job_summary(findings, path, pages))


def _import(args) -> int:
    from robotkit.importer.cli import run

    return run(args)


def _expand(args) -> int:
    from robotkit.recipe.flat import flat_yaml

    sys.stdout.write(flat_yaml(args.recipe, dict(args.arg), args.variant))
    return 0


def _schema(args) -> int:
    from robotkit.recipe.reference import json_schema, markdown

    print(markdown() if args.markdown else json_schema(part=args.part), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
