"""``robotkit check`` of a build folder, per stage and in total, first and again.

Each example (default ur5 and turret_bot) is built once with ``robotkit build --no-report`` into a
temporary folder (or ``--out``, kept: a second run reuses it), then checked ``--repeat`` times, one
whole ``robotkit check FOLDER --format json`` process each, two ways: *first*, with an empty cache
of its own (``ROBOTKIT_CACHE`` a fresh folder: the check of a build folder never checked before),
and *again*, the same folder checked a second time with that cache (the stages cached by content,
robotkit.check.cache, taken from it).  Per stage: the median of its wall time in seconds as the
JSON gives it (``stages[].seconds``; the stages run at once, so they add up to more than the
total); then the median of the check's own total (``seconds``), of the process's wall time and of
its CPU time (user + system, with its worker processes and the programs it runs, those left
running at its exit included: the benchmark is their subreaper), and the CPU time of the main
process alone and of the busiest other process (read from /proc every 10 ms while the check runs:
on 2 cores the wall time cannot be under half the total CPU, nor under the main process's).
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


HZ = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


def proc_stat(pid: int) -> tuple[int, float] | None:
    """(parent pid, CPU seconds so far) of a running process, from /proc; None when it is gone."""
    try:
        with open(f"/proc/{pid}/stat", encoding="utf-8") as f:
            text = f.read()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()
    return int(fields[1]), (int(fields[11]) + int(fields[12])) / HZ


def watch(proc: subprocess.Popen) -> dict[int, float]:
    """Every 10 ms until ``proc`` exits: the CPU seconds last seen of it and of each of its descendants."""
    seen: dict[int, float] = {}
    while proc.poll() is None:
        for entry in os.listdir("/proc"):
            if entry.isdigit():
                stat = proc_stat(int(entry))
                if stat and (int(entry) == proc.pid or int(entry) in seen or stat[0] in seen):
                    seen[int(entry)] = stat[1]
        time.sleep(0.01)
    return seen


def check_once(folder: Path, cache: Path) -> dict:
    cpu, t0 = children_cpu(), time.perf_counter()
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:  # not pipes: nothing reads
        # them while the process is watched, and a JSON larger than a pipe holds would block it
        proc = subprocess.Popen([sys.executable, "-m", "robotkit", "check", str(folder), "--format", "json"],
                                stdout=out, stderr=err, env={**os.environ, "ROBOTKIT_CACHE": str(cache)})
        seen = watch(proc) if os.path.isdir("/proc") else {}
        proc.wait()
        wall = time.perf_counter() - t0
        stdout, stderr = (f.seek(0) or f.read().decode("utf-8", "replace") for f in (out, err))
    wait_orphans()
    cpu = children_cpu() - cpu
    if proc.returncode not in (0, 1):
        raise SystemExit(f"robotkit check {folder} failed ({proc.returncode}):\n{stderr}")
    data = json.loads(stdout)
    others = [c for pid, c in seen.items() if pid != proc.pid]
    return {"stages": {s["stage"]: s.get("seconds") for s in data["stages"]}, "total": data.get("seconds"),
            "wall": wall, "cpu": cpu, "main": seen.get(proc.pid), "busiest": max(others, default=None)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robots", nargs="+", default=["ur5", "turret_bot"])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", help="build folder to keep (default: a temporary one)")
    args = ap.parse_args()
    reap_orphans()
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start; "
          f"medians of {args.repeat} checks, seconds", flush=True)
    with tempfile.TemporaryDirectory(prefix="bench_check.") as tmp:
        out = Path(args.out or tmp)
        for robot in args.robots:
            subprocess.run([sys.executable, "-m", "robotkit", "build", str(REPO / "recipes" / f"{robot}.yaml"),
                            "--out", str(out), "--no-report"], check=True, capture_output=True)
        runs: dict[tuple[str, str], list[dict]] = {}
        for k in range(args.repeat):
            for robot in args.robots:
                cache = Path(tmp) / f"cache-{robot}-{k}"  # empty: the first check; then the same again
                runs.setdefault((robot, "first"), []).append(check_once(out / robot, cache))
                runs.setdefault((robot, "again"), []).append(check_once(out / robot, cache))
        columns = [(r, way) for r in args.robots for way in ("first", "again")]
        print(f"{'':<18}" + "".join(f"{f'{r} {way}':>18}" for r, way in columns))

        def med(column, get):
            values = [v for v in (get(run) for run in runs[column]) if v is not None]
            return f"{statistics.median(values):>18.3f}" if values else f"{'-':>18}"

        for stage in ORDER:
            print(f"{stage:<18}" + "".join(med(c, lambda run, s=stage: run["stages"].get(s)) for c in columns))
        for label, key in (("check total", "total"), ("process wall", "wall"), ("process CPU", "cpu"),
                           ("main process CPU", "main"), ("busiest other CPU", "busiest")):
            print(f"{label:<18}" + "".join(med(c, lambda run, k=key: run[k]) for c in columns))
    print(f"load average {os.getloadavg()[0]:.1f} at the end")
    return 0


if __name__ == "__main__":
    sys.exit(main())
