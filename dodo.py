"""`doit` in the repository root builds every recipe in recipes/ into build/.

The tasks are the same ones `robotkit build recipes/*.yaml` runs (robotkit.tasks),
with the same dependency database (build/.robotkit/doit.sqlite3), so the two
commands share one incremental state.
"""

import sys
from pathlib import Path

from robotkit.build import doit_config, to_doit
from robotkit.errors import RobotkitError
from robotkit.tasks import all_tasks

ROOT = Path(__file__).resolve().parent
OUT = ROOT / "build"
RECIPES = sorted(str(p) for p in (ROOT / "recipes").glob("*.yaml"))

DOIT_CONFIG = {k: v for k, v in doit_config(OUT).items() if k != "continue"}
DOIT_CONFIG["verbosity"] = 1
(OUT / ".robotkit").mkdir(parents=True, exist_ok=True)


def task_robots():
    """Build every recipe in recipes/."""
    try:
        tasks = all_tasks(RECIPES, OUT)
    except RobotkitError as exc:
        for line in exc.lines():
            print(line, file=sys.stderr)
        raise SystemExit(2)
    for task in tasks:
        yield to_doit(task)
