"""Byte-reproducible mesh files: binary STL and OBJ.

Both writers are hand-written (trimesh's exporters also give identical bytes
across runs today, docs/libraries.md, section 3, but their headers and number
formatting belong to trimesh and can change with its version; these bytes
depend only on the geometry):

- :func:`stl_bytes`: binary STL, an 80-byte fixed header, the triangle
  count, then per triangle the unit normal and the three corners as
  little-endian float32 and a zero attribute word.  Normals come from the
  float64 corners (zero for degenerate triangles).  float32 rounds
  coordinates to about 1e-7 relative (0.1 um on a 1 m part): fine for
  collision and visual geometry, use the mass properties computed before
  export for inertials.
- :func:`obj_bytes`: Wavefront OBJ with ``v x y z`` lines in Python's
  shortest round-trip float format (exact float64) and 1-based ``f a b c``
  lines; one object, no normals, no materials (MuJoCo reads one object per
  OBJ file).
"""

from __future__ import annotations

import numpy as np

STL_HEADER = b"robotkit binary STL".ljust(80, b" ")


def stl_bytes(mesh) -> bytes:
    """Binary STL of ``mesh`` (same geometry, same bytes)."""
    V = np.asarray(mesh.vertices, dtype=np.float64)
    F = np.asarray(mesh.faces, dtype=np.int64)
    tri = V[F]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(n, axis=1)
    ok = norm > 0
    n /= np.where(ok, norm, 1.0)[:, None]  # whole rows, not a masked copy
    if not ok.all():
        n[~ok] = 0.0
    # the file is filled in place and copied once (a big world mesh has 10^5 triangles)
    out = np.zeros(84 + 50 * len(F), dtype=np.uint8)
    out[:80] = np.frombuffer(STL_HEADER, dtype=np.uint8)
    out[80:84] = np.frombuffer(np.uint32(len(F)).astype("<u4").tobytes(), dtype=np.uint8)
    rec = out[84:].view(np.dtype([("n", "<f4", (3,)), ("v", "<f4", (3, 3)), ("attr", "<u2")]))
    n += 0.0  # -0.0 -> 0.0 so that equal geometry gives equal bytes
    rec["n"] = n
    del n
    tri += 0.0
    rec["v"] = tri
    del tri, rec
    return out.tobytes()


def obj_bytes(mesh, name: str | None = None) -> bytes:
    """OBJ text of ``mesh`` as UTF-8 bytes (exact float64 coordinates)."""
    V = np.asarray(mesh.vertices, dtype=np.float64) + 0.0
    F = np.asarray(mesh.faces, dtype=np.int64) + 1
    head = "# robotkit OBJ\n" + (f"o {name}\n" if name else "")
    # one %-format over every number (%r: float's repr, the shortest that reads back the same):
    # half the time of a line at a time, the same text
    v = ("v %r %r %r\n" * len(V)) % tuple(V.ravel().tolist())
    f = ("f %d %d %d\n" * len(F)) % tuple(F.ravel().tolist())
    return (head + v + f).encode("utf-8")
