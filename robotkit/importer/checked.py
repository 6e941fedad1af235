"""An imported recipe checked before it is written and after (the MJCF and SDF imports): valid
against the schema, then loaded and resolved as the build will; every problem names the original."""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from pathlib import Path

from pydantic import ValidationError

from robotkit.errors import Problem, RobotkitError, display_path
from robotkit.mesh.io import companions
from robotkit.model.load import load_robots
from robotkit.paths import recipe_policy
from robotkit.recipe.schema import Recipe


@dataclass
class Imported:
    """What an MJCF or SDF import wrote and found."""
    recipe_path: Path
    robot: str
    ledger: list[str] = field(default_factory=list)
    verdict: object | None = None
    """The rebuild compared with the original (the importer's ``Verdict``), None without a build."""
    inputs: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    root: str | None = None
    """The folder outside the project a build of the recipe reads (``--root``), if any."""


def validate_recipe(recipe: dict, source: Path) -> None:
    """The recipe ``recipe`` (a dict) against the schema; problems name ``source``, the original."""
    try:
        Recipe.model_validate(recipe)
    except ValidationError as exc:
        problems = [Problem(f"the imported recipe would be invalid: {'.'.join(str(p) for p in err['loc'])}: "
                            f"{err['msg']}", file=str(source)) for err in exc.errors(include_url=False)]
        raise RobotkitError(problems) from None


def resolves(recipe: Path, source: Path) -> None:
    """Load and resolve the written recipe as the build will; its problems name ``source``."""
    try:
        load_robots([recipe])
    except RobotkitError as exc:
        raise RobotkitError([replace(p, file=str(source), line=None) if p.file == str(recipe) else p
                             for p in exc.problems]) from None


def with_companions(meshes) -> list[str]:
    """The files a build of an imported recipe reads: its mesh files, and the textures and
    material files next to them that the build copies (a Gazebo model's ``../materials/textures/``)."""
    meshes = sorted(set(meshes))
    return meshes + [os.path.normpath(os.path.join(os.path.dirname(m), rel)) for m in meshes for rel in companions(m)]


def outside_reads(files, out: Path) -> tuple[list[str], str | None, list[str]]:
    """The folders outside the project of recipe ``out`` that a build reading ``files`` (and
    their companions) reads, the ``--root`` naming them all (or None), and the note saying so."""
    policy = recipe_policy(out)
    read = sorted({os.path.dirname(f) for f in with_companions(files) if not policy.allows(f)})
    root = display_path(os.path.commonpath(read)) if read else None
    notes = [f"the recipe reads files outside its project {display_path(policy.roots[0])}: "
             f"build it with --root {root}"] if read else []
    return read, root, notes

