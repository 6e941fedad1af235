"""Publishing a robot's outputs: all of them or none, and nothing stale.

The build's tasks write into a staging tree (``OUT/.robotkit/stage/``) that doit keeps up to
date incrementally.  Only when every task of a robot succeeded are its folders
(``OUT/<robot>/`` and ``OUT/<world>/`` of its worlds) published: a new folder is made of hard
links to the staged files (a copy where links are impossible) and swapped in with two
renames.  So a failed build leaves the previous complete output (or nothing) and a published
folder holds exactly the files this build produced: files the recipe no longer produces are
gone.  A build killed at any point publishes on its next run.

Standard library only.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

STATE = ".robotkit"
STAGE = "stage"  # OUT/.robotkit/stage/<unit>/...: what the tasks write
SCRATCH = "publish"  # OUT/.robotkit/publish/: folders being swapped in and out
MANIFEST = "published"  # OUT/.robotkit/published/<robot>.json: the folders a robot published


def stage_dir(out_dir: str | os.PathLike) -> Path:
    return Path(out_dir).absolute() / STATE / STAGE


def staged_files(robot_tasks: list[dict], out_dir: str | os.PathLike) -> dict[str, list[str]]:
    """The files a robot's tasks produce below the stage, per published folder (unit):
    their targets, the collision pieces their records list, the picture report's folder."""
    stage = stage_dir(out_dir)
    units: dict[str, set[str]] = {}

    def add(path: Path):
        rel = path.relative_to(stage)
        units.setdefault(rel.parts[0], set()).add(Path(*rel.parts[1:]).as_posix())

    for task in robot_tasks:
        for target in task.get("targets", []):
            p = Path(target)
            if stage in p.parents:
                add(p)
            elif ":collision:" in task["name"] and p.suffix == ".json":  # pieces: below <robot>/meshes/
                for piece in _pieces(p):
                    add(stage / task["name"].split(":")[0] / "meshes" / piece)
        if task["name"].endswith(":report-html"):
            report = Path(task["targets"][0]).parent
            for root, _dirs, names in os.walk(report):
                for n in names:
                    add(Path(root) / n)
    return {u: sorted(files) for u, files in units.items()}


def _pieces(record: Path) -> list[str]:
    try:
        data = json.loads(record.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return []
    return [p["file"] for p in data.get("pieces", []) if p.get("kind") == "mesh" and "file" in p]


def publish(out_dir: str | os.PathLike, robot: str, units: dict[str, list[str]]) -> list[str]:
    """Make ``OUT/<unit>/`` hold exactly the staged ``units`` (unit -> relative file paths);
    remove the folders ``robot`` published before and publishes no more.  Returns every
    published file path."""
    out = Path(out_dir).absolute()
    stage = out / STATE / STAGE
    scratch = out / STATE / SCRATCH
    published = []
    for unit, files in sorted(units.items()):
        _publish_unit(stage / unit, out / unit, files, scratch / unit)
        published += [str(out / unit / f) for f in files]
    manifest = out / STATE / MANIFEST / f"{robot}.json"
    try:
        before = json.loads(manifest.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        before = []
    for unit in before:
        if unit not in units and isinstance(unit, str) and "/" not in unit and unit not in ("", ".", "..", STATE):
            shutil.rmtree(out / unit, ignore_errors=True)
    if sorted(units) != before:
        manifest.parent.mkdir(parents=True, exist_ok=True)
        tmp = manifest.with_suffix(".tmp")
        tmp.write_text(json.dumps(sorted(units)), encoding="utf-8")
        os.replace(tmp, manifest)
    return published


def _current(staged: Path, final: Path, files: list[str]) -> bool:
    """Whether ``final`` already holds exactly ``files``, each the staged file itself."""
    if not final.is_dir() or final.is_symlink():
        return False
    have = sorted(Path(root, n).relative_to(final).as_posix() for root, _d, names in os.walk(final) for n in names)
    if have != files:
        return False
    try:
        return all(os.path.samefile(staged / f, final / f) for f in files)
    except OSError:
        return False


def _publish_unit(staged: Path, final: Path, files: list[str], scratch: Path) -> None:
    if _current(staged, final, files):
        return
    new, old = scratch.with_name(scratch.name + ".new"), scratch.with_name(scratch.name + ".old")
    for d in (new, old):
        shutil.rmtree(d, ignore_errors=True)
    for f in files:
        dst = new / f
        dst.parent.mkdir(parents=True, exist_ok=True)
        try:
            os.link(staged / f, dst)
        except OSError:  # a filesystem without hard links
            shutil.copy2(staged / f, dst)
    if not files:
        new.mkdir(parents=True, exist_ok=True)
    if final.is_symlink() or final.is_file():
        final.unlink()
    elif final.exists():
        os.rename(final, old)
    os.rename(new, final)
    shutil.rmtree(old, ignore_errors=True)


def loss_warning(robot: str, lost: dict[str, str], files: list[str]) -> str:
    """The one warning on the formats a robot's build left out as beyond their own limits
    (``lost``: format -> why) with ``files``, every file left out (below the output folder):
    not a failure, since no recipe of this robot could have them; listing the format under
    ``outputs:`` makes it one."""
    why = "; ".join(f"{name.upper()}: {reason}" for name, reason in lost.items())
    return (f"{robot}: not written, a limit of the format: {why}; left out: {', '.join(files)} "
            f"(list it under outputs: to make this an error)")
