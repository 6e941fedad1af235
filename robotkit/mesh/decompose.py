"""Approximate convex decomposition with CoACD.

CoACD (``coacd.run_coacd``) is called with its console output switched off
(``coacd.set_log_level("off")``: its C++ logger writes about 2 KB per call
to file descriptor 1, which ``contextlib.redirect_stdout`` cannot catch).
The same input, parameters and ``seed`` give the same pieces, whatever the
number of OpenMP threads (docs/libraries.md, section 5).

Each piece CoACD returns is replaced by its convex hull
(:func:`robotkit.mesh.hull.convex_hull`: closed, outward, canonical order)
with at most ``max_hull_vertices`` vertices, by the hull module's greedy
farthest-point method.  CoACD's own budget (``decimate=True,
max_ch_vertex=n``) is not used: on the L-shaped test mesh it cut a
10-vertex piece to 8 vertices and to 56 % of its volume, where the hull
module keeps 96 %.  Pieces are returned in a canonical order (by centroid), so the list
is reproducible.

Run time depends on the shape more than on the face count: 0.4 s for the
512-face L-shape, but with the defaults (threshold 0.05, no hull limit) 7 s
and 3 pieces for the UR5 forearm (21k faces), 74 s and 32 pieces for the UR5
wrist3 (1.7k faces), 209 s and 184 pieces for the TurtleBot3 LDS (13k faces)
on 2 cores.  Limit ``max_hulls``, raise ``threshold`` for detailed parts, and
cache the result (:mod:`robotkit.mesh.cache`).  A closed mesh made of
overlapping bodies is decomposed as the union of its bodies, without CoACD's
voxel remeshing (:func:`coacd_input`): 3-5 times faster on the UR5's parts,
with pieces as close or closer (docs/performance.md).
"""

from __future__ import annotations

import numpy as np
import trimesh

from robotkit.mesh.decimate import closed_volume, decimate
from robotkit.mesh.hull import convex_hull

PREPROCESS = ("auto", "on", "off")
INPUT_FACES = 20_000  # ``auto``: a larger closed input is decimated to this many faces for CoACD


def decompose(mesh, threshold: float = 0.05, max_hulls: int = -1, resolution: int = 2000,
              preprocess: str = "auto", preprocess_resolution: int = 50, seed: int = 0,
              max_hull_vertices: int | None = None, *, mcts_iterations: int = 150, mcts_nodes: int = 20,
              mcts_max_depth: int = 3, input_faces: int = INPUT_FACES) -> list[trimesh.Trimesh]:
    """Split ``mesh`` into convex pieces with CoACD.

    ``threshold``: CoACD's concavity threshold (0.01-1, smaller = more, finer
    pieces); ``max_hulls``: upper bound on the number of pieces (-1: none);
    ``resolution``: CoACD's sampling resolution; ``preprocess``: ``auto``
    (a closed mesh: the union of its bodies, no remeshing; otherwise CoACD's
    remesh when the input is not a 2-manifold; see :func:`coacd_input`), ``on`` or ``off``;
    ``preprocess_resolution``: voxel resolution of that remeshing; ``seed``:
    CoACD's random seed; ``max_hull_vertices``: vertex budget per piece (>= 4);
    ``mcts_iterations``, ``mcts_nodes``, ``mcts_max_depth``: CoACD's cutting-plane
    search (fewer iterations = faster, coarser; scikit-robot's "balanced" preset
    uses threshold 0.2, at most 6 hulls and 30 iterations).  ``input_faces``: with
    ``preprocess='auto'``, a closed input of more faces is decimated to this many
    first (:func:`coacd_input`; 0: never).

    Raises ValueError for invalid parameters or an empty or flat mesh, and
    RuntimeError when CoACD fails or returns nothing usable.
    """
    _check(threshold, max_hulls, resolution, preprocess, preprocess_resolution, seed, max_hull_vertices,
           mcts_iterations, mcts_nodes, mcts_max_depth, input_faces)
    V = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
    F = np.ascontiguousarray(mesh.faces, dtype=np.int32)
    if len(F) == 0:
        raise ValueError("cannot decompose an empty mesh")
    if not np.isfinite(V).all():
        raise ValueError("cannot decompose a mesh with non-finite vertices")
    extent = float(np.ptp(V, axis=0).min())
    if extent <= 1e-9 * max(float(np.ptp(V, axis=0).max()), 1e-300):
        raise ValueError("cannot decompose a flat mesh (it has no volume)")

    import coacd

    V, F, mode = coacd_input(V, F, preprocess, input_faces)
    coacd.set_log_level("off")
    budget = int(max_hull_vertices) if max_hull_vertices is not None else None
    try:
        parts = coacd.run_coacd(
            coacd.Mesh(V, F), threshold=float(threshold), max_convex_hull=int(max_hulls),
            preprocess_mode=mode, preprocess_resolution=int(preprocess_resolution),
            resolution=int(resolution), seed=int(seed), decimate=False, mcts_iterations=int(mcts_iterations),
            mcts_nodes=int(mcts_nodes), mcts_max_depth=int(mcts_max_depth))
    except Exception as exc:  # the ctypes wrapper raises plain exceptions or asserts
        raise RuntimeError(f"CoACD failed: {type(exc).__name__}: {exc}") from exc
    pieces = []
    for verts, _faces in parts:
        verts = np.asarray(verts, dtype=np.float64)
        if len(verts) < 4 or not np.isfinite(verts).all():
            continue
        try:
            pieces.append(convex_hull(trimesh.Trimesh(verts, np.zeros((0, 3), dtype=np.int64), process=False),
                                      max_vertices=budget))
        except ValueError:  # a flat sliver: no volume, nothing to collide with
            continue
    if not pieces:
        raise RuntimeError(f"CoACD returned no usable convex piece ({len(parts)} pieces, all empty or flat)")
    keys = np.array([np.append(p.vertices.mean(axis=0), p.volume) for p in pieces])
    order = np.lexsort(keys.T[::-1])
    return [pieces[i] for i in order]


