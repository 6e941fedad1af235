"""MuJoCo geoms as a link's visual and collision shapes, and the materials they wear.

A geom collides when its ``contype`` or ``conaffinity`` is set, and is seen when its group is
one MuJoCo shows by default (0, 1, 2): a geom that does both is a visual and a collision shape,
one that does neither is dropped (on the ledger).  Shapes come from the compiled model, so
``fromto``, default classes and frames arrive resolved.  A mesh keeps its file and scale; MuJoCo
moves a mesh's vertices to its inertial frame (``mesh_pos``, ``mesh_quat``) and the geom with
them, so the shape's origin is the compiled geom's pose with that move undone: where the file's
own vertices sit.  A capsule is a cylinder and two spheres (the same solid); an ellipsoid is the
box of its half-axes (stated)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from robotkit.importer.mjcf.frames import compose, inverse, origin, quat_matrix
from robotkit.importer.names import material_name

PLANE, HFIELD, SPHERE, CAPSULE, ELLIPSOID, CYLINDER, BOX, MESH = range(8)
KINDS = {PLANE: "plane", HFIELD: "hfield", SPHERE: "sphere", CAPSULE: "capsule", ELLIPSOID: "ellipsoid",
         CYLINDER: "cylinder", BOX: "box", MESH: "mesh", 8: "sdf"}
SHOWN_GROUPS = (0, 1, 2)


def geom_label(m, g: int, kind: str = "") -> str:
    """``geom 'name' (kind)``, or ``geom #id (kind)`` for an unnamed one."""
    name = m.geom(g).name
    return (f"geom '{name}'" if name else f"geom #{g}") + (f" ({kind})" if kind else "")


def add_geoms(src, tree, out: Path, ledger, materials: dict) -> None:
    """Each geom into its body's link (``visual`` / ``collision`` lists), then each link's lists
    as the recipe writes them."""
    m = src.model
    shapes: dict[str, dict[str, list]] = {}
    for g in range(m.ngeom):
        b = int(m.geom_bodyid[g])
        link = tree.link_of.get(b)
        if link is None:
            ledger.add(src.geom_where(g), geom_label(m, g), "all", "dropped: a shape of the world body "
                       "(the recipe describes the robot)")
            continue
        collides = bool(m.geom_contype[g] or m.geom_conaffinity[g])
        shown = int(m.geom_group[g]) in SHOWN_GROUPS
        kind = KINDS.get(int(m.geom_type[g]), str(m.geom_type[g]))
        if not (collides or shown):
            ledger.add(src.geom_where(g), geom_label(m, g, kind), "all",
                       f"dropped: group {int(m.geom_group[g])} and no contacts (neither seen nor colliding)")
            continue
        made = _shapes(src, g, tree.offset[b], out, ledger)
        if not made:
            continue
        entry = shapes.setdefault(link, {"visual": [], "collision": []})
        if shown:
            mat = _material(src, g, materials, ledger)
            entry["visual"].extend(dict(s, material=mat) if mat else s for s in made)
        if collides:
            entry["collision"].extend(made)
    for name, link in tree.links.items():
        entry = shapes.get(name, {"visual": [], "collision": []})
        if entry["visual"]:
            link["visual"] = entry["visual"] if len(entry["visual"]) > 1 else entry["visual"][0]
        bare = [{k: v for k, v in s.items() if k != "material"} for s in entry["visual"]]
        if entry["collision"] != bare:
            c = entry["collision"]
            link["collision"] = (c if len(c) > 1 else c[0]) if c else "none"


