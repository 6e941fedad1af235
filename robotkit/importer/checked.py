"""An imported recipe checked before it is written and after (the MJCF and SDF imports): valid
against the schema, then loaded and resolved as the build will; every problem names the original."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from pydantic import ValidationError

from robotkit.errors import Problem, RobotkitError
from robotkit.model.load import load_robots
from robotkit.recipe.schema import Recipe


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
