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
    items = getattr(args, "package_path", None) or []
    packages = dict(items) if items and not isinstance(items[0], str) else package_paths(items)
    if packages is None:
        return 2
    options = {"variant": getattr(args, "variant", None), "args": dict(getattr(args, "arg", None) or []),
               "packages": packages}
    kind, make = resolve(Path(args.path), getattr(args, "out", None) or "build", **options)
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
    """Raise (one line, exit 2) when the recipe has no variant ``variant``."""
    loaded = read_recipes(recipe, args)
    names = [one.variant for one in loaded if one.variant is not None]
    if variant not in names and not any(one.problems for one in loaded):  # a broken recipe: the page says why
        raise RobotkitError(Problem(f"no variant named '{variant}' (variants: {', '.join(names) or 'none'})",
                                    file=str(recipe), key="--variant"))


def _build_recipe(recipe: Path, build_out: str, variant: str | None, args: dict[str, str]) -> list[Built]:
    """Build the recipe (every variant) and watch every file it reads; the robots to show: every
    variant, or the one named."""
    watch = [recipe]
    try:
        robots = load_robots([recipe], args=args)
        watch = sorted({Path(f) for loaded, _ in robots for f in loaded.files}
                       | {Path(m.source) for _, robot in robots for m in robot.meshes().values()})
        result = build([recipe], build_out, report=False, args=args)
        if result.errors:  # a bug in a task: shown like a user error, the viewer stays up
            raise RobotkitError([Problem(f"internal error in task {name}: {msg}") for name, msg in result.errors])
    except RobotkitError as exc:
        exc.watch = watch  # still watched: fixing the recipe or a mesh rebuilds
        raise
    shown = []
    for loaded, robot in robots:
        if variant is None or loaded.variant == variant:
            layout = robot_layout(Path(build_out) / robot.name)
            shown.append(Built(layout.urdf, {robot.name: str(layout.root)}, watch, robot.name))
    if not shown:  # the variant was renamed while viewing
        exc = RobotkitError(Problem(f"no variant named '{variant}'", file=str(recipe), key="--variant"))
        exc.watch = watch
        raise exc
    return shown
