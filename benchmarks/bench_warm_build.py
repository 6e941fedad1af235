"""A warm build into a fresh output folder, the picture report at 100 links, and the cold build
they save, side by side in one run (docs/performance.md, "Builds" and "Picture report").

1. cold: ``robotkit build recipes/ur5.yaml`` with an empty ``ROBOTKIT_CACHE`` into an empty
   folder (this fills the cache; ``--cache DIR`` reuses a warm cache and skips it);
2. warm, with the report: the same build into a fresh folder (every task result cached);
3. warm, ``--no-report``: the same without the picture report;
4. the picture report of a 100-link chain (``bench_noop.recipe``: boxes and one STL; its links
   without collision geometry: the self-collision matrix of 100 links costs minutes cold and is
   not what is measured here):
   ``robotkit report BUILD/chain -o DIR`` on its build folder, drawn (no cache: the report
   command draws what it is given), the whole process;
5. the chain's warm build with the report into a fresh folder (its report from the cache).

Each figure is the whole ``robotkit`` process: wall time, CPU time of it and its workers (user +
system, ``os.wait4``) and the load average before and after, since the machine may be shared.
Warm figures are the median of ``--repeat`` runs (with the minimum).  The processes run with
bytecode caching on (``PYTHONDONTWRITEBYTECODE`` unset), as an installed robotkit does.

``python benchmarks/bench_warm_build.py [--recipe recipes/ur5.yaml] [--links 100] [--repeat 5]
[--cache DIR] [--jobs N]`` (``--links 0``: no chain)
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_noop  # noqa: E402


def timed(args: list[str], env: dict, cwd: Path | None = None) -> dict:
    """One ``robotkit`` process: wall, CPU (with its workers), load average before and after."""
    load0 = os.getloadavg()[0]
    with tempfile.TemporaryFile() as err:  # a file, not a pipe: a long stderr would block it
        t0 = time.perf_counter()
        p = subprocess.Popen([sys.executable, "-m", "robotkit", *args], env=env, cwd=cwd,
                             stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(p.pid, 0)
        wall = time.perf_counter() - t0
        if status != 0:
            err.seek(0)
            raise SystemExit(f"robotkit {' '.join(args)} failed: {err.read().decode()}")
    return {"wall": wall, "cpu": usage.ru_utime + usage.ru_stime, "load": (load0, os.getloadavg()[0])}


def row(name: str, runs: list[dict], goal: str) -> str:
    walls, cpus = [r["wall"] for r in runs], [r["cpu"] for r in runs]
    loads = f"{min(r['load'][0] for r in runs):.1f}-{max(r['load'][1] for r in runs):.1f}"
    spread = f" (min {min(walls):.2f})" if len(runs) > 1 else ""
    return (f"| {name} | {statistics.median(walls):.2f}{spread} | {statistics.median(cpus):.2f} | {len(runs)} "
            f"| {loads} | {goal} |")


def chain_recipe(n: int) -> str:
    """``bench_noop.recipe(n)``, its links without collision geometry."""
    lines = bench_noop.recipe(n).splitlines()
    return "\n".join(line[:-1] + ", collision: none}" if line.startswith("  l") and line.endswith("}}") else line
                     for line in lines) + "\n"


def fresh(work: Path, name: str) -> Path:
    out = work / name
    shutil.rmtree(out, ignore_errors=True)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--recipe", default="recipes/ur5.yaml")
    ap.add_argument("--links", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--jobs", type=int, default=None, help="-j of the builds (default: robotkit's)")
    ap.add_argument("--cache", type=Path, help="a warm ROBOTKIT_CACHE to reuse (no cold build)")
    args = ap.parse_args()
    jobs = ["-j", str(args.jobs)] if args.jobs else []
    recipe = str((REPO / args.recipe).resolve())
    print(f"cores: {len(os.sched_getaffinity(0))}, load average at start: "
          + " ".join(f"{v:.2f}" for v in os.getloadavg()), flush=True)
    print("| build | wall (s) | CPU (s) | runs | load | goal |")
    print("|---|---:|---:|---:|---|---|")
    with tempfile.TemporaryDirectory(prefix="bench-warm-") as tmp:
        work = Path(tmp)
        cache = args.cache.resolve() if args.cache else work / "cache"
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env.update(ROBOTKIT_CACHE=str(cache), PYTHONPATH=str(REPO))
        if args.cache is None:
            cold = timed(["build", recipe, "--out", str(fresh(work, "cold")), *jobs], env)
            print(row(f"{args.recipe} cold (empty cache), with report", [cold], "-"), flush=True)
        else:  # the cache may lack this code's task results: fill them
            timed(["build", recipe, "--out", str(fresh(work, "fill")), *jobs], env)
        for report, goal in ((True, "< 1.5 s"), (False, "< 1 s")):
            flags = [] if report else ["--no-report"]
            runs = [timed(["build", recipe, "--out", str(fresh(work, "warm")), *flags, *jobs], env)
                    for _ in range(args.repeat)]
            name = f"{args.recipe} warm, fresh folder, {'with report' if report else '--no-report'}"
            print(row(name, runs, goal), flush=True)
        if args.links:
            chain_rows(args, work, env, jobs)
    print("load average at end: " + " ".join(f"{v:.2f}" for v in os.getloadavg()))
    return 0


def chain_rows(args, work: Path, env: dict, jobs: list[str]) -> None:
    """The chain's rows: its report drawn, its warm build (``--links 0``: none)."""
    chain = work / "chain"
    chain.mkdir()
    (chain / "robot.yaml").write_text(chain_recipe(args.links))
    shutil.copyfile(bench_noop.MESH, chain / "slider.stl")
    timed(["build", "robot.yaml", "--out", "build", *jobs], env, chain)  # fills the cache
    runs = [timed(["report", "build/chain", "-o", str(fresh(work, "report"))], env, chain)
            for _ in range(max(1, args.repeat // 2))]
    print(row(f"{args.links}-link chain: robotkit report (drawn)", runs, "< 5 s"), flush=True)
    runs = [timed(["build", "robot.yaml", "--out", str(fresh(work, "chainwarm")), *jobs], env, chain)
            for _ in range(max(1, args.repeat // 2))]
    print(row(f"{args.links}-link chain warm, fresh folder, with report", runs, "-"), flush=True)


if __name__ == "__main__":
    raise SystemExit(main())
