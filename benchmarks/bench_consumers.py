"""What the consumer checks cost: each program's reading of each example build, and the
whole `robotkit check` of a build folder, against the build itself (warm mesh cache).

    python benchmarks/bench_consumers.py [OUT]

Builds every recipe in recipes/ into OUT (default: a temporary folder), then times each
consumer (median of 3 readings, each in this process) and a whole `robotkit check` process."""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))


def main() -> None:
    from robotkit.pipeline.runner import build
    from robotkit.check.consumers import CONSUMERS, Build, read

    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp())
    names = sorted(p.stem for p in (REPO / "recipes").glob("*.yaml"))
    t = time.perf_counter()
    build([REPO / "recipes" / f"{n}.yaml" for n in names], out)
    print(f"build of {len(names)} examples (warm cache unless the first run): {time.perf_counter() - t:.2f} s")
    header = "| robot | " + " | ".join(CONSUMERS) + " | `robotkit check` (process) |"
    print(header)
    print("|" + "---|" * (len(CONSUMERS) + 2))
    for n in names:
        d = out / n
        base = "free" if "<freejoint" in (d / "mjcf" / f"{n}.xml").read_text() else "fixed"
        b = Build(n, d, d / "urdf" / f"{n}.urdf", d / "model.sdf", d / "mjcf" / f"{n}.xml", base)
        cells = []
        for c in CONSUMERS:
            times = []
            for _ in range(3):
                t = time.perf_counter()
                view = read(c, b)
                if view.poses is not None:
                    view.poses({})
                times.append(time.perf_counter() - t)
            cells.append(f"{statistics.median(times):.3f}")
        t = time.perf_counter()
        subprocess.run([sys.executable, "-m", "robotkit", "check", str(d)], capture_output=True, cwd=REPO)
        cells.append(f"{time.perf_counter() - t:.2f}")
        print(f"| {n} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
