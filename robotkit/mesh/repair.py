"""Mesh repair that reports what it changed.

:func:`repair` works on a copy (the input is never modified) and only makes
changes that keep the shape: it drops faces on non-finite vertices, merges
coincident vertices, removes duplicate and degenerate faces, makes the
winding consistent, fills *small* holes, and turns every closed body outward.
The result keeps geometry only (visual data such as UVs and colours is not
carried over: repaired meshes feed mass properties and collision geometry,
visual meshes are copied verbatim).

Library parts and hand-written parts:

- merging, duplicate and degenerate faces: trimesh (``merge_vertices``,
  ``unique_faces``, ``nondegenerate_faces``); winding: trimesh's
  ``trimesh.repair.fix_winding`` result, face for face (:func:`fix_winding`: its
  breadth-first walk over the face adjacency, without its per-pair Python work);
- hole filling is hand-written: ``trimesh.repair.fill_holes`` fills every
  boundary cycle it finds (triangles and quads only unless ``use_fan``, and
  fans from a vertex, wrong for non-convex holes).  Here boundary loops are
  traced with their orientation, loops through a vertex shared by several
  loops are left alone, and only holes *small against the mesh* are closed: the
  patch's area at most :data:`MAX_HOLE_AREA` of the mesh's surface and the loop's
  perimeter at most twice the circumference of a circle of that area (a slit is
  not small), whatever their edge count; a triangle as it is, a quad split along
  its shorter diagonal, larger loops by a fan from a new vertex at the loop
  centroid.  ``hole_area`` and ``hole_volume_bound`` report how much was
  invented: the bound is the volume of a hemispherical dome over each patch of
  its area, what the missing surface could have enclosed;
- orientation is hand-written: ``trimesh.repair.fix_inversion(multibody=True)``
  makes every closed body's volume positive, which turns the inner shell of a
  hollow part (a cavity, correctly inward) outward and adds the cavity's volume
  instead of subtracting it.  Here a closed body lying entirely inside another
  closed body (winding-number test), and every open body, keeps the orientation
  most of its faces had in the input; every other closed body is made outward.
"""

from __future__ import annotations

import numpy as np
import trimesh

DEFAULT_MAX_HOLE_EDGES = None  # no limit: holes are judged by area and perimeter
MAX_HOLE_AREA = 0.1
"""Largest hole filled, as a fraction of the mesh's surface area."""


def repair(mesh, fill_holes: bool = True, *,
           max_hole_edges: int | None = DEFAULT_MAX_HOLE_EDGES) -> tuple[trimesh.Trimesh, dict]:
    """Return ``(repaired copy, report)``.

    Report keys (counts are ints): ``vertices_in``, ``faces_in``,
    ``nonfinite_faces_removed``, ``vertices_merged``, ``duplicate_faces_removed``,
    ``degenerate_faces_removed``, ``unreferenced_vertices_removed``,
    ``faces_flipped`` (input faces whose orientation changed),
    ``bodies_inverted`` (connected bodies turned around as a whole, after the
    winding fix: closed bodies made outward, other bodies back to the orientation
    most of their input faces had),
    ``nested_bodies`` (closed bodies inside another: cavities or embedded parts),
    ``holes_found``, ``holes_filled``, ``faces_added``, ``vertices_added``,
    ``holes_left`` (open loops too large against the mesh or ambiguous to fill),
    ``hole_area`` (m^2 of patches added), ``hole_volume_bound`` (m^3: how far the
    volume may be off if the missing surface was not flat),
    ``open_edges``, ``nonmanifold_edges``, ``vertices_out``, ``faces_out``,
    ``watertight``, ``winding_consistent``, ``is_volume`` (closed, consistently
    wound, positive volume: the mass properties can be trusted),
    ``volume`` (m^3, signed, None unless watertight) and ``changed`` (bool).
    """
    V = np.array(mesh.vertices, dtype=np.float64).reshape(-1, 3)
    F = np.array(mesh.faces, dtype=np.int64).reshape(-1, 3)
    report: dict = {"vertices_in": int(len(V)), "faces_in": int(len(F))}

    finite = np.isfinite(V).all(axis=1)
    keep = finite[F].all(axis=1) if len(F) else np.zeros(0, bool)
    report["nonfinite_faces_removed"] = int((~keep).sum())
    F = F[keep]
    V = np.where(finite[:, None], V, 0.0)

    m = trimesh.Trimesh(V, F, process=False, validate=False)
    n = len(m.vertices)
    m.merge_vertices(merge_tex=True, merge_norm=True)
    report["vertices_merged"] = n - len(m.vertices)

    n = len(m.faces)
    m.update_faces(m.unique_faces())
    report["duplicate_faces_removed"] = n - len(m.faces)
    n = len(m.faces)
    m.update_faces(m.nondegenerate_faces())
    report["degenerate_faces_removed"] = n - len(m.faces)
    n = len(m.vertices)
    m.remove_unreferenced_vertices()
    report["unreferenced_vertices_removed"] = n - len(m.vertices)

    before = np.array(m.faces)  # orientation reference for faces_flipped
    if len(m.faces) and not m.is_winding_consistent:
        fix_winding(m)

    holes = _fill_holes(m, (max_hole_edges or len(m.faces) * 3) if fill_holes else 0)
    report.update(holes)

    inverted, nested = _orient_bodies(m, before)
    report["bodies_inverted"] = inverted
    report["nested_bodies"] = nested
    report["faces_flipped"] = int(_flipped(before, np.asarray(m.faces)[:len(before)]).sum())

    open_edges, nonmanifold = _edge_counts(m)
    report.update(open_edges=open_edges, nonmanifold_edges=nonmanifold,
                  vertices_out=int(len(m.vertices)), faces_out=int(len(m.faces)),
                  watertight=bool(m.is_watertight), winding_consistent=bool(m.is_winding_consistent),
                  is_volume=bool(len(m.faces) > 0 and m.is_volume))
    report["volume"] = float(m.volume) if report["watertight"] else None
    report["changed"] = any(report[k] for k in (
        "nonfinite_faces_removed", "vertices_merged", "duplicate_faces_removed", "degenerate_faces_removed",
        "unreferenced_vertices_removed", "faces_flipped", "faces_added"))
    return m, report


