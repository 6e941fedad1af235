"""``robotkit catalogue``: a folder (or list) of object meshes -> simulation-ready objects.

    find meshes        a folder, searched recursively, or a text file with one path per line
    units              declared (``--units``, a units column in the mass table) or guessed
                       from the mesh's size, and reported as such in the index
    one recipe each    OUT/.robotkit/catalogue/<name>.yaml: one link, the mesh as visual,
                       a collision strategy, density or the mass from the table
    one build          robotkit.pipeline.runner over every recipe: the same doit tasks as any robot
                       (repair, mass properties, collision decomposition, URDF, SDF, MJCF),
                       incremental, -j / --scheduler for the mesh work, and a failing object
                       never stops the others; progress with the time left (robotkit.pipeline.progress)
    index              OUT/catalogue.json and OUT/catalogue.csv: what was made, what failed and why

A rerun builds only what is missing or changed (doit's record and the mesh cache); the
unit guesses are remembered per file (size and mtime), so a rerun does not read every
mesh again.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import re
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from robotkit import paths
from robotkit.commands.build import cache_messages, scheduler
from robotkit.emit.layout import robot_layout
from robotkit.errors import Problem, RobotkitError
from robotkit.mesh.io import load_mesh
from robotkit.paths import file_stem
from robotkit.pipeline.progress import Progress
from robotkit.pipeline.runner import build

MESH_SUFFIXES = (".stl", ".obj", ".dae")
STATE = Path(".robotkit") / "catalogue"
GUESS_MM_ABOVE = 5.0
"""A mesh whose largest extent is above this many file units is taken to be in millimetres
(a 5 m household object or part is rarer than a 5 mm one); at or below it, metres."""
UNIT_SCALE = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}


@dataclass
class Item:
    """One object of the catalogue."""

    name: str
    source: Path
    rel: str
    units: str = ""
    units_from: str = ""  # declared | table | guessed | file (DAE <unit>)
    extent: float | None = None  # largest extent in file units
    mass: float | None = None
    status: str = "pending"
    errors: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)


def find_meshes(source: Path) -> tuple[Path, list[Path]]:
    """(base folder, mesh files): every STL/OBJ/DAE below a folder, or the paths a list file names."""
    if source.is_dir():
        files = sorted(p for p in source.rglob("*") if p.is_file() and p.suffix.lower() in MESH_SUFFIXES
                       and not any(part.startswith(".") for part in p.relative_to(source).parts))
        return source, files
    if not source.is_file():
        raise RobotkitError(Problem(f"{source}: no such folder or list file"))
    files, problems = [], []
    for n, line in enumerate(source.read_text(encoding="utf-8").splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        p = (source.parent / line) if not os.path.isabs(line) else Path(line)
        if not p.is_file():
            problems.append(Problem(f"no such mesh file: {line}", str(source), n))
        else:
            files.append(p)
    if problems:
        raise RobotkitError(problems)
    return source.parent, files


def object_names(base: Path, files: list[Path]) -> list[tuple[str, str]]:
    """(name, path relative to base) per file: the relative path without suffix, with every
    character a file name cannot hold as ``_``; names that collide get a numeric suffix."""
    out, seen = [], set()
    for f in files:
        try:
            rel = f.resolve().relative_to(base.resolve()).as_posix()
        except ValueError:
            rel = f.as_posix()
        stem = re.sub(r"[^A-Za-z0-9_]+", "_", rel.rsplit(".", 1)[0]).strip("_") or "object"
        if stem[0].isdigit():
            stem = f"o_{stem}"
        name, n = file_stem(stem), 2
        while name in seen:
            name, n = f"{file_stem(stem)}_{n}", n + 1
        seen.add(name)
        out.append((name, rel))
    return out


def read_table(path: Path) -> dict[str, dict]:
    """The mass table: CSV with a header naming ``name`` (object name or relative path) and
    ``mass`` (kg), optionally ``units`` (m, cm, mm, in)."""
    problems, rows = [], {}
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise RobotkitError(Problem(f"cannot read the mass table: {exc.strerror}", str(path))) from None
    reader = csv.DictReader(io.StringIO(text))
    fields = [f.strip() for f in reader.fieldnames or []]
    if "name" not in fields or not ({"mass", "units"} & set(fields)):
        raise RobotkitError(Problem("the mass table needs a header with 'name' and 'mass' (and optionally 'units')",
                                    str(path), 1))
    for row in reader:
        line = reader.line_num
        row = {k.strip(): (v or "").strip() for k, v in row.items() if k}
        entry: dict = {}
        if row.get("mass"):
            try:
                mass = float(row["mass"])
            except ValueError:
                mass = float("nan")
            if not math.isfinite(mass) or mass <= 0:
                problems.append(Problem(f"mass must be a number > 0 (got '{row['mass']}')", str(path), line, "mass"))
                continue
            entry["mass"] = mass
        if row.get("units"):
            if row["units"] not in UNIT_SCALE:
                problems.append(Problem(f"units must be one of m, cm, mm, in (got '{row['units']}')", str(path),
                                        line, "units"))
                continue
            entry["units"] = row["units"]
        rows[row["name"]] = entry
    if problems:
        raise RobotkitError(problems)
    return rows


def _guess_units(items: list[Item], state: Path) -> None:
    """Fill each item's units from the size of its mesh (remembered by file size and mtime)."""
    memo_path = state / "units.json"
    try:
        memo = json.loads(memo_path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        memo = {}
    new_memo = {}
    for it in items:
        if it.units:
            continue
        st = it.source.stat()
        sig = f"{st.st_size}:{st.st_mtime_ns}"
        known = memo.get(str(it.source))
        if known and known.get("sig") == sig:
            extent, from_file = known["extent"], known.get("file_units", False)
        else:
            try:
                mesh = load_mesh(str(it.source), 1.0, Problem("", key=it.rel))
            except RobotkitError as exc:
                it.status, it.errors = "failed", [p.message for p in exc.problems]
                continue
            except Exception as exc:  # a mesh no loader can read: reported, never stops the batch
                it.status, it.errors = "failed", [f"cannot read the mesh: {exc}"]
                continue
            if len(mesh.vertices) == 0:
                it.status, it.errors = "failed", ["the mesh has no vertices"]
                continue
            extent = float(max(mesh.extents))
            from_file = it.source.suffix.lower() == ".dae" and "<unit" in it.source.read_text("utf-8", "replace")[:4000]
        new_memo[str(it.source)] = {"sig": sig, "extent": extent, "file_units": from_file}
        it.extent = extent
        if from_file:  # COLLADA's <unit> already gave metres
            it.units, it.units_from = "m", "file"
        elif not math.isfinite(extent):
            it.status, it.errors = "failed", ["the mesh has coordinates that are not finite"]
        else:
            it.units, it.units_from = ("mm", "guessed") if extent > GUESS_MM_ABOVE else ("m", "guessed")
    state.mkdir(parents=True, exist_ok=True)
    memo_path.write_text(json.dumps(new_memo, sort_keys=True, indent=0) + "\n", encoding="utf-8")


def _recipe(it: Item, density: float, collision: str, recipe_dir: Path) -> str:
    mesh = os.path.relpath(it.source.resolve(), recipe_dir.resolve())
    lines = [
        f"# made by robotkit catalogue from {it.rel} (units {it.units}, {it.units_from})",
        f"robot: {it.name}",
        f"density: {density!r}",
        "open_mesh: hull",
        "links:",
        f"  {it.name}:",
        f"    visual: {{mesh: {json.dumps(mesh)}, units: {it.units}}}",
        f"    collision: {{strategy: {collision}}}" if collision != "none" else "    collision: none",
    ]
    if it.mass is not None:
        lines.append(f"    inertial: {{mass: {it.mass!r}}}")
    return "\n".join(lines) + "\n"


def _write_if_changed(path: Path, text: str) -> None:
    try:
        if path.read_text(encoding="utf-8") == text:
            return
    except OSError:
        pass
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


def catalogue(source: str | os.PathLike, out_dir: str | os.PathLike, *, density: float = 1000.0,
              units: str | None = None, masses: str | os.PathLike | None = None, collision: str = "decompose",
              jobs: int = 1, progress=sys.stderr) -> "Result":
    """Build every mesh of ``source`` into ``out_dir`` and write the index."""
    if not (math.isfinite(density) and density > 0):
        raise RobotkitError(Problem(f"--density must be a number > 0 (got {density})"))
    source, out = Path(source), Path(out_dir)
    base, files = find_meshes(source)
    if not files:
        raise RobotkitError(Problem(f"{source}: no STL, OBJ or DAE meshes found"))
    table = read_table(Path(masses)) if masses else {}
    items = [Item(name, f, rel) for (name, rel), f in zip(object_names(base, files), files)]
    unknown = set(table) - {it.name for it in items} - {it.rel for it in items}
    if unknown:
        raise RobotkitError([Problem(f"the mass table names '{n}', which is not a mesh of the catalogue",
                                     str(masses), key="name") for n in sorted(unknown)])
    for it in items:
        row = table.get(it.name) or table.get(it.rel) or {}
        it.mass = row.get("mass")
        if row.get("units"):
            it.units, it.units_from = row["units"], "table"
        elif units:
            it.units, it.units_from = units, "declared"
    state = out / STATE
    _guess_units(items, state)

    recipe_dir = state / "recipes"
    recipes = []
    wanted = set()
    for it in items:
        if it.status == "failed":
            continue
        path = recipe_dir / f"{it.name}.yaml"
        _write_if_changed(path, _recipe(it, density, collision, recipe_dir))
        recipes.append(str(path))
        wanted.add(path.name)
    for old in recipe_dir.glob("*.yaml"):  # objects no longer in the catalogue
        if old.name not in wanted:
            old.unlink()

    result = None
    if recipes:
        bar = Progress(progress, slow=float("inf"), eta=True, log_every=10.0, label="catalogue ")
        with paths.widened([base.resolve()]):  # the generated recipes read the meshes where they are
            result = build(recipes, out, jobs=jobs, report=False, keep_going=True, progress=bar)
        failed_by_robot: dict[str, list[str]] = {}
        for task, message in result.failed:
            failed_by_robot.setdefault(task.split(":", 1)[0], []).extend(
                line for line in message.splitlines() if line)
        for task, message in result.errors:
            failed_by_robot.setdefault(task.split(":", 1)[0], []).append(f"internal error in {task}")
        warnings = {}
        for w in result.warnings:
            name, _, text = w.partition(": ")
            warnings.setdefault(name, []).append(text)
        for it in items:
            if it.status == "failed":
                continue
            if it.name in failed_by_robot:
                it.status, it.errors = "failed", sorted(set(failed_by_robot[it.name]), key=failed_by_robot[it.name].index)
            else:
                it.status = "ok"
                it.warnings = warnings.get(it.name, [])
    index = _index(items, out, base)
    _write_if_changed(out / "catalogue.json", json.dumps(index, indent=1, sort_keys=True) + "\n")
    _write_if_changed(out / "catalogue.csv", _csv(index))
    return Result(index, result.ran if result else [], result.uptodate if result else [])


@dataclass
class Result:
    index: dict
    ran: list[str]  # the build's tasks that ran (a rerun runs only what is missing or changed)
    uptodate: list[str]


def _index(items: list[Item], out: Path, base: Path) -> dict:
    objects = []
    for it in items:
        entry = {"name": it.name, "source": it.rel, "status": it.status, "units": it.units or None,
                 "units_from": it.units_from or None, "extent_file_units": it.extent, "errors": it.errors,
                 "warnings": it.warnings}
        if it.status == "ok":
            try:
                report = json.loads(robot_layout(out / it.name).report_json.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                report = {}
            inertial = report.get("inertials", {}).get(it.name, {})
            coll = next(iter(report.get("collision", {}).values()), {})
            fid = coll.get("fidelity", {})
            built = robot_layout(it.name)  # the files, relative to the index
            entry.update({
                "mass": inertial.get("mass"), "com": inertial.get("com"), "inertia": inertial.get("inertia"),
                "mass_source": inertial.get("source"),
                "collision_pieces": len(coll.get("pieces", [])) or None,
                "collision_volume_ratio": fid.get("volume_ratio"),
                "collision_distance": (fid.get("distance") or {}).get("max"),
                "urdf": built.urdf.as_posix(), "sdf": built.sdf.as_posix(), "mjcf": built.mjcf.as_posix(),
            })
        objects.append(entry)
    ok = sum(o["status"] == "ok" for o in objects)
    return {"source": base.name, "objects": objects, "ok": ok, "failed": len(objects) - ok}


CSV_FIELDS = ["name", "source", "status", "units", "units_from", "mass", "com", "inertia", "collision_pieces",
              "collision_volume_ratio", "collision_distance", "urdf", "sdf", "mjcf", "errors"]


def _csv(index: dict) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_FIELDS)
    for o in index["objects"]:
        row = []
        for f in CSV_FIELDS:
            v = o.get(f)
            if isinstance(v, list):
                v = " ".join(repr(x) if isinstance(x, float) else str(x) for x in v) if f != "errors" else "; ".join(v)
            elif isinstance(v, float):
                v = repr(v)
            row.append("" if v is None else v)
        w.writerow(row)
    return buf.getvalue()


def run(args) -> int:
    if args.jobs is not None and args.jobs < 1:
        print("robotkit: error: -j must be at least 1", file=sys.stderr)
        return 2
    start = time.perf_counter()
    with scheduler(args) as jobs, cache_messages():
        made = catalogue(args.source, args.out, density=args.density, units=args.units, masses=args.masses,
                         collision=args.collision, jobs=jobs)
    index = made.index
    for obj in index["objects"]:
        if obj["status"] != "ok":
            for line in obj["errors"] or ["failed"]:
                print(f"{obj['source']}: {line}", file=sys.stderr)
    guessed = sum(o["units_from"] == "guessed" for o in index["objects"])
    out = os.path.relpath(os.path.abspath(args.out))
    print(f"catalogue {out}: {index['ok']} objects made, {index['failed']} failed"
          f"{f', units guessed for {guessed}' if guessed else ''} ({out}/catalogue.json; "
          f"{len(made.ran)} tasks run, {len(made.uptodate)} up to date, {time.perf_counter() - start:.1f} s)")
    return 1 if index["failed"] else 0
