"""Expansion cost: a 1000-link robot made of parts against the same robot written flat.

The robot: a body and 250 legs of 4 links each (a leg part with arguments, expressions and
units; 125 left legs and their 125 mirrored right legs), 1001 links and 1000 joints. The
flat recipe is what ``robotkit expand`` prints for it. Timed (median of N runs):

- load: read + expand + validate (robotkit.recipe.load.read_recipes);
- load + resolve: what every build does before doit looks at its database;
- no-op build: ``robotkit build`` with everything up to date (after one full build).

Usage (from the repository root):

    python benchmarks/bench_expand.py [--repeat N] [--legs N]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PART = """
parts:
  leg:
    args: {length: 10 cm, mass: 200 g}
    links:
      hip: {visual: {cylinder: {radius: 2 cm, length: 3 cm}, origin: {rpy: [90 deg, 0, 0]}}, inertial: {mass: "${mass}"}}
      thigh: {visual: {box: {size: [2 cm, 2 cm, "${length}"]}, origin: {xyz: [0, 0, "${-length / 2}"]}}}
      shin: {visual: {cylinder: {radius: 1 cm, length: "${length}"}, origin: {xyz: [0, 0, "${-length / 2}"]}}}
      foot: {visual: {sphere: {radius: 1.5 cm}}, inertial: {mass: 50 g}}
    joints:
      hip: {type: revolute, parent: "${parent}", child: hip, axis: [1, 0, 0], limit: {lower: -30 deg, upper: 45 deg, effort: 5, velocity: 5}}
      pitch: {type: revolute, parent: hip, child: thigh, origin: {xyz: [0, 2 cm, 0]}, axis: [0, 1, 0], limit: {lower: -90 deg, upper: 90 deg, effort: 5, velocity: 5}}
      knee: {type: revolute, parent: thigh, child: shin, origin: {xyz: [0, 0, "${-length}"]}, axis: [0, 1, 0], limit: {lower: -150 deg, upper: 0, effort: 5, velocity: 5}}
      ankle: {type: fixed, parent: shin, child: foot, origin: {xyz: [0, 0, "${-length}"]}}
"""


def recipe_text(pairs: int) -> str:
    lines = ["robot: centipede", "density: 800", "links:",
             f"  body: {{visual: {{box: {{size: [{pairs * 0.08:.2f}, 0.1, 0.05]}}}}}}", PART.strip(), "instances:"]
    for i in range(pairs):
        x = f"{i * 8} cm"
        args = f"{{length: {10 + i % 5} cm}}"
        lines.append(f"  l{i}: {{part: leg, parent: body, origin: {{xyz: [{x}, 5 cm, 0]}}, args: {args}}}")
        lines.append(f"  r{i}: {{part: leg, parent: body, origin: {{xyz: [{x}, 5 cm, 0]}}, args: {args}, mirror: xz}}")
    return "\n".join(lines) + "\n"


def median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--legs", type=int, default=250)
    args = ap.parse_args()
    from robotkit.recipe.load import read_recipes
    from robotkit.model.load import load_robots

    tmp = Path(tempfile.mkdtemp(prefix="bench-expand-"))
    parts = tmp / "parts.yaml"
    parts.write_text(recipe_text(args.legs // 2), encoding="utf-8")
    flat_text = subprocess.run([sys.executable, "-m", "robotkit", "expand", str(parts)], capture_output=True,
                               text=True, check=True).stdout
    flat = tmp / "flat.yaml"
    flat.write_text(flat_text, encoding="utf-8")
    loaded = read_recipes(parts)[0]
    assert not loaded.problems, loaded.problems
    n_links = len(loaded.recipe.links)
    print(f"robot: {n_links} links, {len(loaded.recipe.joints)} joints; recipe {parts.read_text().count(chr(10))} "
          f"lines, flat recipe {flat_text.count(chr(10))} lines")
    rows = []
    for name, path in (("parts", parts), ("flat", flat)):
        load = median_time(lambda: read_recipes(path), args.repeat)
        resolve = median_time(lambda: load_robots([path]), args.repeat)
        out = tmp / f"out-{name}"
        subprocess.run([sys.executable, "-m", "robotkit", "build", str(path), "--out", str(out)], check=True,
                       capture_output=True)

        def noop():
            proc = subprocess.run([sys.executable, "-m", "robotkit", "build", str(path), "--out", str(out)],
                                  check=True, capture_output=True, text=True)
            assert "up to date" in proc.stdout, proc.stdout

        rows.append((name, load, resolve, median_time(noop, args.repeat)))
    print(f"{'recipe':8} {'load':>9} {'load+resolve':>13} {'no-op build':>12}")
    for name, load, resolve, noop_time in rows:
        print(f"{name:8} {load:8.3f}s {resolve:12.3f}s {noop_time:11.3f}s")


if __name__ == "__main__":
    main()
