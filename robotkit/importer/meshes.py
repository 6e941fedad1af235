"""Mesh resolution for the importer: ``package://`` and relative URIs to files (through the
declared package paths), where the recipe references them or copies them, and which meshes
need ``open_mesh: hull`` because an inertial is computed from a mesh that is not closed."""

from __future__ import annotations

import glob
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from robotkit.errors import MeshError, display_path
from robotkit.importer.package_xml import find_package_xml
from robotkit.importer.parsing import Problems
from robotkit.mesh.io import load_mesh, volume_mesh

MESH_FORMATS = (".stl", ".obj", ".dae")


@dataclass
class MeshUse:
    """One mesh file named by the URDF: where it is and where the recipe points."""

    source: str  # absolute path of the file found
    recipe_path: str  # absolute path the recipe names (source, or its copy)
    scale: tuple[float, float, float]
    element: object = None  # the URDF's <mesh> element


LICENCE_FILES = ("LICENSE*", "LICENCE*", "COPYING*")
"""A package's licence files, copied with its meshes."""


class MeshResolver:
    """Where the meshes a URDF names are, and where the recipe points: at them, or at copies
    below the recipe's folder (``meshes/PKG/...``, with the package's licence) for those
    ``copy(path)`` says (every mesh with ``--copy-meshes``; by default those outside the
    project, which its build may not read)."""

    def __init__(self, source: Path, recipe_dir: Path, packages: dict[str, str], copy: bool | Callable[[str], bool]):
        self.source = source
        self.recipe_dir = recipe_dir
        self.packages = packages
        self.copy = copy if callable(copy) else (lambda path, every=bool(copy): every)
        self.copies: dict[str, str] = {}  # destination -> source
        self._dest_of: dict[str, str] = {}

    def leaves_package(self, uri: str) -> str | None:
        """The package a ``package://PKG/../..`` URI climbs out of, when its copy would land
        outside the recipe's ``meshes/`` folder."""
        m = re.match(r"^(package|model):///?([^/]+)/(.+)$", uri)
        if m and os.path.normpath(os.path.join(m.group(2), m.group(3))).split(os.sep)[0] == "..":
            return m.group(2)
        return None

    def locate(self, uri: str, link: str, problems: Problems, line: int | None = None) -> str | None:
        """Absolute path of the file ``uri`` names, or None with a problem (at the naming element's
        ``line``)."""
        path = None
        m = re.match(r"^(package|model):///?([^/]+)/(.+)$", uri)  # package:///PKG/: Pinocchio's reading
        if m:
            pkg, rest = m.group(2), m.group(3)
            if pkg not in self.packages:
                problems.add(f"link '{link}': mesh '{uri}': package '{pkg}' not found; "
                             f"give --package-path {pkg}=DIR", line)
                return None
            path = os.path.join(self.packages[pkg], rest)
        elif uri.startswith("file://"):
            path = uri[len("file://"):]
            if not os.path.isabs(path):
                path = os.path.join(self.source.parent, path)
        elif re.match(r"^[A-Za-z][A-Za-z0-9+.\-]*://", uri):
            problems.add(f"link '{link}': mesh '{uri}': unsupported URI scheme "
                         "(use package://, file:// or a path)", line)
            return None
        else:
            path = uri if os.path.isabs(uri) else os.path.join(self.source.parent, uri)
        path = os.path.normpath(path)
        if not os.path.isfile(path):
            problems.add(f"link '{link}': mesh '{uri}' not found (looked for {display_path(path)})", line)
            return None
        if os.path.splitext(path)[1].lower() not in MESH_FORMATS:
            problems.add(f"link '{link}': mesh '{uri}' has an unsupported format (robotkit reads STL, OBJ and DAE)", line)
            return None
        return path

    def destination(self, path: str, uri: str) -> str:
        """Where the recipe points for the file at ``path`` (a copy below the recipe, or it)."""
        if not self.copy(path):
            return path
        if path in self._dest_of:
            return self._dest_of[path]
        m = re.match(r"^(package|model):///?(.+)$", uri)
        package = self.packages.get(m.group(2).split("/")[0]) if m else None
        if m:
            rel = m.group(2)
        else:
            found = find_package_xml(Path(path))
            package = str(found.parent) if found is not None else None
            rel = (os.path.join(os.path.basename(package), os.path.relpath(path, package)) if package
                   else os.path.basename(path))
        dest = os.path.normpath(os.path.join(self.recipe_dir, "meshes", rel))
        stem, ext = os.path.splitext(dest)
        i = 2
        while dest in self.copies and self.copies[dest] != path:
            dest, i = f"{stem}_{i}{ext}", i + 1
        self.copies[dest] = path
        self._dest_of[path] = dest
        if package is not None:
            self._licence(package, os.path.normpath(os.path.join(self.recipe_dir, "meshes", rel.split("/")[0])))
        return dest

    def _licence(self, package: str, dest_dir: str) -> None:
        """The package's licence files next to its copied meshes (not its package.xml, which would
        make the copy a second package for colcon; its licence is in the recipe's metadata)."""
        found = sorted(f for pattern in LICENCE_FILES for f in glob.glob(os.path.join(glob.escape(package), pattern))
                       if os.path.isfile(f))
        for f in found:
            self.copies.setdefault(os.path.join(dest_dir, os.path.basename(f)), f)

    def recipe_text(self, dest: str) -> str:
        return Path(os.path.relpath(dest, self.recipe_dir)).as_posix()