def fix_winding(m) -> None:
    """``trimesh.repair.fix_winding(m)``, the same faces flipped, in place, at a fraction of its
    cost (it spends its time building a networkx graph and grouping the edges of each pair of
    faces it walks).

    trimesh walks each connected part of the face adjacency breadth-first (networkx's
    ``bfs_edges`` from the part's first node) and reverses a face reached from a neighbour whose
    shared edge runs the same way.  A face is reached once and its neighbour is final by then,
    so its flip is its neighbour's flip XOR whether the pair's *input* edges run the same way:
    the walk here is networkx's (:func:`_walk`), the same order, and the edge comparison one
    vectorised step.  A pair sharing other than exactly one edge (not after ``repair``'s unique
    and non-degenerate faces), or an adjacency listing a pair twice, goes to trimesh's own."""
    if m.is_winding_consistent:
        return
    faces = m.faces.view(np.ndarray)
    tree = _walk(np.asarray(m.face_adjacency, dtype=np.int64).reshape(-1, 2))
    if tree is None:
        trimesh.repair.fix_winding(m)
        return
    if len(tree) == 0:
        return
    parent, child = faces[tree[:, 0]], faces[tree[:, 1]]
    # directed edges (k, 3, 2) of each face: (v0, v1), (v1, v2), (v2, v0)
    pe = np.stack([parent, np.roll(parent, -1, axis=1)], axis=2)
    ce = np.stack([child, np.roll(child, -1, axis=1)], axis=2)
    same = (pe[:, :, None, :] == ce[:, None, :, :]).all(axis=3)  # a directed edge in both
    reverse = (pe[:, :, None, :] == ce[:, None, :, ::-1]).all(axis=3)  # an edge run both ways
    shared = same.sum(axis=(1, 2)) + reverse.sum(axis=(1, 2))
    if (shared != 1).any():
        trimesh.repair.fix_winding(m)
        return
    flips = [False] * len(faces)
    for (a, b), s in zip(tree.tolist(), same.any(axis=(1, 2)).tolist()):
        flips[b] = flips[a] ^ s
    flip = np.array(flips, dtype=bool)
    if flip.any():
        out = faces.copy()
        out[flip] = out[flip][:, ::-1]
        m.faces = out


