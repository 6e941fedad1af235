"""Recipes to resolved robots: every recipe file (every variant of each) loaded, resolved and
checked for output folders that two robots would write, all problems together; and where in the
recipe each mesh and link is written (for the messages of the mesh tasks)."""

from __future__ import annotations

from robotkit.errors import Problem, RobotkitError, display_path
from robotkit.model.resolve import resolve_checked
from robotkit.model.robot import Robot
from robotkit.recipe.load import read_recipes


def mesh_locations(loaded, robot: Robot) -> dict[str, dict]:
    """Recipe location (file, line, key) of the first geometry naming each mesh key, and of
    each link (``link:<name>``)."""
    marks = loaded.marks
    where_source: dict[tuple[str, str], dict] = {}  # (link, source file) -> location
    for name, link in loaded.recipe.links.items():
        places = [("visual",), ("collision",)]
        if hasattr(link.collision, "strategy"):
            places = [("visual",), ("collision", "source")]
        for place in places:
            value = link.visual if place == ("visual",) else (
                link.collision.source if len(place) == 2 else link.collision)
            if value is None or isinstance(value, str):
                continue
            items = [((i,), g) for i, g in enumerate(value)] if isinstance(value, list) else [((), value)]
            for idx, g in items:
                if g.mesh is not None and (name, g.mesh) not in where_source:
                    p = marks.problem(("links", name) + place + idx + ("mesh",), "")
                    where_source[(name, g.mesh)] = {"file": p.file, "line": p.line, "key": p.key}
    out: dict[str, dict] = {}
    for link in robot.links:
        if link.name in loaded.recipe.links:
            p = marks.problem(("links", link.name), "")
            out[f"link:{link.name}"] = {"file": p.file, "line": p.line, "key": p.key}
        for geom in robot.all_geoms(link):
            m = geom.shape.mesh
            if m is not None and m.key not in out and (link.name, m.source) in where_source:
                out[m.key] = where_source[(link.name, m.source)]
    return out


def load_robots(recipe_files, ros: str | None = None, args: dict[str, str] | None = None,
                ignore_unknown_args: bool = False, moveit: bool = False,
                variant: str | None = None) -> list[tuple[object, Robot]]:
    """Load and resolve every recipe (every variant of each, or only ``variant``; ``ros`` overrides
    their ``ros`` key, ``moveit`` turns their ``moveit`` key on); all problems of all recipes together.

    ``args``: ``--arg`` overrides (name -> text); with ``ignore_unknown_args`` a recipe ignores the
    ones it does not declare (doit builds many recipes with one set of arguments)."""
    problems: list[Problem] = []
    robots = []
    names: dict[str, str] = {}
    declared: set[str] = set()
    for f in recipe_files:
        for loaded in read_recipes(f, args, ignore_unknown_args, variant):
            declared.update(loaded.arg_names)
            try:
                robot = resolve_checked(loaded, ros, moveit)
            except RobotkitError as exc:
                problems.extend(p for p in exc.problems if p not in problems)
                continue
            outputs = [("robot",), *[("worlds", w.name) for w in robot.worlds]]
            taken = [key for key in outputs if key[-1] in names or (key[0] == "worlds" and key[-1] == robot.name)]
            if taken:
                key = taken[0]
                other = names.get(key[-1], display_path(str(f)))
                problems.append(loaded.marks.problem(key, f"output folder '{key[-1]}' is also written by {other}"))
                continue
            names[robot.name] = display_path(str(f))
            names.update({w.name: display_path(str(f)) for w in robot.worlds})
            robots.append((loaded, robot))
    if ignore_unknown_args:
        problems += [Problem(f"unknown argument '{name}': no recipe declares it", key=f"--arg {name}")
                     for name in sorted(set(args or {}) - declared)]
    if problems:
        raise RobotkitError(problems)
    return robots