_CLOSED: dict[tuple, bool] = {}


def never_volume(mesh) -> bool:
    """Whether no repair of robotkit's mesh task (robotkit.mesh.repair) can make ``mesh`` a closed
    volume, known without running it: after the repair's clean-up (vertices merged, duplicate and
    degenerate faces removed) an edge is shared by more than two faces.  The repair's later steps
    only flip faces (winding) or add them (hole filling), so such an edge stays; testing this first
    spares the winding fix, a loop over faces that takes minutes on a 351k-face CAD export."""
    import numpy as np
    import trimesh  # late: heavy, and only an import that reads meshes needs it

    vertices = np.asarray(mesh.vertices, dtype=np.float64).reshape(-1, 3)
    faces = np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3)
    if not len(faces) or not np.isfinite(vertices).all():
        return False  # the repair's own answer (it drops faces with non-finite vertices first)
    m = trimesh.Trimesh(vertices, faces, process=False, validate=False)
    m.merge_vertices(merge_tex=True, merge_norm=True)
    m.update_faces(m.unique_faces())
    m.update_faces(m.nondegenerate_faces())
    if not len(m.faces):
        return False
    counts = np.unique(np.sort(np.asarray(m.edges), axis=1), axis=0, return_counts=True)[1]
    return bool((counts > 2).any())


def mesh_is_closed(source: str, scale) -> bool:
    """Whether robotkit's mesh task accepts the mesh without ``open_mesh: hull``."""
    st = os.stat(source)
    key = (source, tuple(scale), st.st_mtime_ns, st.st_size)
    if key not in _CLOSED:
        mesh = load_mesh(source, scale)
        try:
            _CLOSED[key] = not never_volume(mesh)
            if _CLOSED[key]:
                volume_mesh(mesh, "error", os.path.basename(source))
        except MeshError:
            _CLOSED[key] = False
    return _CLOSED[key]


def mark_open_meshes(conv, recipe: dict, warnings: list[str], recompute: bool) -> None:
    """A mesh that is not a closed volume needs ``open_mesh: hull`` only where an inertial is
    computed from it (robotkit accepts open meshes that are only drawn and collided)."""
    open_by_link: dict[str, list[tuple[str, str]]] = {}
    for (link, kind, _i), use in conv.meshes.items():
        if not mesh_is_closed(use.source, use.scale):
            names = open_by_link.setdefault(link, [])
            if (kind, os.path.basename(use.source)) not in names:
                names.append((kind, os.path.basename(use.source)))
    top_level = []
    for link, found in open_by_link.items():
        spec = recipe["links"][link].get("inertial")
        if spec == "none" or (isinstance(spec, dict) and ("inertia" in spec or spec.get("policy") == "estimate")
                              and spec.get("policy") != "recompute"):
            continue  # no inertial is computed from the link's geometry (an estimate reads only its hull)
        source = spec.get("source", "visual") if isinstance(spec, dict) else "visual"
        read = [name for kind, name in found if kind == source]
        if not read:
            continue
        files = ", ".join(dict.fromkeys(read))
        if isinstance(spec, dict):
            spec["open_mesh"] = "hull"
            warnings.append(f"link '{link}': mesh {files} is not a closed volume; its recomputed inertial "
                            "uses the convex hull (open_mesh: hull)")
        else:
            top_level.append(f"{link} ({files})")
    if top_level:
        recipe["open_mesh"] = "hull"
        warnings.append("meshes that are not closed volumes on links whose inertial is computed from them: "
                        f"{'; '.join(top_level)}; the recipe sets open_mesh: hull")
