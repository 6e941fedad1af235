"""Bounding primitives fitted to a mesh: box, cylinder, sphere, capsule.

Each fit returns a :class:`Primitive`: its parameters, its pose in the mesh
frame (4x4; cylinders and capsules lie along the pose's z axis, as in URDF,
SDF and MuJoCo) and its analytic volume.  Every fit *contains* the mesh.

- box: trimesh's oriented bounding box (``trimesh.bounds.oriented_bounds``,
  the smallest box with one face flush with a hull face), with the axes
  relabelled so that the rotation is the one closest to the identity (an
  axis-aligned mesh gives an identity rotation and sizes in x, y, z order);
- cylinder: ``trimesh.bounds.minimum_cylinder`` (volume minimised over axis
  directions), compared with cylinders along the box axes and keeping the
  smallest;
- sphere: ``trimesh.nsphere.minimum_nsphere`` (exact smallest enclosing
  sphere of the hull vertices);
- capsule: hand-written (no installed library fits capsules).  For each
  candidate axis (the fitted cylinder's axis and the box axes), the axis line
  goes through the centre of the smallest circle enclosing the points
  projected on the plane across the axis; for a radius ``r`` at least that
  circle's, the shortest segment whose capsule contains every point follows
  in closed form (a point at distance ``rho`` from the axis and at ``t``
  along it needs the segment to reach ``t -/+ sqrt(r^2 - rho^2)``), and the
  volume ``pi r^2 L + 4/3 pi r^3`` is minimised over ``r`` (grid, then
  bounded scalar search).  The smallest candidate is kept.

Capsule ``length`` is the length of the cylindrical part, between the two cap
centres (the SDF ``<capsule><length>`` convention; MuJoCo's ``size`` takes
half of it, trimesh's ``creation.capsule`` calls it ``height``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import trimesh

from robotkit.geometry import matrix_rpy
from robotkit.mesh.hull import exact_hull


@dataclass(frozen=True, eq=False)
class Primitive:
    """A fitted primitive: ``kind`` is ``box``, ``cylinder``, ``sphere`` or ``capsule``.

    ``params``: box ``{"size": (x, y, z)}``; cylinder ``{"radius", "length"}``;
    sphere ``{"radius"}``; capsule ``{"radius", "length"}`` (cylindrical part).
    ``pose``: 4x4, the primitive's frame in the mesh frame (centred; z is the
    axis of cylinders and capsules).  ``volume``: analytic, m^3.
    """

    kind: str
    params: dict
    pose: np.ndarray = field(repr=False)
    volume: float

    def to_dict(self) -> dict:
        """Plain JSON-able numbers: kind, params, xyz, rpy (URDF convention), pose, volume."""
        params = {k: (tuple(float(x) for x in v) if isinstance(v, (tuple, list, np.ndarray)) else float(v))
                  for k, v in self.params.items()}
        return {"kind": self.kind, "params": params,
                "xyz": tuple(float(v) + 0.0 for v in self.pose[:3, 3]),
                "rpy": tuple(float(v) + 0.0 for v in matrix_rpy(self.pose[:3, :3])),
                "pose": np.asarray(self.pose).tolist(), "volume": float(self.volume)}

    def to_mesh(self, sections: int = 128, subdivisions: int = 5) -> trimesh.Trimesh:
        """A closed triangle mesh of the primitive in the mesh frame (for booleans and distances)."""
        p = self.params
        if self.kind == "box":
            m = trimesh.creation.box(extents=p["size"])
        elif self.kind == "cylinder":
            m = trimesh.creation.cylinder(radius=p["radius"], height=p["length"], sections=sections)
        elif self.kind == "sphere":
            m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=p["radius"])
        elif self.kind == "capsule":
            m = trimesh.creation.capsule(height=p["length"], radius=p["radius"],
                                         count=[sections, sections // 2])
        else:
            raise ValueError(f"unknown primitive kind {self.kind!r}")
        m.apply_transform(self.pose)
        return trimesh.Trimesh(np.asarray(m.vertices), np.asarray(m.faces), process=True)

    def distance(self, points) -> np.ndarray:
        """Exact distance from each point (mesh frame) to the primitive's surface (inside or out)."""
        P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        R, t = np.asarray(self.pose[:3, :3], dtype=np.float64), np.asarray(self.pose[:3, 3], dtype=np.float64)
        q = (P - t) @ R
        p = self.params
        if self.kind == "sphere":
            return np.abs(np.linalg.norm(q, axis=1) - p["radius"])
        if self.kind == "capsule":
            axis = np.zeros_like(q)
            axis[:, 2] = np.clip(q[:, 2], -0.5 * p["length"], 0.5 * p["length"])
            return np.abs(np.linalg.norm(q - axis, axis=1) - p["radius"])
        if self.kind == "box":
            d = np.abs(q) - 0.5 * np.asarray(p["size"], dtype=np.float64)
        elif self.kind == "cylinder":
            d = np.stack([np.hypot(q[:, 0], q[:, 1]) - p["radius"], np.abs(q[:, 2]) - 0.5 * p["length"]], axis=1)
        else:
            raise ValueError(f"unknown primitive kind {self.kind!r}")
        outside = np.linalg.norm(np.maximum(d, 0.0), axis=1)
        return np.where(outside > 0, outside, -d.max(axis=1))

    def sample(self, count: int, seed: int = 0) -> np.ndarray:
        """``count`` points drawn uniformly by area on the exact surface, in the mesh frame."""
        rng = np.random.default_rng(seed)
        p, n = self.params, int(count)
        if self.kind in ("sphere", "capsule"):
            r, half = p["radius"], 0.5 * p.get("length", 0.0)
            side = 2 * np.pi * r * 2 * half
            u = rng.normal(size=(n, 3))
            q = r * u / np.linalg.norm(u, axis=1)[:, None]
            on_side = rng.random(n) < side / (side + 4 * np.pi * r * r)
            z = rng.uniform(-half, half, n)
            q[on_side, 2] = 0.0
            q[on_side] *= r / np.maximum(np.linalg.norm(q[on_side], axis=1), 1e-300)[:, None]
            q[on_side, 2] = z[on_side]
            q[~on_side, 2] += np.sign(q[~on_side, 2]) * half
        elif self.kind == "cylinder":
            r, half = p["radius"], 0.5 * p["length"]
            side, cap = 2 * np.pi * r * 2 * half, np.pi * r * r
            pick = rng.choice(3, size=n, p=np.array([side, cap, cap]) / (side + 2 * cap))
            ang = rng.uniform(0.0, 2 * np.pi, n)
            rad = np.where(pick == 0, r, r * np.sqrt(rng.random(n)))
            z = np.where(pick == 0, rng.uniform(-half, half, n), np.where(pick == 1, half, -half))
            q = np.stack([rad * np.cos(ang), rad * np.sin(ang), z], axis=1)
        elif self.kind == "box":
            h = 0.5 * np.asarray(p["size"], dtype=np.float64)
            areas = np.array([h[1] * h[2], h[0] * h[2], h[0] * h[1]])
            axis = rng.choice(3, size=n, p=areas / areas.sum())
            q = rng.uniform(-1.0, 1.0, (n, 3)) * h
            q[np.arange(n), axis] = np.where(rng.random(n) < 0.5, -1.0, 1.0) * h[axis]
        else:
            raise ValueError(f"unknown primitive kind {self.kind!r}")
        return q @ np.asarray(self.pose[:3, :3], dtype=np.float64).T + np.asarray(self.pose[:3, 3])