def _walk(edges: np.ndarray) -> np.ndarray | None:
    """The (parent, child) pairs, in order, of trimesh's walk over the graph of ``edges`` (face
    pairs): ``nx.from_edgelist`` (nodes in order of first appearance, each one's neighbours in
    edge order), then for each of ``nx.connected_components`` (from each unseen node in graph
    order) ``nx.bfs_edges`` from the first node of its ``subgraph`` (the component's first node
    in graph order, or, for a component under half the graph, the first of networkx's set of its
    nodes, rebuilt here the same way).  None for an edge list networkx would merge (a pair twice,
    a loop): trimesh's own walk then."""
    if len(edges) == 0:
        return np.zeros((0, 2), dtype=np.int64)
    if (edges[:, 0] == edges[:, 1]).any() or len(np.unique(np.sort(edges, axis=1), axis=0)) != len(edges):
        return None
    n = int(edges.max()) + 1
    src = np.concatenate([edges[:, 0], edges[:, 1]])
    dst = np.concatenate([edges[:, 1], edges[:, 0]])
    order = np.lexsort((np.tile(np.arange(len(edges)), 2), src))
    starts = np.concatenate([[0], np.cumsum(np.bincount(src, minlength=n))]).tolist()
    neighbours = dst[order].tolist()
    flat = edges.ravel()
    nodes = flat[np.sort(np.unique(flat, return_index=True)[1])].tolist()
    mark = [0] * n  # the walk that reached each node (0: none yet)
    walks = [0]

    def bfs(source: int) -> list[tuple[int, int]]:
        walks[0] += 1
        stamp = walks[0]
        mark[source] = stamp
        out, queue, i = [], [source], 0
        while i < len(queue):
            parent = queue[i]
            i += 1
            for child in neighbours[starts[parent]:starts[parent + 1]]:
                if mark[child] != stamp:
                    mark[child] = stamp
                    queue.append(child)
                    out.append((parent, child))
        return out

    tree: list[tuple[int, int]] = []
    done = bytearray(n)
    for v in nodes:
        if done[v]:
            continue
        walk = bfs(v)
        component = [v] + [c for _, c in walk]
        for c in component:
            done[c] = 1
        if 2 * len(component) < len(nodes):  # networkx iterates its set of the subgraph's nodes
            members = set()
            for c in component:  # connected_components' set, filled in its order
                members.add(c)
            start = next(iter(set(c for c in members)))  # show_nodes' set, filled from that one
            if start != v:
                walk = bfs(start)
        tree += walk
    return np.array(tree, dtype=np.int64).reshape(-1, 2)


