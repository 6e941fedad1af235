"""Loading mesh files, and making them closed volumes for mass properties.

trimesh returns wrong mass properties without a warning for meshes that are
not closed, consistently wound volumes (docs/libraries.md, section 3), so every mesh
used for an inertial goes through :func:`volume_mesh`: safe repairs first,
then the recipe's policy (convex hull with a warning, or an error).
"""

from __future__ import annotations

import os
from collections import OrderedDict

import numpy as np

from robotkit.errors import MeshError, Problem

SUPPORTED = (".stl", ".obj", ".dae")
MAX_MESH_BYTES = 256 * 2**20
"""Largest mesh file decoded (checked before it is read)."""
MAX_EXTENT = 1e4
"""Farthest a mesh vertex may lie from the mesh's origin, in metres once scaled (10 km)."""


def load_mesh(path: str, scale=(1.0, 1.0, 1.0), where: Problem | None = None):
    """Load ``path`` as one triangle mesh in metres (coordinates times ``scale``).

    ``where`` locates the recipe key that names the file, for error messages.
    """
    import trimesh

    def fail(msg: str) -> MeshError:
        base = where or Problem("")
        return MeshError(Problem(msg, file=base.file, line=base.line, key=base.key))

    name = os.path.basename(path)
    ext = os.path.splitext(path)[1].lower()
    if ext not in SUPPORTED:
        raise fail(f"mesh file '{name}' has an unsupported format (use STL, OBJ or DAE)")
    if not os.path.isfile(path):
        raise fail(f"mesh file '{name}' does not exist")
    size = os.path.getsize(path)
    if size > MAX_MESH_BYTES:
        raise fail(f"mesh file '{name}' is {size:,} bytes; robotkit reads meshes of at most {MAX_MESH_BYTES:,} bytes")
    if ext == ".stl":
        problem = _stl_problem(path)
        if problem:
            raise fail(f"mesh file '{name}' {problem}")
    vertices, faces = _parsed(path, ext, fail)
    vertices = np.asarray(vertices, dtype=np.float64)
    if not np.isfinite(vertices).all():
        raise fail(f"mesh file '{name}' has vertices that are not finite numbers (NaN or inf)")
    scale = np.asarray(scale, dtype=np.float64)
    vertices = vertices * scale
    reach = float(np.abs(vertices).max())
    if not reach <= MAX_EXTENT:
        raise fail(f"mesh file '{name}' reaches {reach:.3g} m from its origin once scaled; robotkit takes meshes "
                   f"within {MAX_EXTENT:g} m (check its units or scale)")
    mesh = trimesh.Trimesh(vertices, faces.copy(), process=True)
    if np.prod(scale) < 0:  # a mirroring scale turns the winding inside out
        mesh.invert()
    return mesh


PARSED_BYTES = 128 * 2**20
"""Most bytes of parsed mesh files :func:`_parsed` keeps (a build reads a file for its facts, at
each scale it is used at, and again to convert it)."""
PARSED: OrderedDict = OrderedDict()
"""(path, size, mtime, inode) -> (vertices, faces), read-only: the files :func:`_parsed` keeps."""


def _parsed(path: str, ext: str, fail) -> tuple[np.ndarray, np.ndarray]:
    """The vertices and faces of a mesh file as trimesh reads it (``process=False``: nothing
    merged or dropped), kept for this process while the file keeps its size, time and inode:
    what :func:`load_mesh` does with them is done again, the same, for each call."""
    import trimesh

    name = os.path.basename(path)
    stat = os.stat(path)
    key = (os.path.realpath(path), stat.st_size, stat.st_mtime_ns, stat.st_ino)
    if key in PARSED:
        PARSED.move_to_end(key)
        return PARSED[key]
    try:
        if ext == ".dae":
            loaded = _dae_in_metres(path)
        else:
            loaded = trimesh.load(path, force="mesh", process=False)  # process would drop NaN faces unseen
    except Exception as exc:  # trimesh raises many kinds on corrupt input
        raise fail(f"cannot read mesh file '{name}': {type(exc).__name__}: {exc}".rstrip(": ")) from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise fail(f"mesh file '{name}' holds no triangles")
    parsed = np.array(loaded.vertices), np.array(loaded.faces)
    for a in parsed:
        a.flags.writeable = False
    _keep(key, parsed)
    return parsed


