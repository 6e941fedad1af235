"""Mesh benchmarks: robotkit against pymeshlab, side by side in one run.

    pip install pymeshlab        # for this benchmark only: not a dependency of robotkit or its tests
    python benchmarks/bench_mesh.py [--quick] [--json out.json]

(a) Volume, centre of mass and inertia: ``robotkit.mesh.inertia.mesh_mass_properties``
    against pymeshlab's ``get_geometric_measures`` (both at unit density, about the
    centre of mass), on a 500k-face torus and on the real meshes in ../shared/assets
    (UR5 visual DAEs in metres, TurtleBot3 STLs in millimetres, scaled to metres).
    Agreement: relative volume difference, COM difference over the bounding-box
    diagonal, largest inertia difference over the largest inertia term.
(b) Quadric decimation: ``robotkit.mesh.decimate.decimate`` (MeshLib)
    against pymeshlab's ``meshing_decimation_quadric_edge_collapse`` (defaults), 500k ->
    50k faces on the torus and to 10 % on the real meshes: time, volume change, and the
    sampled surface distance of each result to the original (the same measure for both).

Times are the minimum over repeats (the machine is shared; the minimum is the least
disturbed run), inputs prepared outside the timed region for both tools: arrays for
robotkit, a loaded MeshSet for pymeshlab.  ``decimate(..., samples=0)`` is timed (the
simplification plus its face/volume report); the surface-distance report costs extra and
is timed separately.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
ASSETS = REPO.parent / "shared" / "assets"

UR5 = ["base", "shoulder", "upperarm", "forearm", "wrist1", "wrist2", "wrist3"]
TB3 = ["bases/burger_base.stl", "wheels/left_tire.stl", "sensors/lds.stl"]


def best_time(fn, repeats: int) -> tuple[float, object]:
    out, best = None, float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def meshes(quick: bool):
    import trimesh

    from robotkit.mesh.io import load_mesh

    sections = 250 if quick else 500
    torus = trimesh.creation.torus(major_radius=0.1, minor_radius=0.03,
                                   major_sections=sections, minor_sections=sections)
    yield f"torus {len(torus.faces) // 1000}k", torus
    for name in UR5:
        yield f"UR5 {name}.dae", load_mesh(str(ASSETS / "ur_description/meshes/ur5/visual" / f"{name}.dae"))
    for rel in TB3:
        yield f"TB3 {Path(rel).name} (mm)", load_mesh(str(ASSETS / "turtlebot3_description/meshes" / rel),
                                                      (0.001, 0.001, 0.001))


def pml_meshset(pymeshlab, V, F):
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(V, dtype=np.float64),
                               face_matrix=np.asarray(F, dtype=np.int32)))
    return ms


def bench_mass(pymeshlab, name, mesh, repeats):
    from robotkit.mesh.inertia import mesh_mass_properties

    V = np.array(mesh.vertices, dtype=np.float64)
    F = np.array(mesh.faces, dtype=np.int64)
    ms = pml_meshset(pymeshlab, V, F)
    t_ours, ours = best_time(lambda: mesh_mass_properties(V, F), repeats)
    t_pml, pml = best_time(lambda: ms.get_geometric_measures(), repeats)
    t_tm, _ = best_time(lambda: mesh.copy().mass_properties, max(1, repeats // 2))
    row = {"mesh": name, "faces": int(len(F)), "closed": bool(mesh.is_volume),
           "t_ours": t_ours, "t_pymeshlab": t_pml, "t_trimesh": t_tm, "speedup": t_pml / t_ours}
    if "mesh_volume" in pml:
        diag = float(np.linalg.norm(np.ptp(V, axis=0)))
        I = np.asarray(pml["inertia_tensor"], dtype=np.float64)
        row.update(
            volume=ours.volume,
            vol_rel=abs(ours.volume - pml["mesh_volume"]) / abs(pml["mesh_volume"]),
            com_rel=float(np.abs(ours.com - np.asarray(pml["center_of_mass"])).max() / diag),
            inertia_rel=float(np.abs(ours.inertia - I).max() / np.abs(I).max()))
    else:
        row.update(volume=None, vol_rel=None, com_rel=None, inertia_rel=None)
    return row


def bench_decimate(pymeshlab, name, mesh, target, repeats):
    import trimesh

    from robotkit.mesh.decimate import closed_volume, decimate, surface_distance

    from robotkit.mesh.decimate import NORMALISED_DIAGONAL, _decimate_core

    t_ours, (out, rep) = best_time(lambda: decimate(mesh, target_faces=target, samples=0), repeats)
    t_dist, dist = best_time(lambda: surface_distance(mesh, out), 1)
    V, F = np.array(mesh.vertices), np.array(mesh.faces)
    # the simplification alone, on the same normalised arrays decimate() passes it
    Vn = (V - 0.5 * (V.min(axis=0) + V.max(axis=0))) * (NORMALISED_DIAGONAL / np.linalg.norm(np.ptp(V, axis=0)))
    closed = bool(rep["is_volume_before"])
    t_core, _ = best_time(lambda: _decimate_core(Vn, F, int(target), closed), repeats)

    def run_pml():
        ms = pml_meshset(pymeshlab, V, F)  # decimation works in place: a fresh copy each run
        t0 = time.perf_counter()
        ms.meshing_decimation_quadric_edge_collapse(targetfacenum=int(target))
        dt = time.perf_counter() - t0
        m = ms.current_mesh()
        return dt, trimesh.Trimesh(m.vertex_matrix(), m.face_matrix(), process=False)

    runs = [run_pml() for _ in range(repeats)]
    t_pml = min(r[0] for r in runs)
    pml_out = runs[-1][1]
    vol = closed_volume(mesh)

    def change(m):
        after = closed_volume(m)
        return after / vol - 1.0 if vol and after else None

    return {"mesh": name, "faces": int(len(F)), "target": int(target),
            "faces_ours": rep["faces_after"], "faces_pymeshlab": int(len(pml_out.faces)),
            "t_ours": t_ours, "t_ours_core": t_core, "t_pymeshlab": t_pml, "speedup": t_pml / t_ours,
            "speedup_core": t_pml / t_core, "t_distance_report": t_dist,
            "vol_change_ours": change(out), "vol_change_pymeshlab": change(pml_out),
            "dist_max_ours": dist["max"], "dist_mean_ours": dist["mean"],
            "dist_max_pymeshlab": surface_distance(mesh, pml_out)["max"],
            "diag": float(np.linalg.norm(np.ptp(V, axis=0)))}


def fmt(v, spec):
    return "-" if v is None else format(v, spec)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="125k-face torus, fewer repeats")
    parser.add_argument("--json", help="also write the results to this JSON file")
    args = parser.parse_args(argv)
    try:
        import pymeshlab
    except ImportError:
        print("bench_mesh.py compares against pymeshlab, which is not installed.\n"
              "Install it for the benchmark only:  pip install pymeshlab\n"
              "(it is not a dependency of robotkit or of its tests)", file=sys.stderr)
        return 2
    if not ASSETS.is_dir():
        print(f"test assets not found at {ASSETS}", file=sys.stderr)
        return 2
    from importlib import metadata

    versions = {p: metadata.version(p) for p in ("numpy", "trimesh", "meshlib", "pymeshlab")}
    cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name")),
               platform.processor()) if os.path.exists("/proc/cpuinfo") else platform.processor()
    print(f"# {time.strftime('%Y-%m-%d')}  {cpu}, {os.cpu_count()} cores, Python {platform.python_version()}")
    print("# " + ", ".join(f"{k} {v}" for k, v in versions.items()))

    mass, deci = [], []
    for name, mesh in meshes(args.quick):
        big = len(mesh.faces) > 100_000
        mass.append(bench_mass(pymeshlab, name, mesh, 5 if big else 9))
        target = 50_000 if big and not args.quick else max(len(mesh.faces) // 10, 4)
        deci.append(bench_decimate(pymeshlab, name, mesh, target, 2 if big else 5))

    print("\n(a) volume, centre of mass, inertia: robotkit mesh_mass_properties vs pymeshlab get_geometric_measures")
    print(f"{'mesh':26s} {'faces':>7s} {'closed':>6s} {'ours ms':>8s} {'pml ms':>8s} {'trimesh ms':>10s} "
          f"{'pml/ours':>8s} {'vol rel':>8s} {'com rel':>8s} {'I rel':>8s}")
    for r in mass:
        print(f"{r['mesh']:26s} {r['faces']:7d} {str(r['closed']):>6s} {r['t_ours'] * 1e3:8.2f} "
              f"{r['t_pymeshlab'] * 1e3:8.2f} {r['t_trimesh'] * 1e3:10.2f} {r['speedup']:7.1f}x "
              f"{fmt(r['vol_rel'], '8.1e')} {fmt(r['com_rel'], '8.1e')} {fmt(r['inertia_rel'], '8.1e')}")
    print("\n(b) quadric decimation: robotkit decimate (MeshLib) vs pymeshlab quadric edge collapse")
    print("    ours = decimate(samples=0) with its face and volume report; core = the simplification alone (meshoptimizer pass + MeshLib)")
    print(f"{'mesh':26s} {'faces':>7s} {'target':>7s} {'got':>6s} {'pml got':>7s} {'ours s':>7s} {'core s':>7s} "
          f"{'pml s':>7s} {'pml/ours':>8s} {'pml/core':>8s} "
          f"{'dvol ours':>10s} {'dvol pml':>10s} {'dmax/diag ours':>14s} {'pml':>8s} {'dist s':>7s}")
    for r in deci:
        print(f"{r['mesh']:26s} {r['faces']:7d} {r['target']:7d} {r['faces_ours']:6d} {r['faces_pymeshlab']:7d} "
              f"{r['t_ours']:7.3f} {r['t_ours_core']:7.3f} {r['t_pymeshlab']:7.3f} "
              f"{r['speedup']:7.1f}x {r['speedup_core']:7.1f}x "
              f"{fmt(r['vol_change_ours'], '10.1e')} {fmt(r['vol_change_pymeshlab'], '10.1e')} "
              f"{r['dist_max_ours'] / r['diag']:14.1e} {r['dist_max_pymeshlab'] / r['diag']:8.1e} "
              f"{r['t_distance_report']:7.3f}")
    if args.json:
        Path(args.json).write_text(json.dumps({"mass": mass, "decimate": deci, "versions": versions,
                                               "cpu": cpu, "cores": os.cpu_count()}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