def _shapes(src, g: int, offset, out: Path, ledger) -> list[dict]:
    m = src.model
    t = int(m.geom_type[g])
    size = [float(v) for v in m.geom_size[g]]
    pos, R = np.array(m.geom_pos[g], float) - offset, quat_matrix(m.geom_quat[g])
    if t == SPHERE:
        return [_at({"sphere": {"radius": size[0]}}, pos, R)]
    if t == CYLINDER:
        return [_at({"cylinder": {"radius": size[0], "length": 2 * size[1]}}, pos, R)]
    if t == BOX:
        return [_at({"box": {"size": [2 * s for s in size]}}, pos, R)]
    if t == CAPSULE:
        ends = [pos + R @ np.array([0, 0, s * size[1]]) for s in (-1, 1)]
        return [_at({"cylinder": {"radius": size[0], "length": 2 * size[1]}}, pos, R)] + [
            _at({"sphere": {"radius": size[0]}}, e, np.eye(3)) for e in ends]
    if t == ELLIPSOID:
        ledger.add(src.geom_where(g), geom_label(m, g, "ellipsoid"), "all",
                   "approximated: the box of its half-axes " + " ".join(f"{s:g}" for s in size))
        return [_at({"box": {"size": [2 * s for s in size]}}, pos, R)]
    if t == MESH:
        return _mesh(src, g, pos, R, out, ledger)
    ledger.add(src.geom_where(g), geom_label(m, g, KINDS.get(t, str(t))), "all",
               "dropped: the recipe has no such shape")
    return []


def _at(shape: dict, pos, R) -> dict:
    o = origin(pos, R)
    return dict(shape, origin=o) if o else shape


def _mesh(src, g: int, pos, R, out: Path, ledger) -> list[dict]:
    m = src.model
    d = int(m.geom_dataid[g])
    file = src.mesh_file(d)
    if file is None:
        ledger.add(src.geom_where(g), geom_label(m, g, f"mesh '{m.mesh(d).name}'"), "all",
                   "dropped: a mesh given by its vertices in the file (no mesh file to name)")
        return []
    back_p, back_R = inverse(m.mesh_pos[d], quat_matrix(m.mesh_quat[d]))
    p, Rm = compose(pos, R, back_p, back_R)  # undo MuJoCo's move of the mesh to its inertial frame
    scale = [float(v) for v in m.mesh_scale[d]]
    ref_p, ref_R = src.mesh_ref(d)  # MuJoCo reads the file's vertices as scale * ref_R^T (v - ref_p)
    if len(set(scale)) > 1 and not np.allclose(ref_R, np.eye(3)):
        ledger.add(src.geom_where(g), geom_label(m, g, f"mesh '{m.mesh(d).name}'"), "all",
                   "approximated: refquat with a non-uniform scale (the scale taken along the file's axes)")
    p, Rm = compose(p, Rm, *inverse(np.asarray(scale) * ref_p, ref_R))
    shape = {"mesh": Path(os.path.relpath(file, out.parent)).as_posix()}
    if scale != [1.0, 1.0, 1.0]:
        shape["scale"] = scale[0] if len(set(scale)) == 1 else scale
    return [_at(shape, p, Rm)]


def _material(src, g: int, materials: dict, ledger) -> str | None:
    """The recipe material a visual geom wears: its MJCF material's colour, else its rgba."""
    m = src.model
    mat = int(m.geom_matid[g])
    if mat >= 0:
        rgba = _colour(m.mat_rgba[mat])
        name = m.material(mat).name or f"material{mat}"
        if name not in src.textured_noted and int(m.mat_texid[mat].max()) >= 0:
            src.textured_noted.add(name)
            ledger.add(src.where_named("material", name), f"material '{name}'", "all",
                       "texture dropped: the recipe's material is a colour (its rgba kept)")
    else:
        rgba = _colour(m.geom_rgba[g])
        name = None
    for known, value in materials.items():
        if value["rgba"] == rgba and (name is None or known == name):
            return known
    key = material_name(name or "rgba_" + "_".join(f"{v:g}" for v in rgba).replace(".", "p"), set(materials))
    materials[key] = {"rgba": rgba}
    return key


def _colour(rgba) -> list[float]:
    """MuJoCo keeps colours in float32: each as the shortest decimal that float32 reads back (0.690196,
    not 0.6901959776878357), as the file wrote it."""
    return [float(str(np.float32(v))) for v in rgba]
