"""Wall cells -> one closed, consistently oriented wall mesh, exact on the cell grid.

The construction works in *grid coordinates* (x = image column, y = image rows - image
row, in cells; grid point (0, 0) is the map origin) and only at the end maps the vertices
into the map frame (resolution, origin and yaw), so every step is exact:

1. The side walls are the outline of the wall region: on each grid line, the unit edges
   between a wall cell and a non-wall cell, merged into straight segments, each extruded
   into a quad that faces away from the wall.
2. The top and bottom are the region inside the outline loops, triangulated by
   manifold3d's polygon triangulator (which keeps every outline edge), one piece of wall
   (an outer loop and its holes) at a time, with any flat triangle it returns removed by
   an edge flip.  The result is checked (every cap triangle faces up, the caps add up to
   the wall area, every edge has exactly two faces); should a check fail, or a piece of
   wall have too many holes for the triangulator (:data:`MAX_HOLE_WORK`), the caps are
   built from rectangles instead: the wall
   cells merged into rectangles (:func:`rectangles`), each triangulated through every
   rectangle corner on its perimeter so that faces meet edge to edge (no T-junctions),
   with the side walls split at those corners too.

Two wall cells that touch only at a corner (a "pinch", common in scanned maps) would make
the vertical edge through that corner shared by four faces.  To keep every edge shared by
exactly two faces, even after the STL is reloaded and its vertices merged, the faces of
one of the two cells split that edge at half height with an extra vertex.

The mesh has no duplicate or internal faces, every edge has exactly two faces, and its
volume is exactly the wall area times the height.  :func:`rectangles` also gives the
MuJoCo collision boxes (MuJoCo collides with the convex hull of a mesh).
"""

from __future__ import annotations

import numpy as np

from robotkit.errors import MapError, Problem


# manifold3d's time on a piece of wall grows with its holes times its points (about 7e-9 s
# each: 31 s for the 16,632 holes in 227,238 points of a 600 x 600 map of 70 % noise); past
# this (0.35 s) the caps come from rectangles instead, whose time is linear (1 s there)
MAX_HOLE_WORK = 50_000_000


def grid_mask(walls_image: np.ndarray) -> np.ndarray:
    """Image-order mask (row 0 at the top) -> grid-order mask (row 0 at the bottom)."""
    return np.ascontiguousarray(walls_image[::-1, :], dtype=bool)


def _padded(mask: np.ndarray) -> np.ndarray:
    """``mask`` with a ring of False around it: shape (rows + 2, cols + 2), ``mask`` is its [1:-1, 1:-1]."""
    rows, cols = mask.shape
    g = np.zeros((rows + 2, cols + 2), dtype=bool)
    g[1:-1, 1:-1] = mask
    return g


def _row_transitions(g: np.ndarray):
    """Where the cells of a :func:`_padded` mask change along each row, row by row, left to right.

    Returns (row, x, start): grid row, grid x of the change (between cells x - 1 and x) and
    whether a run of wall cells starts there.  One comparison of the flat array with itself
    shifted by one: the zero columns keep the rows apart.
    """
    width = g.shape[1]
    flat = g.ravel()
    p = np.flatnonzero(flat[1:] != flat[:-1]) + 1  # the cell right of each change
    row, col = np.divmod(p, width)
    return row - 1, col - 1, flat[p] > 0


def _column_transitions(g: np.ndarray):
    """As :func:`_row_transitions` down the columns: (column, y, start), column by column, bottom to top."""
    width = g.shape[1]
    flat = g.ravel()
    p = np.flatnonzero(flat[width:] != flat[:-width]) + width  # the cell above each change
    row, col = np.divmod(p, width)
    # a stable sort on the column alone keeps each column bottom to top (radix sort for 16 bits)
    order = np.argsort(col.astype(np.uint16) if width <= 1 << 16 else col, kind="stable")
    return col[order] - 1, row[order] - 1, flat[p[order]] > 0