def _flipped(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """Per face: True if ``after`` is not a cyclic rotation of ``before`` (orientation reversed)."""
    same = np.zeros(len(before), dtype=bool)
    for k in range(3):
        same |= (np.roll(before, k, axis=1) == after).all(axis=1)
    return ~same


def _edge_counts(m) -> tuple[int, int]:
    if len(m.faces) == 0:
        return 0, 0
    counts = np.unique(trimesh.grouping.hashable_rows(m.edges_sorted), return_counts=True)[1]
    return int((counts == 1).sum()), int((counts > 2).sum())


def _fill_holes(m, max_edges: int) -> dict:
    """Close boundary loops of at most ``max_edges`` edges that are small against the mesh, in
    place; return counts."""
    out = {"holes_found": 0, "holes_filled": 0, "faces_added": 0, "vertices_added": 0, "holes_left": 0,
           "hole_area": 0.0, "hole_volume_bound": 0.0}
    if len(m.faces) == 0:
        return out
    edges = np.asarray(m.edges)  # directed, 3 per face, in face order
    single = trimesh.grouping.group_rows(np.sort(edges, axis=1), require_count=1)
    if len(single) == 0:
        return out
    out["holes_found"], loops = _boundary_loops(edges, single)
    V = np.asarray(m.vertices)
    new_faces, new_vertices = [], []
    max_area = MAX_HOLE_AREA * float(m.area)
    max_perimeter = 2 * 2 * np.sqrt(np.pi * max_area)  # twice a circle's of the largest area
    for loop in loops:
        if len(loop) > max_edges:
            continue
        patch, centre, area, perimeter = _patch(V, loop, len(V) + len(new_vertices))
        if area > max_area or perimeter > max_perimeter:  # not small against the mesh: left open
            continue
        if centre is not None:
            new_vertices.append(centre)
        new_faces += patch
        out["hole_area"] += area
        out["hole_volume_bound"] += 2 / 3 * area * np.sqrt(area / np.pi)  # a hemisphere of the patch's area
        out["holes_filled"] += 1
    out["holes_left"] = out["holes_found"] - out["holes_filled"]
    if new_faces:
        V2 = np.vstack([V] + ([np.array(new_vertices)] if new_vertices else []))
        F2 = np.vstack([np.asarray(m.faces), np.array(new_faces, dtype=np.int64)])
        m.vertices = V2
        m.faces = F2
        out["faces_added"] = len(new_faces)
        out["vertices_added"] = len(new_vertices)
    return out


def _boundary_loops(edges: np.ndarray, single: np.ndarray) -> tuple[int, list[list[int]]]:
    """(holes, loops): the number of holes (connected groups of boundary edges; loops sharing a
    vertex count as one) and the simple boundary loops, each walked against the direction of
    the faces around it.  A loop running into a pinched vertex is left out (left open)."""
    # a hole is walked against the direction of the faces around it: its edges are b -> a
    starts, ends = edges[single, 1], edges[single, 0]
    order = np.lexsort((ends, starts))
    starts, ends = starts[order], ends[order]
    uniq, first, count = np.unique(starts, return_index=True, return_counts=True)
    nxt = {int(s): int(ends[i]) for s, i, c in zip(uniq, first, count) if c == 1}
    pinched = {int(s) for s, c in zip(uniq, count) if c > 1}
    from scipy.sparse import coo_matrix  # late: scipy is slow to import and only a mesh with holes needs it
    from scipy.sparse.csgraph import connected_components

    bverts, bidx = np.unique(np.concatenate([starts, ends]), return_inverse=True)
    nb = len(bverts)
    graph = coo_matrix((np.ones(len(starts)), (bidx[:len(starts)], bidx[len(starts):])), shape=(nb, nb))
    holes = int(connected_components(graph, directed=True, connection="weak")[0])
    visited: set[int] = set()
    loops = []
    for s in uniq.tolist():
        if s in visited or s in pinched:
            continue
        loop, v = [], s
        while v not in visited and v in nxt:
            visited.add(v)
            loop.append(v)
            v = nxt[v]
        if v == s and len(loop) >= 3:  # else it ran into a pinched vertex: left open
            loops.append(loop)
    return holes, loops


def _patch(V: np.ndarray, loop: list[int], c: int):
    """(faces, new centre vertex or None, area, perimeter) of the patch closing ``loop``: the
    triangle itself, the shorter diagonal's pair of a quad, or a fan around the loop's centre
    (new vertex index ``c``)."""
    k = len(loop)
    centre = None
    if k == 3:
        patch = [loop]
    elif k == 4:
        a, b, c4, d = loop
        if np.linalg.norm(V[a] - V[c4]) <= np.linalg.norm(V[b] - V[d]):
            patch = [[a, b, c4], [a, c4, d]]
        else:
            patch = [[a, b, d], [b, c4, d]]
    else:
        centre = V[loop].mean(axis=0)
        patch = [[loop[i], loop[(i + 1) % k], c] for i in range(k)]
    if k > 4:  # the fan's triangles around the new centre vertex
        tri = np.stack([V[loop], V[np.roll(loop, -1)], np.broadcast_to(centre, (k, 3))], axis=1)
    else:
        tri = V[np.array(patch)]
    area = float(np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum() / 2)
    perimeter = float(np.linalg.norm(V[loop] - V[np.roll(loop, -1)], axis=1).sum())
    return patch, centre, area, perimeter


def _orient_bodies(m, before: np.ndarray) -> tuple[int, int]:
    """Make closed bodies outward (nested ones keep their input majority); return (inverted, nested)."""
    if len(m.faces) == 0:
        return 0, 0
    F = np.asarray(m.faces)
    nf = len(F)
    labels = trimesh.graph.connected_component_labels(m.face_adjacency, node_count=nf)
    nb = int(labels.max()) + 1
    # a body is closed when each of its edges is used by exactly two faces, in opposite directions
    edges = np.asarray(m.edges)
    face_of_edge = np.repeat(np.arange(nf), 3)
    _, inv, cnt = np.unique(trimesh.grouping.hashable_rows(np.sort(edges, axis=1)),
                            return_inverse=True, return_counts=True)
    bad_edge = cnt[inv] != 2
    _, inv, cnt = np.unique(trimesh.grouping.hashable_rows(edges), return_inverse=True, return_counts=True)
    bad_edge |= cnt[inv] != 1
    body_bad = np.zeros(nb, dtype=bool)
    body_bad[labels[face_of_edge[bad_edge]]] = True
    # signed volume per body about the mesh's bounding-box centre
    V = np.asarray(m.vertices)
    ref = 0.5 * (V.min(axis=0) + V.max(axis=0))
    tri = V[F] - ref
    six = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2]))
    vol = np.bincount(labels, weights=six, minlength=nb) / 6.0
    scale = float(np.abs(six).sum()) / 6.0 or 1.0
    closed = np.nonzero(~body_bad & (np.abs(vol) > 1e-12 * scale))[0]
    # input majority orientation of each body (before winding fixes): +1 kept, -1 flipped
    flipped = _flipped(before, F[:len(before)])
    votes = np.bincount(labels[:len(before)], weights=np.where(flipped, -1.0, 1.0), minlength=nb)
    nested = _nested(V, F, labels, closed, vol)
    flip_body = np.zeros(nb, dtype=bool)
    # open bodies, and closed bodies nested in another (cavities or embedded parts): keep what
    # most of their input faces said (the winding fix may have turned a whole body around)
    flip_body[votes < 0] = True
    for b in closed:
        if not nested[int(b)]:  # a free closed body: outward
            flip_body[b] = vol[b] < 0
    inverted = int(flip_body.sum())
    if inverted:
        fl = flip_body[labels]
        F2 = F.copy()
        F2[fl] = F2[fl][:, ::-1]
        m.faces = F2
    return inverted, int(sum(bool(nested[int(b)]) for b in closed))


