"""Walls from an occupancy map: robotkit's mesher against one box per occupied cell.

One box per occupied cell is map2gazebo's method (it extrudes a 12-triangle box per
contour pixel); it is reimplemented here in two ways: vectorised with numpy (the fastest
way to do it, so the fairest time to compare with) and as map2gazebo writes it, one
``trimesh.creation.box`` per cell joined with ``trimesh.util.concatenate``.

Usage (from the repository root, with ../shared beside it):

    python benchmarks/bench_world.py [MAP.yaml] [--repeat N]

Times are the median of N runs (default 5) of the mesher alone, on a map already loaded;
the map reading and the whole `build_world` (all five files written) are timed once each.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh

from robotkit.world import build_world, load_map, wall_mesh

REPO = Path(__file__).resolve().parents[1]
DEFAULT_MAP = REPO.parent / "shared" / "assets" / "maps" / "nav2_warehouse" / "warehouse.yaml"


def boxes_vectorised(om, height: float) -> trimesh.Trimesh:
    """One closed 12-triangle box per occupied cell, all in one array (map frame, yaw applied)."""
    rows, cols = np.nonzero(om.occupied)
    unit = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    corners = np.asarray(unit.vertices) + 0.5  # [0, 1]^3
    gx = cols[:, None] + corners[None, :, 0]
    gy = (om.rows - 1 - rows)[:, None] + corners[None, :, 1]
    m = om.grid_to_map()
    x = m[0, 0] * gx + m[0, 1] * gy + m[0, 2]
    y = m[1, 0] * gx + m[1, 1] * gy + m[1, 2]
    z = np.broadcast_to(corners[None, :, 2] * height, x.shape)
    vertices = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    faces = (np.asarray(unit.faces)[None, :, :] + 8 * np.arange(len(rows))[:, None, None]).reshape(-1, 3)
    return trimesh.Trimesh(vertices=vertices, faces=faces, process=False)


def boxes_map2gazebo(om, height: float) -> trimesh.Trimesh:
    """As map2gazebo does it: a trimesh box per cell, then one concatenate."""
    rows, cols = np.nonzero(om.occupied)
    centres = om.cell_centres(rows, cols)
    yaw = om.origin[2]
    r = om.resolution
    meshes = []
    for (cx, cy) in centres:
        transform = trimesh.transformations.rotation_matrix(yaw, (0, 0, 1))
        transform[:3, 3] = (cx, cy, height / 2)
        meshes.append(trimesh.creation.box(extents=(r, r, height), transform=transform))
    return trimesh.util.concatenate(meshes)


def timed(fn, repeat: int):
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return result, statistics.median(times)


def internal_faces(mesh: trimesh.Trimesh, om, height: float) -> int:
    """Faces with wall on both sides: probe a little in front of and behind each face's centre."""
    c = mesh.triangles_center
    n = mesh.face_normals
    inv = np.linalg.inv(om.grid_to_map())
    walls = np.pad(om.occupied[::-1], 1)  # grid order, padded
    inside = []
    for sign in (1.0, -1.0):
        p = c + sign * 1e-3 * om.resolution * n
        gx = inv[0, 0] * p[:, 0] + inv[0, 1] * p[:, 1] + inv[0, 2]
        gy = inv[1, 0] * p[:, 0] + inv[1, 1] * p[:, 1] + inv[1, 2]
        i = np.clip(np.floor(gx).astype(np.int64) + 1, 0, walls.shape[1] - 1)
        j = np.clip(np.floor(gy).astype(np.int64) + 1, 0, walls.shape[0] - 1)
        inside.append(walls[j, i] & (p[:, 2] > 0) & (p[:, 2] < height))
    return int((inside[0] & inside[1]).sum())


def quality(mesh: trimesh.Trimesh, exact_volume: float) -> dict:
    """What a user gets after saving to STL and loading it back (vertices merged)."""
    m = trimesh.Trimesh(mesh.vertices, mesh.faces)  # merges vertices, as trimesh.load does
    sorted_faces = np.sort(m.faces, axis=1)
    _, counts = np.unique(sorted_faces, axis=0, return_counts=True)
    edges, edge_counts = np.unique(m.edges_sorted, axis=0, return_counts=True)
    return {
        "faces": len(mesh.faces),
        "duplicate faces": int((counts - 1).sum()),
        "non-manifold edges": int((edge_counts > 2).sum()),
        "watertight": m.is_watertight,
        "volume rel. error": abs(m.volume - exact_volume) / exact_volume,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("map", nargs="?", default=str(DEFAULT_MAP), help="map_server YAML (default: nav2 warehouse)")
    ap.add_argument("--repeat", type=int, default=5, help="runs per mesher; the median is reported")
    ap.add_argument("--height", type=float, default=2.0)
    ap.add_argument("--skip-loop", action="store_true", help="skip the slow per-cell map2gazebo loop")
    args = ap.parse_args(argv)

    start = time.perf_counter()
    om = load_map(args.map)
    t_load = time.perf_counter() - start
    n = int(om.occupied.sum())
    exact = n * om.resolution ** 2 * args.height
    print(f"map: {Path(args.map).name}, {om.cols} x {om.rows} px at {om.resolution} m, "
          f"{n} occupied cells; read in {t_load:.3f} s")

    ours, t_ours = timed(lambda: wall_mesh(om, args.height), args.repeat)
    boxes, t_boxes = timed(lambda: boxes_vectorised(om, args.height), args.repeat)
    rows = [("robotkit wall_mesh", ours, t_ours), ("one box per cell (numpy)", boxes, t_boxes)]
    if not args.skip_loop:
        loop, t_loop = timed(lambda: boxes_map2gazebo(om, args.height), 1)
        rows.append(("one box per cell (map2gazebo loop, 1 run)", loop, t_loop))

    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        build_world(args.map, tmp, height=args.height)
        t_build = time.perf_counter() - start

    header = (f"{'method':44} {'faces':>8} {'time s':>8} {'internal':>8} {'dup faces':>9} {'nonmanif':>8} "
              f"{'closed':>6} {'vol err':>8}")
    print(header)
    print("-" * len(header))
    for label, mesh, t in rows:
        q = quality(mesh, exact)
        print(f"{label:44} {q['faces']:>8} {t:>8.3f} {internal_faces(mesh, om, args.height):>8} "
              f"{q['duplicate faces']:>9} {q['non-manifold edges']:>8} "
              f"{str(q['watertight']):>6} {q['volume rel. error']:>8.1e}")
    print()
    print(f"faces: robotkit / boxes = {len(ours.faces) / len(boxes.faces):.4f} "
          f"(1 / {len(boxes.faces) / len(ours.faces):.1f}; target <= 0.1)")
    print(f"time:  robotkit / boxes (numpy) = {t_ours / t_boxes:.2f}; robotkit mesher {t_ours:.3f} s (target < 1 s)")
    if not args.skip_loop:
        print(f"time:  robotkit / boxes (map2gazebo loop) = {t_ours / t_loop:.4f}")
    print(f"build_world, all five files written: {t_build:.3f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
