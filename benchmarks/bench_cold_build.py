"""A cold build of a recipe (empty ``ROBOTKIT_CACHE``, empty output folder), whole process.

Prints, per run: wall time, CPU time of the process and its workers (user + system, from
``os.wait4``), and the load average before and after, since the machine may be shared.
``--checkout DIR`` also times another robotkit checkout (e.g. the code before a change) on
its own copy of the recipe, interleaved with this one, so both see the same load.

``python benchmarks/bench_cold_build.py [--recipe recipes/ur5.yaml] [--jobs 2 1] [--repeat 1]
[--checkout ../main]``
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def cold_build(checkout: Path, recipe: str, jobs: int, work: Path) -> dict:
    cache, out = work / "cache", work / "out"
    for d in (cache, out):
        shutil.rmtree(d, ignore_errors=True)
    env = {**os.environ, "ROBOTKIT_CACHE": str(cache), "PYTHONPATH": str(checkout)}
    load0 = os.getloadavg()[0]
    with tempfile.TemporaryFile() as err:  # a file, not a pipe: a long stderr would block the build
        t0 = time.perf_counter()
        p = subprocess.Popen([sys.executable, "-m", "robotkit", "build", str(checkout / recipe), "-j", str(jobs),
                              "--out", str(out)], env=env, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(p.pid, 0)
        wall = time.perf_counter() - t0
        if status != 0:
            err.seek(0)
            raise SystemExit(f"build failed in {checkout}: {err.read().decode()}")
    return {"wall": wall, "cpu": usage.ru_utime + usage.ru_stime, "load": (load0, os.getloadavg()[0])}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--recipe", default="recipes/ur5.yaml", help="relative to each checkout")
    ap.add_argument("--jobs", type=int, nargs="+", default=[2, 1])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--checkout", type=Path, help="another robotkit checkout to time beside this one")
    args = ap.parse_args()
    checkouts = [("this", REPO)] + ([("other", args.checkout.resolve())] if args.checkout else [])
    print("| checkout | -j | wall (s) | CPU (s) | load before / after |")
    print("|---|---:|---:|---:|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.repeat):
            for jobs in args.jobs:
                for name, checkout in checkouts:
                    r = cold_build(checkout, args.recipe, jobs, Path(tmp))
                    print(f"| {name} ({checkout}) | {jobs} | {r['wall']:.1f} | {r['cpu']:.1f} "
                          f"| {r['load'][0]:.1f} / {r['load'][1]:.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
