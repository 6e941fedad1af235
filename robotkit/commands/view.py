"""``robotkit view PATH``: what PATH is, how to (re)build what the viewer shows, and the viewer
itself (:mod:`robotkit.picture.viewer`)."""

from __future__ import annotations

from functools import partial
from pathlib import Path

from robotkit.commands.inputs import classify
from robotkit.emit.layout import robot_layout
from robotkit.errors import Problem, RobotkitError
from robotkit.model.load import load_robots
from robotkit.picture.viewer import Built, serve
from robotkit.pipeline.runner import build


def run(args) -> int:
    kind, make = resolve(Path(args.path), args.out)
    return serve(args.path, kind, make, args.port, open_browser=not args.no_browser)


def resolve(path: Path, build_out: str) -> tuple[str, callable]:
    """(kind, make) for PATH: ``make()`` (re)builds if needed and returns a :class:`Built`."""
    what = classify(path, ("recipe", "build", "urdf"), "a recipe .yaml, a build folder or a .urdf")
    if what.kind == "build":
        robot = what.one_robot()
        return "build", lambda: Built(robot.urdf, {robot.name: str(robot.root)}, [robot.urdf])
    if what.kind == "recipe":
        return "recipe", partial(_build_recipe, path, build_out)
    return "urdf", lambda: Built(path, {}, [path])


def _build_recipe(recipe: Path, build_out: str) -> Built:
    """Build the recipe (its first robot: a recipe with variants shows the first) and watch every
    file it reads."""
    watch = [recipe]
    try:
        (loaded, robot), *_ = load_robots([recipe])
        watch = [Path(f) for f in loaded.files] + sorted({Path(m.source) for m in robot.meshes().values()})
        result = build([recipe], build_out, report=False)
        if result.errors:  # a bug in a task: shown like a user error, the viewer stays up
            raise RobotkitError([Problem(f"internal error in task {name}: {msg}") for name, msg in result.errors])
    except RobotkitError as exc:
        exc.watch = watch  # still watched: fixing the recipe or a mesh rebuilds
        raise
    layout = robot_layout(Path(build_out) / robot.name)
    return Built(layout.urdf, {robot.name: str(layout.root)}, watch)