def coacd_input(V: np.ndarray, F: np.ndarray, preprocess: str,
                input_faces: int = INPUT_FACES) -> tuple[np.ndarray, np.ndarray, str]:
    """The mesh CoACD gets and its ``preprocess_mode``: (vertices, faces, mode).

    ``auto``: a closed mesh whose bodies overlap (CAD exports often are several
    closed bodies pushed into each other) is replaced by the union of its bodies
    (manifold3d's exact boolean union, float64), and CoACD runs with its
    preprocessing off.  CoACD's own ``auto`` finds such a mesh "not manifold"
    (its triangles intersect) and remeshes it on a voxel grid: the UR5's
    500-1,200-face collision parts became 64,000-104,000 triangles, which made
    CoACD 3-5 times slower and the pieces no closer (docs/performance.md).  A
    mesh manifold3d does not take as a closed volume keeps CoACD's ``auto``.
    CoACD's time grows with the faces it cuts (a 100,000-face torus: 15 s; decimated to
    20,000 faces: 4.4 s, 1 % more volume), so a union of more than ``input_faces`` faces
    is decimated to that many first (MeshLib, :func:`robotkit.mesh.decimate.decimate`;
    kept only if it is still a closed volume).
    ``on`` and ``off`` pass the mesh unchanged with CoACD's meaning.
    """
    if preprocess != "auto":
        return V, F, preprocess
    import manifold3d as m3

    whole = m3.Manifold(m3.Mesh64(vert_properties=np.array(V, dtype=np.float64), tri_verts=np.array(F, dtype=np.uint64)))
    if whole.status() != m3.Error.NoError or whole.is_empty():
        return V, F, "auto"
    bodies = whole.decompose()
    union = m3.Manifold.batch_boolean(bodies, m3.OpType.Add) if len(bodies) > 1 else whole
    if union.status() != m3.Error.NoError or union.is_empty():
        return V, F, "auto"
    mesh = union.to_mesh64()
    V = np.ascontiguousarray(np.asarray(mesh.vert_properties)[:, :3], dtype=np.float64)
    F = np.ascontiguousarray(mesh.tri_verts, dtype=np.int32)
    if input_faces and len(F) > input_faces:
        fewer, _ = decimate(trimesh.Trimesh(V, F, process=False), target_faces=int(input_faces), samples=0)
        if closed_volume(fewer) is not None:
            V = np.ascontiguousarray(fewer.vertices, dtype=np.float64)
            F = np.ascontiguousarray(fewer.faces, dtype=np.int32)
    return V, F, "off"


def _check(threshold, max_hulls, resolution, preprocess, preprocess_resolution, seed, max_hull_vertices,
           mcts_iterations=150, mcts_nodes=20, mcts_max_depth=3, input_faces=INPUT_FACES):
    def whole(name, v, low):
        if isinstance(v, bool) or not float(v).is_integer() or int(v) < low:
            raise ValueError(f"{name} must be a whole number >= {low}, got {v!r}")

    if not 0.01 <= float(threshold) <= 1.0:
        raise ValueError(f"threshold must be between 0.01 and 1, got {threshold!r}")
    if int(max_hulls) != -1:
        whole("max_hulls", max_hulls, 1)
    whole("resolution", resolution, 20)
    whole("preprocess_resolution", preprocess_resolution, 20)
    whole("seed", seed, 0)
    if preprocess not in PREPROCESS:
        raise ValueError(f"preprocess must be one of {', '.join(PREPROCESS)}, got {preprocess!r}")
    if max_hull_vertices is not None:
        whole("max_hull_vertices", max_hull_vertices, 4)
    whole("mcts_iterations", mcts_iterations, 1)
    whole("mcts_nodes", mcts_nodes, 1)
    whole("mcts_max_depth", mcts_max_depth, 1)
    whole("input_faces", input_faces, 0)