def _runs_merged(line: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """Runs from the changes along lines (``line``, ``pos``: line by line, in order along each),
    each merged with identical runs in the next lines: (n, 4) [start, line0, end, line1 + 1]."""
    # along a line a run starts and ends in turn
    ys, xs, xe = line[0::2], pos[0::2], pos[1::2]
    order = np.lexsort((ys, xe, xs))
    xs, xe, ys = xs[order], xe[order], ys[order]
    new = np.ones(len(xs), dtype=bool)
    new[1:] = (xs[1:] != xs[:-1]) | (xe[1:] != xe[:-1]) | (ys[1:] != ys[:-1] + 1)
    first = np.flatnonzero(new)
    last = np.r_[first[1:], len(xs)] - 1
    return np.stack([xs[first], ys[first], xe[first], ys[last] + 1], axis=1).astype(np.int64)


def rectangles(mask: np.ndarray, *, padded: np.ndarray | None = None) -> np.ndarray:
    """Disjoint rectangles covering the True cells of a grid-order ``mask`` exactly.

    Returns an int64 array (n, 4) of [x0, y0, x1, y1] (cells x0 <= x < x1, y0 <= y < y1),
    sorted by y0 then x0.  ``padded``: the mask with a ring of False around it, when the
    caller has it (:func:`padded_wall_cells`), saves a copy of the whole grid.
    """
    g = _padded(mask) if padded is None else padded
    by_rows = _runs_merged(*_row_transitions(g)[:2])
    by_cols = _runs_merged(*_column_transitions(g)[:2])[:, [1, 0, 3, 2]]
    rects = by_rows if len(by_rows) <= len(by_cols) else by_cols
    return rects[np.lexsort((rects[:, 0], rects[:, 1]))]


class _Grid:
    """The wall mask and what the outline needs from it.

    Only the points where the outline turns are kept (as coordinate lists), not whole
    arrays per grid point: a 5000 x 5000 map has 25 million grid points and a few hundred
    thousand turns.  The padded mask is only read while the turns are found.
    """

    def __init__(self, mask: np.ndarray, padded: np.ndarray | None = None):
        self.mask = mask
        self.rows, self.cols = mask.shape
        g = _padded(mask) if padded is None else padded
        # The outline changes direction at a grid point (y, x) where one or three of the four
        # cells around it are walls, or at a pinch (two walls touching at a corner): where the
        # row below (y - 1) changes at x and the row above (y) does not, or the other way
        # round, or both change the other way.  So the turns come from the changes along the
        # rows (a few hundred thousand on a 5000 x 5000 map) rather than from whole-grid arrays.
        self.trans_row, self.trans_x, self.trans_start = row, x, start = _row_transitions(g)
        width = self.cols + 1
        key = row * width + x
        self.trans_keys = key  # sorted: row by row, left to right
        # each change as seen from the grid line below its row and from the one above it, with
        # its kind; a change seen from both sides with the same kind is a straight wall face
        seen = np.concatenate([2 * key + start, 2 * (key + width) + start])
        seen.sort(kind="stable")  # two sorted runs: a merge
        same = seen[1:] == seen[:-1]
        drop = np.zeros(len(seen), dtype=bool)
        drop[1:] = same
        drop[:-1] |= same
        point = seen[~drop] >> 1
        twice = point[1:] == point[:-1]  # both changes, of opposite kinds: a pinch
        keys = point[np.r_[True, ~twice]]
        self.turn_y, self.turn_x = np.divmod(keys, width)  # row-major order
        self._pinch_keys = point[1:][twice]  # sorted
        self.pinch_y, self.pinch_x = np.divmod(self._pinch_keys, width)
        # whether the south-west cell is a wall (else the north-west and south-east ones are)
        self._pinch_ne_sw = self.cell(self.pinch_y - 1, self.pinch_x - 1) > 0

    def cell(self, y: np.ndarray, x: np.ndarray) -> np.ndarray:
        """The mask at the cells (row y, column x) as int8, 0 outside the grid."""
        inside = (y >= 0) & (y < self.rows) & (x >= 0) & (x < self.cols)
        out = np.zeros(len(y), dtype=np.int8)
        out[inside] = self.mask[y[inside], x[inside]]
        return out

    def pinch_index(self, y: np.ndarray, x: np.ndarray, ne_sw: bool | None = None) -> np.ndarray:
        """The index of the pinch at each grid point (y, x) (of that kind, unless None), -1 where there is none."""
        keys = np.asarray(y, dtype=np.int64) * (self.cols + 1) + x
        if len(self._pinch_keys) == 0:
            return np.full(keys.shape, -1, dtype=np.int64)
        pos = np.minimum(np.searchsorted(self._pinch_keys, keys), len(self._pinch_keys) - 1)
        found = self._pinch_keys[pos] == keys
        if ne_sw is not None:
            found &= self._pinch_ne_sw[pos] == ne_sw
        return np.where(found, pos, -1)

    def outline(self, py: np.ndarray, px: np.ndarray):
        """Directed outline segments A -> B (the wall on the left), split at the grid points (py, px).

        The points must include every turn, once each, in row-major order.  Between two
        consecutive points of a grid line, the unit edges all have the same wall face or none:
        horizontal line y = j, +1 when the cell below is a wall and the one above is not;
        vertical line x = i, +1 when the cell on the left is a wall and the one on the right is not.
        Returns ax, ay, bx, by, am, bm: am / bm is the pinch index when the wall face of this
        segment must split its vertical edge at A / B (see the module docstring), else -1.
        """
        cell = self.cell
        same = py[1:] == py[:-1]
        j, xa, xb = py[:-1][same], px[:-1][same], px[1:][same]
        kind = cell(j - 1, xa) - cell(j, xa)
        keep = kind != 0
        j, xa, xb, west = j[keep], xa[keep], xb[keep], kind[keep] > 0
        low = self.pinch_index(j, xa)  # a pinch at the segment's west end belongs to this segment's cell
        h = (np.where(west, xb, xa), j, np.where(west, xa, xb), j,
             np.where(west, -1, low), np.where(west, low, -1))
        order = np.lexsort((py, px))
        vy, vx = py[order], px[order]
        same = vx[1:] == vx[:-1]
        i, ya, yb = vx[:-1][same], vy[:-1][same], vy[1:][same]
        kind = cell(ya, i - 1) - cell(ya, i)
        keep = kind != 0
        i, ya, yb, north = i[keep], ya[keep], yb[keep], kind[keep] > 0
        low = self.pinch_index(ya, i, ne_sw=True)
        high = self.pinch_index(yb, i, ne_sw=False)
        v = (i, np.where(north, ya, yb), i, np.where(north, yb, ya),
             np.where(north, low, high), np.where(north, high, low))
        return tuple(np.concatenate(p) for p in zip(h, v))


def _side_faces(a0, b0, ah, bh, am, bm) -> np.ndarray:
    """Each segment's wall quad [A0, B0, Bh, Ah] (A0 bottom, Ah top) as triangles facing out."""
    has_a, has_b = am >= 0, bm >= 0
    plain, only_a, only_b, both = ~has_a & ~has_b, has_a & ~has_b, ~has_a & has_b, has_a & has_b
    tri = lambda *cols: np.stack(cols, axis=1)  # noqa: E731
    return np.concatenate([
        tri(a0, b0, bh)[plain], tri(a0, bh, ah)[plain],
        tri(b0, bh, ah)[only_a], tri(b0, ah, am)[only_a], tri(b0, am, a0)[only_a],
        tri(a0, b0, bm)[only_b], tri(a0, bm, bh)[only_b], tri(a0, bh, ah)[only_b],
        tri(a0, b0, bm)[both], tri(a0, bm, am)[both], tri(am, bm, bh)[both], tri(am, bh, ah)[both],
    ])


def _outline_caps(grid: _Grid, seg):
    """Triangulate the region inside the outline loops (manifold3d's triangulator).

    Returns (x, y, triangles) with the triangles indexing the points (x, y), or None when
    the triangulator cannot be used (the caller then falls back to rectangles).
    """
    try:
        import manifold3d
    except ImportError:  # pragma: no cover - a dependency, but the fallback needs nothing
        return None
    ax, ay, bx, by = seg[:4]
    n = len(ax)
    width = grid.cols + 1
    dx, dy = np.sign(bx - ax), np.sign(by - ay)
    code = np.where(dx > 0, 0, np.where(dy > 0, 1, np.where(dx < 0, 2, 3)))  # E N W S
    key = (ay * width + ax) * 4 + code
    order = np.argsort(key)
    sorted_key = key[order]

    def find(k):
        pos = np.clip(np.searchsorted(sorted_key, k), 0, n - 1)
        return np.where(sorted_key[pos] == k, order[pos], -1)

    end = (by * width + bx) * 4
    left, right = find(end + (code + 1) % 4), find(end + (code + 3) % 4)
    # at a pinch both turns exist: turning left keeps the two diagonal cells apart
    succ = np.where(left >= 0, left, right)
    if (succ < 0).any():
        return None
    idx, sizes = _cycles(succ)
    px, py = ax[idx], ay[idx]
    pts = np.empty((n, 2), dtype=np.float64)
    pts[:, 0], pts[:, 1] = px, py
    starts = np.cumsum(sizes) - sizes
    polygons = [pts[a:b] for a, b in zip(starts.tolist(), (starts + sizes).tolist())]  # np.split: 3x slower
    outer = _outer_loops(grid, seg, idx, starts, sizes)
    if _hole_work(outer, sizes) > MAX_HOLE_WORK:
        return None
    try:
        tris = _triangulate(manifold3d, polygons, starts, sizes, outer)
    except Exception:  # noqa: BLE001 - any failure of the optional fast path falls back
        return None
    tris = _flip_flat(px, py, tris)
    return None if tris is None else (px, py, tris)


def _hole_work(outer: np.ndarray | None, sizes: np.ndarray) -> int:
    """The largest (holes x points) of one triangulation call (see :data:`MAX_HOLE_WORK`)."""
    if outer is None:  # one call
        return (len(sizes) - 1) * int(sizes.sum())
    loops = np.bincount(outer, minlength=len(sizes))
    points = np.bincount(outer, weights=sizes, minlength=len(sizes))
    return int(((loops - 1) * points).max())


def _outer_loops(grid: _Grid, seg, idx: np.ndarray, starts: np.ndarray, sizes: np.ndarray):
    """For each outline loop (``idx``/``starts``/``sizes`` as :func:`_cycles` gives them), the
    outer loop of its piece of wall: itself for an outer loop, the loop around it for a hole.

    An outer loop runs counter-clockwise (the wall on its left, inside), a hole clockwise.
    Left of a hole's lowest point on its leftmost side is a wall cell; the run of wall cells
    through it starts at an outline edge of the same piece of wall (further left), on the
    outer loop or on another hole of that piece, which is then followed the same way
    (pointer doubling; each step moves left, so it ends on the outer loop).  None if
    something does not add up (then every loop goes in one group).
    """
    ax, ay, bx, by = seg[:4]
    n, n_loops = len(idx), len(sizes)
    px, py = ax[idx], ay[idx]
    nxt = np.arange(1, n + 1)
    nxt[starts + sizes - 1] = starts
    area = np.add.reduceat(px * py[nxt] - px[nxt] * py, starts)  # twice the signed area
    hole = np.flatnonzero(area < 0)
    if len(hole) == 0:
        return np.arange(n_loops)
    # the hole's lowest point on its leftmost side, and the wall run left of it
    height = grid.rows + 2
    low = np.minimum.reduceat(px * height + py, starts)[hole]
    hx, hy = np.divmod(low, height)
    i = np.searchsorted(grid.trans_keys, hy * (grid.cols + 1) + hx - 1, side="right") - 1
    if (i < 0).any():
        return None
    i = np.maximum(i, 0)
    run_x = grid.trans_x[i]
    if not ((grid.trans_row[i] == hy) & grid.trans_start[i] & (run_x < hx)).all():
        return None
    # the vertical outline segment at the start of that run, and its loop
    vertical = np.flatnonzero(ax == bx)
    y0, y1 = np.minimum(ay, by)[vertical], np.maximum(ay, by)[vertical]
    vkey = ax[vertical] * (grid.rows + 1) + y0
    order = np.argsort(vkey)
    j = np.searchsorted(vkey[order], run_x * (grid.rows + 1) + hy, side="right") - 1
    if (j < 0).any():
        return None
    j = order[np.maximum(j, 0)]
    if not ((ax[vertical[j]] == run_x) & (y0[j] <= hy) & (hy < y1[j])).all():
        return None
    loop_of = np.empty(n, dtype=np.int64)
    loop_of[idx] = np.repeat(np.arange(n_loops), sizes)
    parent = np.arange(n_loops)
    parent[hole] = loop_of[vertical[j]]
    for _ in range(int(n_loops).bit_length() + 1):
        parent = parent[parent]
    if not (area[parent] > 0).all():
        return None
    return parent


def _triangulate(manifold3d, polygons, starts, sizes, outer) -> np.ndarray:
    """manifold3d's triangulation of the loops: (m, 3) indices into the loops' points in order.

    Its cost grows faster than the number of loops (0.49 s for the 6,691 loops of a
    5000 x 5000 map in one call), so each outer loop goes in a call of its own, with its
    holes: 0.1 s, and the same triangles (each piece of wall is triangulated the same way
    alone).  Without ``outer`` (holes not placed), one call.
    """
    if outer is None:
        return np.asarray(manifold3d.triangulate(polygons), dtype=np.int64).reshape(-1, 3)
    loops = np.lexsort((np.arange(len(sizes)), outer != np.arange(len(sizes)), outer))  # outer loop first
    bounds = np.flatnonzero(np.diff(outer[loops])) + 1
    # the groups' points in call order (each group's loops one after the other), and each
    # call's triangles, indexing its own points, shifted by where the group's points begin
    size = sizes[loops]
    begin = np.cumsum(size) - size  # where each loop's points begin in call order
    point = np.arange(int(size.sum())) + np.repeat(starts[loops] - begin, size)
    first = begin[np.r_[0, bounds]]
    polys = [polygons[k] for k in loops.tolist()]
    cut = np.r_[0, bounds, len(loops)].tolist()
    parts = [manifold3d.triangulate(polys[a:b]) for a, b in zip(cut[:-1], cut[1:])]
    counts = np.array([len(t) for t in parts], dtype=np.int64)
    local = np.concatenate(parts).astype(np.int64).reshape(-1, 3) + np.repeat(first, counts)[:, None]
    return point[local]


def _cycles(succ: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cycles of the permutation ``succ``: (every index in cycle order, the cycle sizes).

    Cycles come in the order of their smallest index, each starting there and following
    ``succ``: what walking from index 0 upwards and following each unvisited cycle gives,
    computed by pointer doubling (log2(n) whole-array steps instead of a Python loop).
    """
    n = len(succ)
    label = np.arange(n)
    jump = succ.copy()
    steps = max(int(n).bit_length(), 1)
    for _ in range(steps):  # label: the smallest index of each cycle
        np.minimum(label, label[jump], out=label)
        jump = jump[jump]
    start = label == np.arange(n)
    # distance forward to the cycle's start, by list ranking with the start as the end
    nxt = np.where(start, np.arange(n), succ)
    dist = (~start).astype(np.int64)
    for _ in range(steps):
        dist += dist[nxt]
        nxt = nxt[nxt]
    size = np.bincount(label, minlength=n)
    pos = (size[label] - dist) % size[label]  # the start 0, its successor 1, ...
    order = np.lexsort((pos, label))
    return order, size[start]


def _cross(px, py, tris) -> np.ndarray:
    """Twice the signed area of each triangle (exact: the points are on the integer grid)."""
    x, y = px[tris], py[tris]
    return (x[:, 1] - x[:, 0]) * (y[:, 2] - y[:, 0]) - (y[:, 1] - y[:, 0]) * (x[:, 2] - x[:, 0])


def _flip_flat(px, py, tris):
    """Remove zero-area triangles by edge flips; None if a triangle is inverted or a flip fails.

    The ear clipper may return a flat triangle (a, b, c) with c on the segment ab, when a
    hole corner lies on the line of an outline edge.  Its neighbour across ab is (b, a, d);
    both are replaced by (c, a, d) and (c, d, b), which cover the same area, keep every
    other edge, and are not flat unless d is on the same line (then they are flipped in turn).
    """
    cross = _cross(px, py, tris)
    if (cross < 0).any():
        return None
    flat = np.flatnonzero(cross == 0)
    if len(flat) == 0:
        return tris
    tris = tris.copy()
    # the triangle owning each directed edge: a sorted table of the edges as they are, and the
    # flips' changes on top (a dict of every edge cost more than the flips on a big map)
    n_pts = len(px)
    edges = tris[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    keys = edges[:, 0] * n_pts + edges[:, 1]
    order = np.argsort(keys, kind="stable")
    table, table_owner = keys[order], order // 3
    changed: dict[int, int | None] = {}

    def owner(a, b):
        k = a * n_pts + b
        if k in changed:
            return changed[k]
        i = int(np.searchsorted(table, k, side="right")) - 1  # the last, as a dict filled in order
        return int(table_owner[i]) if i >= 0 and table[i] == k else None
    xs, ys = px.tolist(), py.tolist()

    def is_flat(tri):
        a, b, c = tri
        return (xs[b] - xs[a]) * (ys[c] - ys[a]) - (ys[b] - ys[a]) * (xs[c] - xs[a]) == 0

    def between(p, a, b):
        return min(xs[a], xs[b]) <= xs[p] <= max(xs[a], xs[b]) and min(ys[a], ys[b]) <= ys[p] <= max(ys[a], ys[b])

    queue = flat.tolist()
    budget = 20 * len(queue) + 100
    while queue:
        budget -= 1
        if budget < 0:
            return None
        t = queue.pop()
        tri = tris[t].tolist()
        if not is_flat(tri):
            continue
        for r in range(3):  # rotate so that c, the middle point, comes last
            a, b, c = tri[r:] + tri[:r]
            if between(c, a, b):
                break
        else:
            return None
        u = owner(b, a)
        if u is None:
            return None
        d = [v for v in tris[u].tolist() if v not in (a, b)][0]
        for e in ((a, b), (b, c), (c, a), (b, a), (a, d), (d, b)):
            changed[e[0] * n_pts + e[1]] = None
        tris[t], tris[u] = (c, a, d), (c, d, b)
        for (e0, e1), x in (((c, a), t), ((a, d), t), ((d, c), t), ((c, d), u), ((d, b), u), ((b, c), u)):
            changed[e0 * n_pts + e1] = x
        queue.extend(x for x in (t, u) if is_flat(tris[x].tolist()))
    return tris if (_cross(px, py, tris) > 0).all() else None


def _rectangle_caps(grid: _Grid, rects: np.ndarray):
    """Triangulate each rectangle through every rectangle corner on its perimeter.

    Returns (corner mask, px, py, triangles, centres): triangles index the points
    (px, py) and, as ``-1 - k``, the centre points ``centres[k]``.
    """
    rows, cols = grid.rows, grid.cols
    n_rect = len(rects)
    x0, y0, x1, y1 = rects.T
    w, h = x1 - x0, y1 - y0
    label = np.full((rows + 2, cols + 2), -1, dtype=np.int64)
    area = w * h
    rid = np.repeat(np.arange(n_rect), area)
    k = np.arange(int(area.sum())) - np.repeat(np.cumsum(area) - area, area)
    label[y0[rid] + k // w[rid] + 1, x0[rid] + k % w[rid] + 1] = rid

    corner = np.zeros((rows + 1, cols + 1), dtype=bool)
    corner[y0, x0] = corner[y0, x1] = corner[y1, x0] = corner[y1, x1] = True
    vy, vx = np.nonzero(corner)

    around = np.stack([label[vy, vx], label[vy, vx + 1], label[vy + 1, vx], label[vy + 1, vx + 1]], axis=1)
    for j in range(1, 4):
        dup = (around[:, j:j + 1] == around[:, :j]).any(axis=1)
        around[dup, j] = -1
    point, slot = np.nonzero(around >= 0)
    prect = around[point, slot]
    px, py = vx[point], vy[point]
    X0, Y0, X1, Y1, W, H = x0[prect], y0[prect], x1[prect], y1[prect], w[prect], h[prect]
    on_bottom, on_right, on_top = py == Y0, px == X1, py == Y1
    t = np.where(on_bottom, px - X0,
                 np.where(on_right, W + py - Y0, np.where(on_top, W + H + X1 - px, 2 * W + H + Y1 - py)))
    order = np.lexsort((t, prect))
    point, prect = point[order], prect[order]
    edge = np.where(on_bottom, 0, np.where(on_right, 1, np.where(on_top, 2, 3)))[order]
    is_corner = (((px == X0) | (px == X1)) & ((py == Y0) | (py == Y1)))[order]
    count = np.bincount(prect, minlength=n_rect)
    offset = np.cumsum(count) - count
    extra = np.bincount(prect[~is_corner] * 4 + edge[~is_corner], minlength=4 * n_rect).reshape(n_rect, 4)
    eb, er, et, el = extra.T
    # fan from a corner whose two edges carry no extra vertex (start = its place in the order)
    start = np.full(n_rect, -1, dtype=np.int64)
    for ok, pos in (((et == 0) & (el == 0), 3 + eb + er + et), ((er == 0) & (et == 0), 2 + eb + er),
                    ((eb == 0) & (er == 0), 1 + eb), ((eb == 0) & (el == 0), 0 * eb)):
        start = np.where(ok, pos, start)

    fan = np.flatnonzero(start >= 0)
    m = count[fan] - 2
    r = np.repeat(fan, m)
    kk = np.arange(int(m.sum())) - np.repeat(np.cumsum(m) - m, m) + 1
    s, n, o = start[r], count[r], offset[r]
    corner_tris = np.stack([point[o + s], point[o + (s + kk) % n], point[o + (s + kk + 1) % n]], axis=1)

    centred = np.flatnonzero(start < 0)
    m = count[centred]
    r = np.repeat(centred, m)
    kk = np.arange(int(m.sum())) - np.repeat(np.cumsum(m) - m, m)
    n, o = count[r], offset[r]
    centre_of = np.full(n_rect, -1, dtype=np.int64)
    centre_of[centred] = np.arange(len(centred))
    centre_tris = np.stack([-1 - centre_of[r], point[o + kk], point[o + (kk + 1) % n]], axis=1)
    centres = np.stack([(x0[centred] + x1[centred]) / 2.0, (y0[centred] + y1[centred]) / 2.0], axis=1)
    return corner, vx, vy, np.concatenate([corner_tris, centre_tris]), centres


def _closed(faces: np.ndarray, n_vertices: int) -> bool:
    """Every directed edge once, and its reverse once: closed and consistently oriented.

    One sort: each edge as (its smaller end, its larger end, whether it runs downwards); then
    the keys must come in pairs k, k + 1 (both directions of each edge, once each).
    """
    a = np.ascontiguousarray(faces, dtype=np.int64).ravel()
    b = faces[:, [1, 2, 0]].astype(np.int64).ravel()  # edge a -> b
    key = np.minimum(a, b)  # in place from here on: a big mesh has millions of edges
    key *= n_vertices
    key += np.maximum(a, b)
    key *= 2
    key += a > b
    del b
    key.sort()
    return bool(len(key) % 2 == 0 and (key[0::2] % 2 == 0).all() and np.array_equal(key[0::2] + 1, key[1::2]))


def extrude(mask: np.ndarray, height: float, method: str = "outline", *, padded: np.ndarray | None = None):
    """Closed wall mesh of a grid-order ``mask``, in grid coordinates (z in metres).

    ``method`` "outline" triangulates the top and bottom inside the outline (fewest
    faces), falling back to "rectangles" if that fails its checks; "rectangles" builds
    them from :func:`rectangles`.  Returns (vertices (n, 3) float64, faces (m, 3) int64);
    x and y are in cells.  ``padded`` as for :func:`rectangles`.
    """
    if method not in ("outline", "rectangles"):
        raise ValueError(f"unknown method {method!r} (outline or rectangles)")
    mask = np.asarray(mask, dtype=bool)
    grid = _Grid(mask, padded)
    z = float(height)
    width = grid.cols + 1
    area = int(mask.sum())

    for attempt in dict.fromkeys((method, "rectangles")):
        if attempt == "outline":
            seg = grid.outline(grid.turn_y, grid.turn_x)
            caps = _outline_caps(grid, seg)
            if caps is None:
                continue
            cx, cy, cap = caps
            centres = np.zeros((0, 2))
        else:
            corner, cx, cy, cap, centres = _rectangle_caps(grid, rectangles(mask, padded=padded))
            breaks = np.union1d(cy * width + cx, grid.turn_y * width + grid.turn_x)  # sorted: row-major
            seg = grid.outline(*np.divmod(breaks, width))
        ax, ay, bx, by, am, bm = seg
        # vertices: grid points used (bottom, then top), centres (bottom, top), pinch splits
        keys, inverse = np.unique(np.concatenate([cy * width + cx, ay * width + ax, by * width + bx]),
                                  return_inverse=True)
        n_v, n_c, n_p = len(keys), len(centres), len(grid.pinch_x)
        cap_pt = inverse[:len(cx)]
        a0 = inverse[len(cx):len(cx) + len(ax)]
        b0 = inverse[len(cx) + len(ax):]
        top = np.where(cap >= 0, cap_pt[np.maximum(cap, 0)] + n_v, 2 * n_v + n_c + (-1 - cap))
        bottom = np.where(cap >= 0, cap_pt[np.maximum(cap, 0)], 2 * n_v + (-1 - cap))[:, ::-1]
        pm = lambda p: np.where(p >= 0, 2 * n_v + 2 * n_c + p, -1)  # noqa: E731
        side = _side_faces(a0, b0, a0 + n_v, b0 + n_v, pm(am), pm(bm))
        faces = np.concatenate([top, bottom, side]).astype(np.int64)

        gy, gx = np.divmod(keys, width)
        vertices = np.concatenate([
            np.stack([gx, gy, np.zeros(n_v)], 1),
            np.stack([gx, gy, np.full(n_v, z)], 1),
            np.column_stack([centres, np.zeros(n_c)]),
            np.column_stack([centres, np.full(n_c, z)]),
            np.stack([grid.pinch_x, grid.pinch_y, np.full(n_p, z / 2.0)], 1),
        ]).astype(np.float64)
        # the checks that make the result trustworthy: caps all face up and add up to the wall
        # area (so they cover it once), and every edge is shared by exactly two faces
        p = vertices[top]
        cross = (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - \
                (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0])
        if (cross > 0).all() and cross.sum() == 2 * area and _closed(faces, len(vertices)):
            return vertices, faces
    raise AssertionError("wall mesh failed its closedness checks")  # a bug: the rectangle path is exact


def wall_cells(occupancy_map, unknown_as_wall: bool = False) -> np.ndarray:
    """Grid-order mask of the cells that become walls; MapError when there is none."""
    return grid_mask(_walls_image(occupancy_map, unknown_as_wall))


def padded_wall_cells(occupancy_map, unknown_as_wall: bool = False) -> np.ndarray:
    """:func:`wall_cells` with a ring of False around it, made in one copy: shape (rows + 2,
    cols + 2), the mask is its [1:-1, 1:-1] (for ``padded`` of :func:`extrude` and :func:`rectangles`)."""
    return _padded(_walls_image(occupancy_map, unknown_as_wall)[::-1])


def _walls_image(occupancy_map, unknown_as_wall: bool) -> np.ndarray:
    """The image-order mask of wall cells; MapError when there is none."""
    walls = occupancy_map.walls(unknown_as_wall)
    if not walls.any():
        om = occupancy_map
        size = f"{om.cols} x {om.rows} px"
        if unknown_as_wall:
            detail = f"no occupied or unknown cell in '{om.image_name}' ({size}, all free)"
        else:
            detail = (f"no occupied cell in '{om.image_name}' ({size}: {int(om.free.sum())} free, "
                      f"{int(om.unknown.sum())} unknown)")
        raise MapError(om.problem(f"{detail}, so there is no wall to build"))
    return walls


def check_height(height) -> float:
    try:
        value = float(height)
    except (TypeError, ValueError):
        value = float("nan")
    if isinstance(height, bool) or not (np.isfinite(value) and value > 0):
        raise MapError(Problem(f"must be > 0 (metres), not {height}", key="height"))
    return value


def wall_mesh(occupancy_map, height: float = 2.0, *, unknown_as_wall: bool = False, method: str = "outline"):
    """The walls of ``occupancy_map`` as one closed trimesh.Trimesh in the map frame (m).

    z runs from 0 to ``height``; the map's yaw is applied, so the mesh is posed at the identity.
    """
    z = check_height(height)
    mask = wall_cells(occupancy_map, unknown_as_wall)
    return mask_mesh(mask, z, occupancy_map.grid_to_map(), method=method)


def mask_mesh(mask: np.ndarray, height: float, grid_to_map: np.ndarray, method: str = "outline"):
    """:func:`extrude` a grid-order mask and place it in the map frame: a trimesh.Trimesh."""
    import trimesh

    vertices, faces = extrude(mask, height, method=method)
    vertices[:, :2] = to_map(vertices[:, :2], grid_to_map)
    return trimesh.Trimesh(vertices=vertices, faces=faces, process=False)


def to_map(points_xy: np.ndarray, grid_to_map: np.ndarray) -> np.ndarray:
    """Grid coordinates (cells) -> map frame (m) with the 3x3 affine ``grid_to_map``."""
    m = grid_to_map
    x, y = points_xy[..., 0], points_xy[..., 1]
    return np.stack([m[0, 0] * x + m[0, 1] * y + m[0, 2], m[1, 0] * x + m[1, 1] * y + m[1, 2]], axis=-1)
