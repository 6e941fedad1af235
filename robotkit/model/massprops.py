"""Mass properties of rigid bodies that need no mesh, in float64: primitives (box, cylinder,
sphere) at unit density, parallel-axis combination of parts, and the smallest bounding primitive
of a set of points (``estimate``: a link's mass spread over the primitive that encloses it).
Mesh volume integrals are ``robotkit.mesh.inertia``'s."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class MassProps:
    volume: float
    com: np.ndarray  # (3,)
    inertia: np.ndarray  # (3, 3) about the centre of mass, mesh axes, unit density

    def scaled(self, density: float) -> tuple[float, np.ndarray, np.ndarray]:
        return self.volume * density, self.com, self.inertia * density


def box_props(size) -> MassProps:
    x, y, z = (float(v) for v in size)
    vol = x * y * z
    return MassProps(vol, np.zeros(3), vol / 12.0 * np.diag([y * y + z * z, x * x + z * z, x * x + y * y]))


def cylinder_props(radius: float, length: float) -> MassProps:
    """Cylinder along z, centred on its origin."""
    r, h = float(radius), float(length)
    vol = np.pi * r * r * h
    ixx = vol * (3 * r * r + h * h) / 12.0
    return MassProps(vol, np.zeros(3), np.diag([ixx, ixx, vol * r * r / 2.0]))


def sphere_props(radius: float) -> MassProps:
    r = float(radius)
    vol = 4.0 / 3.0 * np.pi * r ** 3
    return MassProps(vol, np.zeros(3), np.eye(3) * 0.4 * vol * r * r)


def combine(parts: list[tuple[float, np.ndarray, np.ndarray]]) -> tuple[float, np.ndarray, np.ndarray]:
    """Sum (mass, com, inertia about own com) parts, all in one frame (parallel-axis theorem)."""
    mass = sum(m for m, _, _ in parts)
    com = sum(m * np.asarray(c) for m, c, _ in parts) / mass
    I = np.zeros((3, 3))
    for m, c, Ic in parts:
        r = np.asarray(c) - com
        I += Ic + m * (np.dot(r, r) * np.eye(3) - np.outer(r, r))
    return mass, com, I


@dataclass(frozen=True)
class Bounding:
    """A solid primitive enclosing a set of points: ``kind`` box | cylinder | sphere, its
    ``size`` (box edges; cylinder radius and length along its z; sphere radius) and its pose
    ``transform`` (4x4, the primitive's centre and axes in the points' frame)."""

    kind: str
    size: tuple[float, ...]
    transform: np.ndarray

    @property
    def volume(self) -> float:
        return {"box": lambda s: s[0] * s[1] * s[2], "cylinder": lambda s: np.pi * s[0] ** 2 * s[1],
                "sphere": lambda s: 4.0 / 3.0 * np.pi * s[0] ** 3}[self.kind](self.size)

    def inertia(self, mass: float) -> tuple[np.ndarray, np.ndarray]:
        """(centre of mass, inertia about it) of the primitive as a uniform solid of ``mass``,
        in the points' frame (a flat or thin primitive gives a plate's or a rod's tensor)."""
        s = self.size
        if self.kind == "box":
            x2, y2, z2 = (v * v for v in s)
            d = np.array([y2 + z2, x2 + z2, x2 + y2]) / 12.0
        elif self.kind == "cylinder":
            r2, h2 = s[0] ** 2, s[1] ** 2
            d = np.array([(3 * r2 + h2) / 12.0, (3 * r2 + h2) / 12.0, r2 / 2.0])
        else:
            d = np.full(3, 0.4 * s[0] ** 2)
        R = self.transform[:3, :3]
        I = R @ np.diag(mass * d) @ R.T
        return self.transform[:3, 3].copy(), 0.5 * (I + I.T)


def bounding_primitive(points) -> Bounding:
    """The smallest in volume of four solids enclosing ``points`` (trimesh.bounds): the box
    along the points' axes, the minimum-volume oriented box, the minimum cylinder and the
    minimum sphere.  Ties (to 1e-9) go to that order, so a box along the link's axes comes
    first; points in a plane or on a line get the box along the points' axes."""
    import trimesh

    P = np.unique(np.asarray(points, dtype=float).reshape(-1, 3), axis=0)
    lo, hi = P.min(axis=0), P.max(axis=0)
    aabb = np.eye(4)
    aabb[:3, 3] = 0.5 * (lo + hi)
    found = [Bounding("box", tuple(float(v) for v in hi - lo), aabb)]
    if not solid(P):
        return found[0]  # points in a plane or on a line: no hull; a plate's or a rod's box
    to_origin, extents = trimesh.bounds.oriented_bounds(P)
    found.append(Bounding("box", tuple(float(v) for v in extents), np.linalg.inv(to_origin)))
    cyl = trimesh.bounds.minimum_cylinder(P)  # a local search: it can miss the axis of a long part
    cylinders = [Bounding("cylinder", (float(cyl["radius"]), float(cyl["height"])), np.asarray(cyl["transform"]))]
    axes = np.vstack([np.eye(3), found[1].transform[:3, :3].T, np.linalg.eigh(np.cov(P.T))[1].T])
    cylinders += [_cylinder_along(P, axis) for axis in axes]
    found.append(min(cylinders, key=lambda b: b.volume))
    centre, radius = trimesh.nsphere.minimum_nsphere(P)
    sphere = np.eye(4)
    sphere[:3, 3] = centre
    found.append(Bounding("sphere", (float(radius),), sphere))
    smallest = min(b.volume for b in found)
    return next(b for b in found if b.volume <= smallest * (1 + 1e-9))


def _cylinder_along(P: np.ndarray, axis: np.ndarray) -> Bounding:
    """The smallest cylinder along ``axis`` enclosing ``P`` (the smallest circle of their
    projection, trimesh.nsphere)."""
    import trimesh

    T = trimesh.geometry.align_vectors([0.0, 0.0, 1.0], axis)  # the cylinder's axes -> the points' frame
    local = P @ T[:3, :3]
    centre, radius = trimesh.nsphere.minimum_nsphere(local[:, :2])
    lo, hi = local[:, 2].min(), local[:, 2].max()
    T[:3, 3] = T[:3, :3] @ np.array([centre[0], centre[1], 0.5 * (lo + hi)])
    return Bounding("cylinder", (float(radius), float(hi - lo)), T)


def solid(P: np.ndarray) -> bool:
    """Whether points span a volume (qhull can make their hull)."""
    size = float((P.max(axis=0) - P.min(axis=0)).max()) if len(P) else 0.0
    return size > 0 and np.linalg.matrix_rank(P - P.mean(axis=0), tol=1e-12 * size) == 3