def fit_box(mesh) -> Primitive:
    """Oriented bounding box of ``mesh``."""
    return _box(_hull_points(mesh))


def _box(P: np.ndarray) -> Primitive:
    to_origin, extents = trimesh.bounds.oriented_bounds(P)
    pose = np.linalg.inv(to_origin)
    R, size = _closest_to_identity(pose[:3, :3], np.asarray(extents, dtype=np.float64))
    # recentre exactly on the points in the chosen axes
    local = P @ R
    lo, hi = local.min(axis=0), local.max(axis=0)
    size = hi - lo
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = R @ (0.5 * (lo + hi))
    return Primitive("box", {"size": tuple(float(v) for v in size)}, T, float(np.prod(size)))


def fit_cylinder(mesh) -> Primitive:
    """Smallest-volume bounding cylinder found (see the module docstring)."""
    return _cylinder(_hull_points(mesh))


def _cylinder(P: np.ndarray) -> Primitive:
    axes = [_axis_of(trimesh.bounds.minimum_cylinder(P)["transform"])]
    axes += list(_box(P).pose[:3, :3].T)
    best = None
    for a in axes:
        a = _canonical_axis(a)
        centre, r = _circle_across(P, a)
        t = P @ a
        length = float(t.max() - t.min())
        vol = math.pi * r * r * length
        if best is None or vol < best[0] * (1 - 1e-12):
            pose = _pose_along(a, centre + a * (0.5 * (t.max() + t.min()) - centre @ a))
            best = (vol, Primitive("cylinder", {"radius": r, "length": length}, pose, vol))
    return best[1]


def fit_sphere(mesh) -> Primitive:
    """Smallest bounding sphere."""
    P = _hull_points(mesh)
    centre, r = _min_ball(P)
    T = np.eye(4)
    T[:3, 3] = centre
    return Primitive("sphere", {"radius": r}, T, 4.0 / 3.0 * math.pi * r ** 3)