def remember_written_obj(path: str, vertices: np.ndarray, faces: np.ndarray) -> None:
    """Keep, as :func:`_parsed` would read it back, the OBJ file robotkit just wrote at ``path``
    from ``vertices`` and ``faces`` (:func:`robotkit.mesh.export.obj_bytes` of a mesh
    :func:`load_mesh` gave: its numbers exact, every vertex referenced, faces in order, no
    texture: trimesh reads back the same arrays, -0.0 as 0.0 as written; tested), so that the
    build's later readers of the file (an MJCF's lowest point) do not parse it again."""
    stat = os.stat(path)
    key = (os.path.realpath(path), stat.st_size, stat.st_mtime_ns, stat.st_ino)
    parsed = np.asarray(vertices, dtype=np.float64) + 0.0, np.array(faces, dtype=np.int64)
    for a in parsed:
        a.flags.writeable = False
    _keep(key, parsed)


def _keep(key: tuple, parsed: tuple[np.ndarray, np.ndarray]) -> None:
    PARSED[key] = parsed
    PARSED.move_to_end(key)
    while sum(v.nbytes + f.nbytes for v, f in PARSED.values()) > PARSED_BYTES and len(PARSED) > 1:
        PARSED.popitem(last=False)


def _dae_in_metres(path: str):
    """A COLLADA file as one mesh in metres: its ``<unit meter="...">`` applied, as RViz and
    Gazebo apply it (trimesh reads the unit but leaves the coordinates in file units)."""
    import trimesh

    scene = trimesh.load(path, force="scene", process=False)
    if not scene.geometry:
        scene = _dae_unbound(path) or scene
    units = getattr(scene, "units", None)
    if units and units not in ("meters", "m", "meter"):
        scene = scene.convert_units("meters", guess=False)
    geometry = scene.to_geometry() if hasattr(scene, "to_geometry") else scene.dump(concatenate=True)
    return geometry


def _dae_unbound(path: str):
    """A COLLADA file read without its ``<bind_material>`` elements (None when it does not parse):
    pycollada drops a whole node whose binding names a material the file lacks (ANYmal B's
    anymal_foot.dae, a Blender export whose texture's effect is broken, read as no triangles),
    where Assimp (RViz, Gazebo) draws its geometry with a default material."""
    import io

    import trimesh

    from robotkit.urdfxml import MalformedXML, parse_file

    try:
        tree = parse_file(path)
    except (MalformedXML, OSError):
        return None
    bindings = list(tree.getroot().iter("{*}bind_material"))
    if not bindings:
        return None
    for element in bindings:
        element.getparent().remove(element)
    from lxml import etree  # loaded already by parse_file

    return trimesh.load(io.BytesIO(etree.tostring(tree)), file_type="dae", force="scene", process=False)


def companions(path: str) -> list[str]:
    """Files a mesh file references and its viewers load beside it, as relative paths: a
    COLLADA file's images (``<init_from>``), an OBJ's material library and that library's
    texture maps.  Only existing files named by relative paths (no absolute paths, no URIs);
    they may climb out of the mesh's folder (a Gazebo model's ``../materials/textures/``): where a
    copy of the mesh needs them, relative to it.  Reads text only (cheap)."""
    import re

    folder = os.path.dirname(os.path.abspath(path))
    ext = os.path.splitext(path)[1].lower()

    def text(p: str) -> str:
        try:
            with open(p, encoding="utf-8", errors="replace") as f:
                return f.read(4_000_000)
        except OSError:
            return ""

    names: list[str] = []
    if ext == ".dae":
        names = re.findall(r"<init_from>\s*([^<]+?)\s*</init_from>", text(path))
    elif ext == ".obj":
        for lib in re.findall(r"^mtllib\s+(.+?)\s*$", text(path), re.M):
            names.append(lib)
            names += re.findall(r"^\s*(?:map_\w+|bump|disp|decal|refl)\s+(?:-\S+\s+\S+\s+)*(\S+)\s*$",
                                text(os.path.join(folder, lib)), re.M)
    out = []
    for name in names:
        name = name.strip().removeprefix("file://").removeprefix("./")
        if not name or os.path.isabs(name) or "://" in name:
            continue
        name = os.path.normpath(name.replace("\\", "/")).replace(os.sep, "/")
        if os.path.isfile(os.path.join(folder, name)) and name not in out:
            out.append(name)
    return out


