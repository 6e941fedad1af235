"""CoACD settings for the UR5 recipe: time and collision fidelity per link, before and after.

Every collision source of ``recipes/ur5.yaml`` (the seven closed low-poly STLs, repaired as the
build repairs them) is decomposed with each setting below through robotkit's own
``robotkit.mesh.decompose.decompose`` (64 vertices per piece, as the recipe), and measured with
robotkit's fidelity report (``robotkit.mesh.fidelity.fidelity``, 4,000 samples each way, the
report the build writes).  "before" is the recipe's setting as it was, with CoACD's own
``preprocess_mode='auto'`` (the overlapping bodies of these parts made CoACD remesh them on a
voxel grid); the others pass the union of the bodies (``coacd_input``) with the preprocessing off.

The fidelity target: over the robot, none of these may be worse than "before": the largest
surface distance of any link (over the part's diagonal), the largest and the mean volume ratio
(proxy / part), and the mean of the links' mean surface distances.

CPU time (user + system of this process, ``resource.getrusage``) is the figure to compare on a
shared machine; the wall time and the load average are printed beside it.  ``OMP_NUM_THREADS``
is set to 1 before CoACD loads, as in a build's worker processes.

``python benchmarks/bench_coacd.py [--only NAME ...] [--json out.json]``
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
LINKS = ("base", "shoulder", "upperarm", "forearm", "wrist1", "wrist2", "wrist3")
BEFORE = dict(threshold=0.08, max_hulls=6, resolution=1000, mcts_iterations=40)
SETTINGS = {
    "before": (BEFORE, False),
    "union": (BEFORE, True),
    "union, 20 iterations": ({**BEFORE, "mcts_iterations": 20}, True),
    "union, 20 iterations, resolution 500": ({**BEFORE, "mcts_iterations": 20, "resolution": 500}, True),
    "union, 10 iterations": ({**BEFORE, "mcts_iterations": 10}, True),
    "union, threshold 0.1, 20 iterations": ({**BEFORE, "threshold": 0.1, "mcts_iterations": 20}, True),
    "union, threshold 0.1, 15 iterations": ({**BEFORE, "threshold": 0.1, "mcts_iterations": 15}, True),
    "union, threshold 0.15, 20 iterations": ({**BEFORE, "threshold": 0.15, "mcts_iterations": 20}, True),
    "union, threshold 0.2, 20 iterations": ({**BEFORE, "threshold": 0.2, "mcts_iterations": 20}, True),
    "union, threshold 0.1, 20 iterations, resolution 500": ({**BEFORE, "threshold": 0.1, "mcts_iterations": 20,
                                                             "resolution": 500}, True),
}


def cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def run(name: str, params: dict, union: bool, meshes: dict) -> dict:
    import robotkit.mesh.decompose as dec
    from robotkit.mesh.fidelity import fidelity

    plain = dec.coacd_input
    if not union:  # the behaviour before: CoACD's own preprocessing decides
        dec.coacd_input = lambda V, F, preprocess: (V, F, preprocess)
    rows = []
    try:
        for link, mesh in meshes.items():
            w0, c0 = time.perf_counter(), cpu()
            pieces = dec.decompose(mesh, max_hull_vertices=64, **params)
            wall, used = time.perf_counter() - w0, cpu() - c0
            f = fidelity(mesh, pieces)
            rows.append({"link": link, "cpu": used, "wall": wall, "pieces": len(pieces),
                         "volume_ratio": f["volume_ratio"], "distance_relative": f["distance_relative"],
                         "distance_mean": f["distance"]["mean"]})
            print(f"  {link:9s} cpu {used:6.2f} s  wall {wall:6.2f} s  {len(pieces)} pieces  volume ratio "
                  f"{f['volume_ratio']:.4f}  max distance {f['distance_relative']:.4f}  mean distance "
                  f"{f['distance']['mean'] * 1000:.2f} mm", flush=True)
    finally:
        dec.coacd_input = plain
    n = len(rows)
    summary = {
        "setting": name, "params": params, "union": union,
        "cpu": sum(r["cpu"] for r in rows), "wall": sum(r["wall"] for r in rows),
        "slowest_link_cpu": max(r["cpu"] for r in rows),
        "worst_distance": max(r["distance_relative"] for r in rows),
        "worst_volume_ratio": max(r["volume_ratio"] for r in rows),
        "mean_volume_ratio": sum(r["volume_ratio"] for r in rows) / n,
        "mean_distance_mm": 1000 * sum(r["distance_mean"] for r in rows) / n,
        "load": os.getloadavg()[0], "links": rows,
    }
    return summary


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", help="settings to run (names as in the table)")
    ap.add_argument("--json", help="write every figure to this file")
    args = ap.parse_args()
    from robotkit.mesh.io import load_mesh
    from robotkit.mesh.repair import repair

    meshes = {link: repair(load_mesh(str(REPO / "recipes" / "meshes" / "ur5" / "collision" / f"{link}.stl")))[0]
              for link in LINKS}
    results = []
    for name, (params, union) in SETTINGS.items():
        if args.only and name not in args.only:
            continue
        print(f"{name}: {params}{' (union of bodies, preprocessing off)' if union else ''}", flush=True)
        results.append(run(name, params, union, meshes))
    keys = ("worst_distance", "worst_volume_ratio", "mean_volume_ratio", "mean_distance_mm")
    ref = next((r for r in results if r["setting"] == "before"), None)
    print("\n| setting | CPU (s) | slowest link CPU (s) | wall (s) | load | worst max distance | worst volume "
          "ratio | mean volume ratio | mean distance (mm) | target met |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for r in results:
        met = "" if ref is None else ("yes" if all(r[k] <= ref[k] for k in keys) else "no")
        print(f"| {r['setting']} | {r['cpu']:.1f} | {r['slowest_link_cpu']:.1f} | {r['wall']:.1f} | {r['load']:.1f} "
              f"| {r['worst_distance']:.4f} | {r['worst_volume_ratio']:.4f} | {r['mean_volume_ratio']:.4f} "
              f"| {r['mean_distance_mm']:.2f} | {met} |")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
