"""``robotkit view PATH``: what PATH is, how to (re)build what the viewer shows, and the viewer
itself (:mod:`robotkit.picture.viewer`).

A recipe with variants shows every variant (a selector in the page switches robots), or the
one ``--variant NAME`` names; ``--arg NAME:=VALUE`` sets its arguments."""

from __future__ import annotations

from functools import partial
from pathlib import Path

from robotkit.commands.inputs import classify, package_paths
from robotkit.emit.layout import robot_layout
from robotkit.errors import Problem, RobotkitError
from robotkit.model.load import load_robots
from robotkit.picture.viewer import Built, serve
from robotkit.pipeline.runner import build
from robotkit.recipe.load import read_recipes


def run(args) -> int:
    packages = package_paths(args.package_path)
    if packages is None:
        return 2
    options = {"variant": args.variant, "args": dict(args.arg), "packages": packages}
    kind, make = resolve(Path(args.path), args.out, **options)
    return serve(args.path, kind, make, args.port, open_browser=not args.no_browser)


def resolve(path: Path, build_out: str, variant: str | None = None, args: dict[str, str] | None = None,
            packages: dict[str, str] | None = None) -> tuple[str, callable]:
    """(kind, make) for PATH: ``make()`` (re)builds if needed and returns the robots to show, a
    :class:`Built` each (a recipe's variants, or the one ``variant`` names)."""
    what = classify(path, ("recipe", "build", "urdf"), "a recipe .yaml, a build folder or a .urdf")
    packages = dict(packages or {})
    if what.kind == "build":
        robot = what.one_robot()
        return "build", lambda: [Built(robot.urdf, {**packages, robot.name: str(robot.root)}, [robot.urdf],
                                       robot.name)]
    if what.kind == "recipe":
        if variant is not None:
            check_variant(path, variant, args)
        return "recipe", partial(_build_recipe, path, build_out, variant, dict(args or {}))
    return "urdf", lambda: [Built(path, packages, [path])]


def check_variant(recipe: Path, variant: str, args: dict[str, str] | None) -> None:
    """Raise (one line, exit 2) when the recipe has no variant ``variant`` (a recipe that does
    not load otherwise opens: the page says why)."""
    problems = read_recipes(recipe, args, variant=variant)[0].problems
    if problems and problems[0].key == "--variant" and problems[0].message.startswith("no variant named"):
        raise RobotkitError(problems[0])


def _build_recipe(recipe: Path, build_out: str, variant: str | None, args: dict[str, str]) -> list[Built]:
    """Build the recipe (every variant, or the one named) and watch every file it reads."""
    watch = [recipe]
    try:
        robots = load_robots([recipe], args=args, variant=variant)
        watch = sorted({Path(f) for loaded, _ in robots for f in loaded.files}
                       | {Path(m.source) for _, robot in robots for m in robot.meshes().values()})
        result = build([recipe], build_out, report=False, args=args, variant=variant)
        if result.errors:  # a bug in a task: shown like a user error, the viewer stays up
            raise RobotkitError([Problem(f"internal error in task {name}: {msg}") for name, msg in result.errors])
    except RobotkitError as exc:
        exc.watch = watch  # still watched: fixing the recipe or a mesh rebuilds
        raise
    layouts = [robot_layout(Path(build_out) / robot.name) for _, robot in robots]
    return [Built(layout.urdf, {layout.name: str(layout.root)}, watch, layout.name) for layout in layouts]