def read_vertices(path: str) -> np.ndarray:
    """The vertices of a mesh file, in the file's coordinates (metres for COLLADA)."""
    return np.asarray(load_mesh(path).vertices, dtype=np.float64)


def _stl_problem(path: str) -> str | None:
    """Why a binary STL cannot be complete, or None (ASCII STL is left to the parser)."""
    size = os.path.getsize(path)
    if size == 0:
        return "is empty"
    with open(path, "rb") as f:
        head = f.read(84)
    if head[:5].lower() == b"solid" and b"facet" in open(path, "rb").read(4096):
        return None  # ASCII
    if size < 84:
        return f"is truncated ({size} bytes, shorter than a binary STL header)"
    count = int.from_bytes(head[80:84], "little")
    if size < 84 + 50 * count:
        return (f"is truncated: its header announces {count} triangles "
                f"({84 + 50 * count} bytes), the file has {size} bytes")
    return None


NOTICEABLE = 0.01
"""A hole filling that may change a mesh's volume by more than this fraction is warned about."""


def volume_mesh(mesh, policy: str, name: str, where: Problem | None = None):
    """Return (mesh, repairs, used, warnings) where ``mesh`` is a closed volume.

    ``used`` is ``"mesh"`` or ``"hull"``.  Safe repairs are those that do not
    change the shape: merging vertices, removing duplicate and degenerate
    faces, making the winding consistent and outward.
    """
    repairs: list[str] = []
    warnings: list[str] = []
    if not mesh.is_volume:
        from robotkit.mesh.repair import repair  # late: it imports trimesh (0.8 s), not needed to list companions

        mesh, report = repair(mesh)
        for key, text in (("vertices_merged", "merged {} vertices"),
                          ("duplicate_faces_removed", "removed {} duplicate faces"),
                          ("degenerate_faces_removed", "removed {} degenerate faces"),
                          ("faces_flipped", "flipped {} faces"), ("bodies_inverted", "turned {} bodies outward"),
                          ("holes_filled", "filled {} holes")):
            if report.get(key):
                repairs.append(text.format(report[key]))
        if mesh.is_volume and report["hole_volume_bound"] > NOTICEABLE * abs(mesh.volume):
            warnings.append(
                f"mesh '{name}': filled {report['holes_filled']} holes ({report['hole_area']:.3g} m^2, "
                f"{100 * report['hole_area'] / mesh.area:.2g}% of its surface) with flat patches; if the missing "
                f"surface was not flat, the volume and the mass properties may be off by up to "
                f"{100 * report['hole_volume_bound'] / abs(mesh.volume):.2g}%")
    if mesh.is_volume:
        return mesh, repairs, "mesh", warnings
    reason = _why_not_volume(mesh)
    if policy == "visual-only":  # no inertial depends on it: facts for display only
        return mesh.convex_hull, repairs, "hull", warnings
    if policy == "hull":  # the recipe's choice: a fact of report.json's meshes, not a warning
        repairs.append(f"not a closed volume ({reason}): mass properties from its convex hull (open_mesh: hull), "
                       "which overestimates the volume")
        return mesh.convex_hull, repairs, "hull", warnings
    base = where or Problem("")
    raise MeshError(Problem(
        f"mesh '{name}' is not a closed volume ({reason}), so its mass properties would be wrong; "
        "repair the mesh, give an explicit inertial, or set 'open_mesh: hull'",
        file=base.file, line=base.line, key=base.key))


def _why_not_volume(mesh) -> str:
    import trimesh

    edges = mesh.edges_sorted
    groups = trimesh.grouping.group_rows(edges, require_count=1)
    counts = np.unique(trimesh.grouping.hashable_rows(edges), return_counts=True)[1]
    open_edges = len(groups)
    nonmanifold = int((counts > 2).sum())
    parts = []
    if open_edges:
        parts.append(f"{open_edges} open edges")
    if nonmanifold:
        parts.append(f"{nonmanifold} non-manifold edges")
    if not parts and not mesh.is_winding_consistent:
        parts.append("inconsistent winding")
    if not parts:
        parts.append(f"volume {mesh.volume:.3g} m^3")
    return ", ".join(parts)