def _nested(V, F, labels, closed, vol) -> dict:
    """For each closed body: is it entirely inside another closed body?"""
    nested = {int(b): False for b in closed}
    if len(closed) < 2:
        return nested
    fmin = V[F].min(axis=1)
    fmax = V[F].max(axis=1)
    nb = int(labels.max()) + 1
    lo = np.full((nb, 3), np.inf)
    hi = np.full((nb, 3), -np.inf)
    np.minimum.at(lo, labels, fmin)
    np.maximum.at(hi, labels, fmax)
    lo, hi = lo[closed], hi[closed]
    faces_of = None
    for a in range(0, len(closed), 512):
        inside = ((lo[a:a + 512, None] >= lo[None]) & (hi[a:a + 512, None] <= hi[None])).all(axis=2)
        inside[np.arange(len(inside)), np.arange(a, a + len(inside))] = False
        for i, j in zip(*np.nonzero(inside)):
            bi, bj = int(closed[a + i]), int(closed[j])
            if nested[bi]:
                continue
            if faces_of is None:
                order = np.argsort(labels, kind="stable")
                bounds = np.searchsorted(labels[order], np.arange(nb + 1))
                faces_of = (order, bounds)
            order, bounds = faces_of
            fi = F[order[bounds[bi]:bounds[bi + 1]]]
            fj = F[order[bounds[bj]:bounds[bj + 1]]]
            pts = V[np.unique(fi)]
            if len(pts) > 16:
                pts = pts[np.linspace(0, len(pts) - 1, 16).astype(int)]
            nested[bi] = _all_inside(pts, V[fj], np.sign(vol[bj]))
    return nested


def _all_inside(points: np.ndarray, triangles: np.ndarray, sign: float) -> bool:
    """Whether every point's winding number about ``triangles`` (times ``sign``) is above 1/2:
    point by point, up to the first that is not (most candidate pairs fail at their first point;
    each number is the one :func:`_winding_numbers` gives for all the points at once)."""
    return all(_winding_numbers(points[k:k + 1], triangles)[0] * sign > 0.5 for k in range(len(points)))


def _winding_numbers(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Generalised winding number of each point w.r.t. a closed triangle set (Van Oosterom-Strackee)."""
    out = np.zeros(len(points))
    for k, p in enumerate(points):
        a, b, c = (triangles[:, i] - p for i in range(3))
        la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
        num = np.einsum("ij,ij->i", a, np.cross(b, c))
        den = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", b, c) * la
               + np.einsum("ij,ij->i", c, a) * lb)
        out[k] = 2.0 * np.arctan2(num, den).sum() / (4.0 * np.pi)
    return out
