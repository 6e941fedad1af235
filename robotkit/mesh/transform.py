"""Scale, recenter, rotate and translate a mesh, returning the exact matrix applied.

The matrix is ``M = T(translate) @ R(rpy) @ T(-c) @ S(scale)``: the mesh is
scaled about its own origin (units, mirroring), shifted so that the
recentering point ``c`` of the *scaled* mesh (its axis-aligned bounding-box
centre, or its centre of mass) is at the origin, then rotated by the
fixed-axis roll-pitch-yaw ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (the URDF
convention, :func:`robotkit.geometry.rpy_matrix`) and translated.  This is
the same order as a recipe geometry: origin composed with the recentering
offset, applied to the scaled mesh.

Each new vertex is ``M[:3, :3] @ v + M[:3, 3]`` in float64, so quantities
derived from the input carry over with the returned matrix: for unit density,
volume times ``|det M[:3, :3]|``, centre of mass ``M @ com``, and for a
similarity transform (uniform scale ``s``) inertia ``s^5 R I R^T``.  A scale
with a negative determinant mirrors the mesh; its faces are reversed so the
winding stays outward (and the volume positive).
"""

from __future__ import annotations

import numpy as np
import trimesh

from robotkit.geometry import rpy_matrix
from robotkit.mesh.inertia import mesh_mass_properties

RECENTER = ("none", "bbox", "com")


def transform_matrix(scale=(1.0, 1.0, 1.0), translate=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0),
                     center=(0.0, 0.0, 0.0)) -> np.ndarray:
    """``T(translate) @ R(rpy) @ T(-center) @ S(scale)`` as a 4x4 float64 array."""
    S = np.diag(np.append(np.asarray(scale, dtype=np.float64), 1.0))
    C = np.eye(4)
    C[:3, 3] = -np.asarray(center, dtype=np.float64)
    R = np.eye(4)
    R[:3, :3] = rpy_matrix(rpy)
    R[:3, 3] = np.asarray(translate, dtype=np.float64)
    return R @ C @ S


def transform(mesh, scale=(1.0, 1.0, 1.0), translate=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0),
              recenter: str = "none") -> tuple[trimesh.Trimesh, np.ndarray]:
    """Return ``(transformed copy, 4x4 matrix applied)``; the input is not modified.

    ``scale`` is one number or three; ``recenter`` is ``'none'``, ``'bbox'``
    or ``'com'`` (the latter needs a closed volume: see
    :func:`robotkit.mesh.repair.repair`).  Raises ValueError for a zero or
    non-finite scale, an unknown ``recenter``, or ``'com'`` on a mesh that is
    not a closed volume.
    """
    s = np.broadcast_to(np.asarray(scale, dtype=np.float64), (3,)).copy()
    if not np.isfinite(s).all() or (s == 0).any():
        raise ValueError(f"scale must be finite and non-zero on every axis, got {tuple(s.tolist())}")
    for name, v in (("translate", translate), ("rpy", rpy)):
        if np.shape(v) != (3,) or not np.isfinite(np.asarray(v, dtype=np.float64)).all():
            raise ValueError(f"{name} must be three finite numbers, got {v!r}")
    if recenter not in RECENTER:
        raise ValueError(f"recenter must be one of {', '.join(RECENTER)}, got {recenter!r}")
    V = np.asarray(mesh.vertices, dtype=np.float64)
    F = np.asarray(mesh.faces, dtype=np.int64)
    mirror = float(np.prod(s)) < 0
    center = np.zeros(3)
    if recenter != "none":
        scaled = V * s
        if recenter == "bbox":
            center = 0.5 * (scaled.min(axis=0) + scaled.max(axis=0))
        else:
            probe = trimesh.Trimesh(scaled, F[:, ::-1] if mirror else F, process=False)
            if not probe.is_volume:
                raise ValueError("recenter='com' needs a closed, consistently wound mesh "
                                 "(repair it first, or use recenter='bbox')")
            center = mesh_mass_properties(probe.vertices, probe.faces).com
    M = transform_matrix(s, translate, rpy, center)
    out = mesh.copy()
    out.vertices = V @ M[:3, :3].T + M[:3, 3]
    if mirror:
        out.faces = F[:, ::-1].copy()
    return out, M
