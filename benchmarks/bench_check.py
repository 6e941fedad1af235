"""``robotkit check`` of a build folder, per stage and in total.

Each example (default ur5 and turret_bot) is built once with ``robotkit build --no-report`` into a
temporary folder (or ``--out``, kept: a second run reuses it), then checked ``--repeat`` times, one
whole ``robotkit check FOLDER --format json`` process each.  Per stage: the median of its wall time
in seconds as the JSON gives it (``stages[].seconds``; the stages run at once, so they add up to more
than the total); then the median of the check's own total (``seconds``), of the process's wall
time and of its CPU time (user + system, with its worker processes and the programs it runs, those left running at
its exit included: the benchmark is their subreaper).
The load average at the start and the end says how busy the machine was.

``python benchmarks/bench_check.py [--robots ur5 turret_bot] [--repeat 5] [--out DIR]``
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
ORDER = ("check_urdf", "ign sdf -k", "mujoco", "lints", "equivalence", "consumers", "simulation",
         "self-collision", "motion")


def children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def reap_orphans() -> None:
    """Become the subreaper of this process's descendants (Linux), so that worker processes the
    check leaves running when it exits (a pool shut down without waiting) are reparented here and
    their CPU time is counted when :func:`wait_orphans` reaps them."""
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(36, 1, 0, 0, 0)  # PR_SET_CHILD_SUBREAPER
    except (OSError, AttributeError):
        pass


def wait_orphans() -> None:
    while True:
        try:
            os.waitpid(-1, 0)
        except ChildProcessError:
            return


def check_once(folder: Path) -> dict:
    cpu, t0 = children_cpu(), time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "robotkit", "check", str(folder), "--format", "json"],
                          capture_output=True, text=True)
    wall = time.perf_counter() - t0
    wait_orphans()
    cpu = children_cpu() - cpu
    if proc.returncode not in (0, 1):
        raise SystemExit(f"robotkit check {folder} failed ({proc.returncode}):\n{proc.stderr}")
    data = json.loads(proc.stdout)
    return {"stages": {s["stage"]: s.get("seconds") for s in data["stages"]}, "total": data.get("seconds"),
            "wall": wall, "cpu": cpu}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robots", nargs="+", default=["ur5", "turret_bot"])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", help="build folder to keep (default: a temporary one)")
    args = ap.parse_args()
    reap_orphans()
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start; "
          f"medians of {args.repeat} checks, seconds")
    with tempfile.TemporaryDirectory(prefix="bench_check.") as tmp:
        out = Path(args.out or tmp)
        for robot in args.robots:
            subprocess.run([sys.executable, "-m", "robotkit", "build", str(REPO / "recipes" / f"{robot}.yaml"),
                            "--out", str(out), "--no-report"], check=True, capture_output=True)
        print(f"{'stage':<16}" + "".join(f"{r:>12}" for r in args.robots))
        runs = {r: [check_once(out / r) for _ in range(args.repeat)] for r in args.robots}

        def med(robot, get):
            values = [v for v in (get(run) for run in runs[robot]) if v is not None]
            return f"{statistics.median(values):>12.3f}" if values else f"{'-':>12}"

        for stage in ORDER:
            print(f"{stage:<16}" + "".join(med(r, lambda run, s=stage: run["stages"].get(s)) for r in args.robots))
        for label, key in (("check total", "total"), ("process wall", "wall"), ("process CPU", "cpu")):
            print(f"{label:<16}" + "".join(med(r, lambda run, k=key: run[k]) for r in args.robots))
    print(f"load average {os.getloadavg()[0]:.1f} at the end")
    return 0


if __name__ == "__main__":
    sys.exit(main())
