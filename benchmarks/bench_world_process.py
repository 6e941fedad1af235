"""``robotkit world`` as a whole process: wall time and peak memory.

On the nav2 warehouse map (1006 x 1674 cells, ../shared/assets/maps) and on a generated
5000 x 5000 map (the warehouse image tiled and cropped, same resolution and thresholds),
``--repeat`` runs each in a fresh process into an empty folder; prints the median wall time
and the largest peak resident memory (``os.wait4``'s ``ru_maxrss``) and the load average.
``python benchmarks/bench_world_process.py [--repeat 5] [--size 5000]``.
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
ASSETS = REPO.parent / "shared" / "assets"
if not ASSETS.is_dir():
    ASSETS = Path("/work/shared/assets")
WAREHOUSE = ASSETS / "maps" / "nav2_warehouse" / "warehouse.yaml"
ROBOTKIT = Path(sys.executable).parent / "robotkit"


def big_map(folder: Path, size: int) -> Path:
    """Written by a child process: this one stays small, since a child's ``ru_maxrss`` starts
    from the size of the process that started it (81 MB reported for the warehouse before)."""
    code = ("import sys; from pathlib import Path; sys.path.insert(0, sys.argv[1]); "
            "import bench_world_process as b; b.write_big_map(Path(sys.argv[2]), int(sys.argv[3]))")
    subprocess.run([sys.executable, "-c", code, str(Path(__file__).parent), str(folder), str(size)], check=True)
    return folder / "big.yaml"


def write_big_map(folder: Path, size: int) -> Path:
    import numpy as np
    from PIL import Image

    img = np.asarray(Image.open(WAREHOUSE.parent / "warehouse.pgm"))
    reps = (size // img.shape[0] + 1, size // img.shape[1] + 1)
    tiled = np.tile(img, reps)[:size, :size]
    Image.fromarray(tiled).save(folder / "big.pgm")
    text = WAREHOUSE.read_text().replace("warehouse.pgm", "big.pgm")
    (folder / "big.yaml").write_text(text)
    return folder / "big.yaml"


def run(map_yaml: Path, out: Path, checkout: Path = REPO) -> tuple[float, float, float]:
    """(wall s, peak MB, CPU s) of one ``robotkit world`` process running ``checkout``'s code."""
    if out.exists():
        shutil.rmtree(out)
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    t0 = time.perf_counter()
    p = subprocess.Popen([str(ROBOTKIT), "world", str(map_yaml), "--out", str(out)],
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    _, status, usage = os.wait4(p.pid, 0)
    dt = time.perf_counter() - t0
    if status != 0:
        raise SystemExit(f"robotkit world {map_yaml} failed: {p.stderr.read().decode()}")
    return dt, usage.ru_maxrss / 1024.0, usage.ru_utime + usage.ru_stime  # MB


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--size", type=int, default=5000)
    ap.add_argument("--checkout", type=Path, help="another robotkit checkout to time beside this one, interleaved")
    args = ap.parse_args()
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start; median of {args.repeat}")
    with tempfile.TemporaryDirectory(prefix="bench_world.") as tmp:
        tmp = Path(tmp)
        maps = {"nav2 warehouse 1006 x 1674": WAREHOUSE, f"tiled {args.size} x {args.size}": big_map(tmp, args.size)}
        checkouts = [("this", REPO)] + ([("other", args.checkout.resolve())] if args.checkout else [])
        runs = [(k, c) for k in maps for c in checkouts]
        times = {r: [] for r in runs}
        cpu = {r: [] for r in runs}
        mem = {r: 0.0 for r in runs}
        for _ in range(args.repeat):
            for k, (name, checkout) in runs:
                dt, mb, used = run(maps[k], tmp / "out", checkout)
                times[k, (name, checkout)].append(dt)
                cpu[k, (name, checkout)].append(used)
                mem[k, (name, checkout)] = max(mem[k, (name, checkout)], mb)
        for r in runs:
            print(f"  {r[0]:28} {r[1][0]:5} {statistics.median(times[r]):6.2f} s  CPU "
                  f"{statistics.median(cpu[r]):6.2f} s  peak {mem[r]:6.0f} MB")
    print(f"load average {os.getloadavg()[0]:.1f} at the end")
    return 0


if __name__ == "__main__":
    sys.exit(main())
