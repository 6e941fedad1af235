"""MJCF import over the shared MuJoCo Menagerie set, and SDF import over the shared Gazebo model
set (``--gazebo DIR``: each model folder with a model.config, read through libsdformat, the
rebuilt model.sdf compared through libsdformat): per model, the import (read through MuJoCo,
convert, write, and the verification's comparison in MuJoCo), the build of the recipe the
verification makes, whether the rebuild agrees with the original, and the ledger's size; then
the totals and the distribution.

Every ``<model>/*.xml`` that is not a scene (``scene*.xml``) is imported into a temporary folder
(a file MuJoCo refuses on its own, such as a fragment another includes, is listed as refused).  The build is
the verification's (``robotkit.commands.import_.build_mjcf``: the MJCF and the URDF it compares),
timed apart from the import.  Each model starts from an empty mesh cache (``$ROBOTKIT_CACHE`` a
fresh folder: a first import, nothing reused from an earlier run or model) unless ``--cache DIR``
names one to share.  Times are wall (``perf_counter``) and CPU (:func:`cpu_time`: this process's and its
finished children's, what compares on a machine other work shares; the load average is printed); the distribution is of the CPU time of
import plus verification (its build included), the issue's measure.  For comparison, the figures the other converters publish: MJCF to USD
converts 85 of 85 Menagerie variants at 0.63 s each on average, unverified (its authors checked
75 by hand); Pinocchio's MJCF reader loads 25 of 34 Menagerie descriptions.

Usage (from the repository root):

    python benchmarks/bench_import_mjcf.py [--menagerie DIR] [--gazebo DIR] [--sets menagerie gazebo]
                                           [--only NAME...] [--cache DIR]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from robotkit.commands.import_ import build_mjcf, build_sdf  # noqa: E402
from robotkit.errors import RobotkitError  # noqa: E402
from robotkit.importer import import_mjcf, import_sdf  # noqa: E402

MENAGERIE = REPO.parent / "shared" / "assets" / "menagerie"
GAZEBO = REPO.parent / "shared" / "assets" / "gazebo_models"


def cpu_time() -> float:
    """CPU seconds of this process (all its threads) and of its finished child processes: work
    moved to a worker process still counts."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def models(folder: Path, only: list[str]) -> list[Path]:
    found = []
    for d in sorted(p for p in folder.iterdir() if p.is_dir()):
        if only and d.name not in only:
            continue
        found.extend(f for f in sorted(d.glob("*.xml")) if not f.name.startswith("scene")
                     and "<mujoco" in f.read_text(encoding="utf-8", errors="replace"))
    return found


def gazebo_models(folder: Path, only: list[str]) -> list[Path]:
    """Every model folder (a model.config) of a Gazebo model set."""
    return [d for d in sorted(p for p in folder.iterdir() if p.is_dir())
            if (d / "model.config").is_file() and (not only or d.name in only)]


def one(model: Path, out: Path, kind: str = "mjcf") -> dict:
    built = {}
    importer, builder = (import_sdf, build_sdf) if kind == "sdf" else (import_mjcf, build_mjcf)
    label = model.name if kind == "sdf" else f"{model.parent.name}/{model.name}"

    def build(recipe, folder):
        start, cpu = time.perf_counter(), cpu_time()
        path = builder(recipe, folder)
        built["s"], built["cpu"] = time.perf_counter() - start, cpu_time() - cpu
        return path

    start, cpu = time.perf_counter(), cpu_time()
    try:
        result = importer(model, out / f"{model.stem}.yaml", build=build)
    except RobotkitError as exc:
        return {"model": label, "error": str(exc).splitlines()[0]}
    total, cpu = time.perf_counter() - start, cpu_time() - cpu
    v = result.verdict
    return {"model": label, "import": total - built.get("s", 0.0), "build": built.get("s", 0.0),
            "cpu": cpu, "build_cpu": built.get("cpu", 0.0), "ok": v.ok, "configs": v.configurations,
            "worst": max(e for e, _ in v.worst.values()), "ledger": len(result.ledger)}


def run_set(title: str, todo: list[Path], kind: str, cache: Path | None = None) -> list[dict]:
    """Import (and verify) each model of one set, a line each, then the set's totals.  Each
    model gets an empty mesh cache unless ``cache`` names one folder for all."""
    rows = []
    print(f"\n{title}\n{'model':52} {'import s':>9} {'build s':>8} {'CPU s':>6} {'of it build':>11} "
          f"{'verified':>9} {'largest rel. diff':>18} {'ledger':>7}")
    with tempfile.TemporaryDirectory(prefix=f"bench-{kind}-") as tmp:
        for i, model in enumerate(todo):
            os.environ["ROBOTKIT_CACHE"] = str(cache or Path(tmp) / f"cache{i}")
            row = one(model, Path(tmp) / str(i), kind)
            rows.append(row)
            if "error" in row:
                print(f"{row['model']:52} refused: {row['error']}")
                continue
            print(f"{row['model']:52} {row['import']:9.2f} {row['build']:8.2f} {row['cpu']:6.2f} "
                  f"{row['build_cpu']:11.2f} {'yes' if row['ok'] else 'NO':>9} {row['worst']:18.1e} "
                  f"{row['ledger']:7d}", flush=True)
    totals(rows)
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--menagerie", type=Path, default=MENAGERIE)
    ap.add_argument("--gazebo", type=Path, default=GAZEBO, help="a folder of Gazebo model folders")
    ap.add_argument("--sets", nargs="*", default=["menagerie", "gazebo"], choices=["menagerie", "gazebo"])
    ap.add_argument("--only", nargs="*", default=[], help="model folder names")
    ap.add_argument("--cache", type=Path, help="one mesh cache folder for every model (default: an empty one each)")
    args = ap.parse_args()
    print(f"load average at the start: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    rows = []
    if "menagerie" in args.sets:
        rows += run_set(f"MJCF: {args.menagerie}", models(args.menagerie, args.only), "mjcf", args.cache)
    if "gazebo" in args.sets:
        rows += run_set(f"SDF: {args.gazebo}", gazebo_models(args.gazebo, args.only), "sdf", args.cache)
    print(f"load average at the end: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0 if all(r.get("ok") for r in rows) else 1


def totals(rows: list[dict]) -> None:
    done = [r for r in rows if "error" not in r]
    if done:
        imports = [r["import"] for r in done]
        builds = [r["build"] for r in done]
        print(f"\n{len(done)} of {len(rows)} imported, {sum(r['ok'] for r in done)} verified; "
              f"ledger lines {sum(r['ledger'] for r in done)}")
        print(f"wall: import + verification: mean {statistics.mean(imports):.2f} s, median "
              f"{statistics.median(imports):.2f} s, max {max(imports):.2f} s; build: mean {statistics.mean(builds):.2f} s, "
              f"median {statistics.median(builds):.2f} s, max {max(builds):.2f} s")
        cpu = sorted(r["cpu"] for r in done)
        p90 = cpu[min(len(cpu) - 1, round(0.9 * (len(cpu) - 1)))]
        print(f"CPU, import + verification (its build included): mean {statistics.mean(cpu):.2f} s, median "
              f"{statistics.median(cpu):.2f} s, 90th percentile {p90:.2f} s, min {cpu[0]:.2f} s, max {cpu[-1]:.2f} s; "
              f"{sum(c < 2 for c in cpu)} of {len(cpu)} under 2 s; of it the build: mean "
              f"{statistics.mean(r['build_cpu'] for r in done):.2f} s")


if __name__ == "__main__":
    raise SystemExit(main())
