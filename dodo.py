"""`doit` in the repository root builds every recipe in recipes/ into build/.

The tasks are the same ones `robotkit build recipes/*.yaml` runs (robotkit.pipeline.tasks),
with the same dependency database (build/.robotkit/doit.sqlite3), so the two
commands share one incremental state.

Recipe arguments: ``doit args='NAME:=VALUE NAME2:=VALUE2'`` (doit's command-line
variables); each recipe takes the ones it declares, and a name no recipe declares
is an error.
"""

import sys
from pathlib import Path

from doit import get_var

from robotkit.pipeline.runner import doit_config, to_doit
from robotkit.errors import RobotkitError
from robotkit.pipeline.tasks import all_tasks

ROOT = Path(__file__).resolve().parent
OUT = ROOT / "build"
RECIPES = sorted(str(p) for p in (ROOT / "recipes").glob("*.yaml"))

DOIT_CONFIG = {k: v for k, v in doit_config(OUT).items() if k != "continue"}
DOIT_CONFIG["verbosity"] = 1
(OUT / ".robotkit").mkdir(parents=True, exist_ok=True)


def recipe_args(text: str) -> dict[str, str]:
    """``NAME:=VALUE NAME2:=VALUE2`` -> {name: value}."""
    out = {}
    for item in text.split():
        name, sep, value = item.partition(":=")
        if not sep or not name:
            print(f"robotkit: error: args: '{item}' is not NAME:=VALUE", file=sys.stderr)
            raise SystemExit(2)
        out[name] = value
    return out


def task_robots():
    """Build every recipe in recipes/."""
    try:
        tasks = all_tasks(RECIPES, OUT, args=recipe_args(get_var("args", "")), ignore_unknown_args=True)
    except RobotkitError as exc:
        for line in exc.lines():
            print(line, file=sys.stderr)
        raise SystemExit(2)
    for task in tasks:
        yield to_doit(task)
