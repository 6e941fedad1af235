"""Which mesh file each output references, and the conversions that make those files.

Shared by the emitters (URDF, SDF, MJCF) and the tasks that write the files:

- visual geometry references the copied (or processed) visual file, except in MJCF, which
  reads no COLLADA, only binary STL and at most 200,000 triangles in an STL: a DAE becomes
  ``meshes/mjcf/<stem>.obj``, an ASCII STL ``meshes/mjcf/<stem>.stl``, a larger binary STL OBJ;
- collision geometry references an OBJ in every format: Drake takes convex meshes only as
  OBJ, VTK or glTF; MuJoCo, Gazebo and RViz read OBJ too.  Collision pieces are written as OBJ
  by their task; any other mesh used for collision is converted to ``meshes/collision/<stem>.obj``.

Conversions keep the coordinates the reference's ``out_scale`` applies to (file units for a
copied mesh, metres for a processed one), so every format uses the same scale.
"""

from __future__ import annotations

import os

MJCF_VISUAL_EXT = (".stl", ".obj")


def is_ascii_stl(path: str) -> bool:
    """Whether the STL file is ASCII: not the binary layout (84 bytes + 50 per triangle), whatever
    its header says (binary files whose header starts with ``solid`` exist)."""
    import struct

    try:
        size = os.path.getsize(path)
        with open(path, "rb") as f:
            head = f.read(84)
    except OSError:
        return False
    if len(head) == 84 and size == 84 + 50 * struct.unpack("<I", head[80:84])[0]:
        return False
    return head.lstrip()[:5].lower() == b"solid"


MJCF_STL_FACES = 200000
"""MuJoCo's STL reader takes at most this many triangles (its OBJ reader has no such limit)."""


def binary_stl_faces(path: str) -> int:
    """The triangle count a binary STL's header announces (0 when unreadable)."""
    import struct

    try:
        with open(path, "rb") as f:
            head = f.read(84)
    except OSError:
        return 0
    return struct.unpack("<I", head[80:84])[0] if len(head) == 84 else 0


def visual_file(mesh, fmt: str) -> str:
    """Path below ``meshes/`` of the file a visual geom of format ``fmt`` references: for MJCF, a
    DAE becomes OBJ (Go1's trunk has 351,394 triangles, past what MuJoCo's STL reader takes),
    an ASCII STL binary STL, and a binary STL with too many triangles OBJ."""
    stem, ext = os.path.splitext(mesh.file_name)
    if fmt == "mjcf" and ext.lower() not in MJCF_VISUAL_EXT:
        return f"mjcf/{stem}.obj"
    if fmt == "mjcf" and ext.lower() == ".stl" and not mesh.processed:
        if is_ascii_stl(mesh.source):
            return f"mjcf/{stem}.stl"
        if binary_stl_faces(mesh.source) > MJCF_STL_FACES:
            return f"mjcf/{stem}.obj"
    return mesh.path


def collision_file(mesh) -> str:
    """Path below ``meshes/`` of the OBJ a collision geom references (every format)."""
    if mesh.folder == "collision" and mesh.file_name.lower().endswith(".obj"):
        return mesh.path
    return f"collision/{os.path.splitext(mesh.file_name)[0]}.obj"


def conversions(robot) -> dict[str, tuple[str, tuple[float, float, float]]]:
    """Files to convert: path below ``meshes/`` -> (source file, scale to apply to it)."""
    out: dict = {}
    for link in robot.links:
        for g in link.visuals:
            m = g.shape.mesh
            if g.shape.kind == "mesh" and not m.processed and visual_file(m, "mjcf") != m.path:
                out.setdefault(visual_file(m, "mjcf"), (m.source, (1.0, 1.0, 1.0)))
        for fmt in ("urdf", "sdf", "mjcf"):
            for g in link.collisions_for(fmt):
                m = g.shape.mesh
                if g.shape.kind == "mesh" and collision_file(m) != m.path:  # not a proxy: its task writes OBJ
                    # a processed visual is in metres: convert its source the same way
                    out.setdefault(collision_file(m), (m.source, m.scale if m.processed else (1.0, 1.0, 1.0)))
    return dict(sorted(out.items()))