def fit_capsule(mesh) -> Primitive:
    """Smallest-volume bounding capsule found (see the module docstring)."""
    from scipy.optimize import minimize_scalar

    P = _hull_points(mesh)
    axes = [_cylinder(P).pose[:3, 2]] + list(_box(P).pose[:3, :3].T)
    best = None
    for a in axes:
        a = _canonical_axis(a)
        centre, r0 = _circle_across(P, a)
        w = P - centre
        t = w @ a
        rho2 = np.maximum(np.einsum("ij,ij->i", w, w) - t * t, 0.0)
        r0 = max(r0, math.sqrt(float(rho2.max())))
        mid_t = 0.5 * (float(t.max()) + float(t.min()))
        r_top = max(r0, math.sqrt(float((rho2 + (t - mid_t) ** 2).max())))  # a sphere: length 0

        def span(r):
            h = np.sqrt(np.maximum(r * r - rho2, 0.0))
            return float((t - h).max()), float((t + h).min())  # the segment must reach from lo to hi

        def volume(r):
            hi, lo = span(r)
            return math.pi * r * r * max(hi - lo, 0.0) + 4.0 / 3.0 * math.pi * r ** 3

        grid = np.linspace(r0, r_top, 65)
        vals = np.array([volume(r) for r in grid])
        k = int(np.argmin(vals))
        res = minimize_scalar(volume, bounds=(grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]),
                              method="bounded", options={"xatol": 1e-12 * max(r_top, 1e-300)})
        r = float(res.x) if volume(float(res.x)) <= vals[k] else float(grid[k])
        hi, lo = span(r)
        length = max(hi - lo, 0.0)
        mid = 0.5 * (hi + lo)
        vol = volume(r)
        if best is None or vol < best[0] * (1 - 1e-12):
            pose = _pose_along(a, centre + a * mid)
            best = (vol, Primitive("capsule", {"radius": r, "length": length}, pose, vol))
    return best[1]


FITS = {"box": fit_box, "cylinder": fit_cylinder, "sphere": fit_sphere, "capsule": fit_capsule}


def fit(mesh, kind: str) -> Primitive:
    """Fit the primitive named ``kind`` (``box``, ``cylinder``, ``sphere`` or ``capsule``)."""
    try:
        return FITS[kind](mesh)
    except KeyError:
        raise ValueError(f"unknown primitive {kind!r} (use {', '.join(FITS)})") from None


# --- helpers -----------------------------------------------------------------------------------

def _hull_points(mesh) -> np.ndarray:
    """The mesh's convex-hull vertices (or its vertices when the hull is degenerate)."""
    V = np.asarray(getattr(mesh, "vertices", mesh), dtype=np.float64)
    if len(V) == 0:
        raise ValueError("cannot fit a primitive to an empty mesh")
    try:
        return np.asarray(exact_hull(V).vertices)
    except ValueError:  # flat or tiny: all vertices
        return np.unique(V, axis=0)


def _min_ball(P: np.ndarray) -> tuple[np.ndarray, float]:
    """Smallest enclosing ball (trimesh); falls back to the box centre for degenerate sets."""
    try:
        c, r = trimesh.nsphere.minimum_nsphere(P)
        c = np.asarray(c, dtype=np.float64)
        r = float(np.sqrt(((P - c) ** 2).sum(axis=1).max()))  # contain every point exactly
        if np.isfinite(c).all() and np.isfinite(r):
            return c, r
    except Exception:  # qhull errors on flat or collinear sets
        pass
    c = 0.5 * (P.min(axis=0) + P.max(axis=0))
    return c, float(np.sqrt(((P - c) ** 2).sum(axis=1).max()))


def _circle_across(P: np.ndarray, a: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre (3D, on the plane through the origin across ``a``) and radius of the smallest circle
    enclosing the points projected along ``a``."""
    u, v = _basis(a)
    q = np.stack([P @ u, P @ v], axis=1)
    c2, r = _min_ball(np.unique(q, axis=0))
    return c2[0] * u + c2[1] * v, r


def _basis(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    R = _rotation_z_to(a)
    return R[:, 0], R[:, 1]


def _rotation_z_to(a: np.ndarray) -> np.ndarray:
    """The smallest rotation taking +z to unit vector ``a`` (Rodrigues)."""
    a = np.asarray(a, dtype=np.float64)
    a = a / np.linalg.norm(a)
    z = np.array([0.0, 0.0, 1.0])
    c = float(a @ z)
    if c > 1 - 1e-15:
        return np.eye(3)
    if c < -1 + 1e-15:
        return np.diag([1.0, -1.0, -1.0])
    k = np.cross(z, a)
    s = np.linalg.norm(k)
    k /= s
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * K + (1 - c) * K @ K


def _pose_along(a: np.ndarray, centre: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = _rotation_z_to(a)
    T[:3, 3] = centre
    return T


def _canonical_axis(a: np.ndarray) -> np.ndarray:
    """Unit axis with its largest component positive (an axis has no direction)."""
    a = np.asarray(a, dtype=np.float64)
    a = a / np.linalg.norm(a)
    a = np.where(np.abs(a) < 1e-15, 0.0, a)
    return -a if a[int(np.argmax(np.abs(a)))] < 0 else a


def _axis_of(T) -> np.ndarray:
    return np.asarray(T, dtype=np.float64)[:3, 2]


def _closest_to_identity(R: np.ndarray, size: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Relabel the box axes (signed permutation, det +1) so that R is closest to the identity."""
    import itertools

    if np.linalg.det(R) < 0:
        R = R.copy()
        R[:, 2] *= -1
    best = None
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            Q = R[:, perm] * np.array(signs)
            if np.linalg.det(Q) < 0:
                continue
            tr = float(np.trace(Q))
            if best is None or tr > best[0] + 1e-12:
                best = (tr, Q, size[list(perm)])
    return best[1], best[2]
