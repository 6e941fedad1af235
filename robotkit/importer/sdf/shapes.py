"""SDF visuals, collisions, materials and inertials as a recipe link's, in the link's recipe frame.

box, cylinder, sphere and mesh (its scale; ``model://`` URIs found on the model path) map one to
one; a capsule is a cylinder and two spheres (the same solid); an ellipsoid is the box of its
half-axes (stated); a plane, heightmap or polyline is dropped (stated).  A visual's material is
its diffuse colour (else ambient) and its Gazebo script name.  An inertial no real body has (SDF
files carry them: simple_arm, create) is recomputed from the link's geometry as the URDF import
does (robotkit.importer.inertials.chosen_inertial), keeping the mass, stated."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from robotkit.importer.inertials import chosen_inertial
from robotkit.importer.names import material_name
from robotkit.importer.sdf.frames import pose_of
from robotkit.importer.sdf.model import children
from robotkit.importer.sdf.tree import origin_of
from robotkit.recipe.schema import MAX_MASS, MIN_LENGTH, MIN_MASS

PRIMITIVES = ("box", "cylinder", "sphere")
GAZEBO_COLOURS = {"Gazebo/White": "1 1 1", "Gazebo/Grey": "0.7 0.7 0.7", "Gazebo/DarkGrey": "0.175 0.175 0.175",
                  "Gazebo/FlatBlack": "0.1 0.1 0.1", "Gazebo/Black": "0 0 0", "Gazebo/Red": "1 0 0",
                  "Gazebo/Green": "0 1 0", "Gazebo/Blue": "0 0 1", "Gazebo/Yellow": "1 1 0", "Gazebo/Purple": "1 0 1",
                  "Gazebo/Turquoise": "0 1 1", "Gazebo/Orange": "1 0.5088 0.0468"}
"""The diffuse colour of Gazebo classic's standard materials (gazebo-classic's media/materials/scripts/gazebo.material: the values checked against that file),
for a visual that names one and gives no colour: the other formats' colour."""


def add_shapes(src, m, tree, out: Path, ledger, materials: dict, repaired: dict) -> list[str]:
    """Each SDF link's shapes and inertial into its recipe link; the mesh files read."""
    files: list[str] = []
    for name, link in m.links.items():
        O = np.linalg.inv(tree.offset(name, link.T))  # SDF link frame -> recipe frame
        entry = tree.links[name]
        visual = []
        for v in children(link.el, "visual"):
            mat = _material(src, v, materials, ledger)
            visual += [dict(s, material=mat) if mat else s for s in _shape(src, v, O, out, ledger, files, "visual")]
        collision = [s for c in children(link.el, "collision") for s in _shape(src, c, O, out, ledger, files,
                                                                                 "collision")]
        if visual:
            entry["visual"] = visual if len(visual) > 1 else visual[0]
        bare = [{k: v for k, v in s.items() if k != "material"} for s in visual]
        if collision != bare:
            entry["collision"] = (collision if len(collision) > 1 else collision[0]) if collision else "none"
        _inertial(src, name, link, O, entry, collision, visual, ledger, repaired, tree.scaled)
        given = link.el.find("inertial")
        if given is not None and given.find("inertia") is None and link.mass > 0 and name not in repaired:
            tree.link_notes[name] = ("the SDF gives its mass and no <inertia>: SDF's default moments, 1 kg m^2 "
                                     "about each axis, as Gazebo simulates it")
    return files


def _shape(src, el, O, out_path: Path, ledger, files: list, kind: str) -> list[dict]:
    geometry = el.find("geometry")
    _, P = pose_of(el)
    T = O @ P
    shape = next((g for g in (geometry if geometry is not None else []) if isinstance(g.tag, str)), None)
    label = f"{kind} '{el.get('name', '')}' of link '{src.link_of(el)}'"
    if shape is None:
        return []
    thin: list[float] = []

    def num(tag: str, d: str = "0") -> list[float]:
        """The numbers of ``tag``; a length under the recipe's least (a box 0 thick, which
        libsdformat and Gazebo take) written as that, noted in ``thin``."""
        values = [float(x) for x in (shape.findtext(tag) or d).split()]
        thin.extend(v for v in values if 0 <= v < MIN_LENGTH)
        return [MIN_LENGTH if 0 <= v < MIN_LENGTH else v for v in values]

    out = _primitive(src, el, shape, T, num, ledger, label, kind)
    if thin:
        ledger.add(src.where_el(kind, el), f"{label} ({shape.tag})", "all", f"approximated: its length"
                   f"{'s' if len(thin) > 1 else ''} {', '.join(f'{v:g}' for v in thin)} written {MIN_LENGTH:g} m, "
                   "the least the recipe takes")
    if out is not None:
        return out
    if shape.tag == "mesh":
        return _mesh(src, el, shape, T, out_path, ledger, files, label, kind)
    ledger.add(src.where_el(kind, el), f"{label} ({shape.tag})", "all", "dropped: the recipe has no such shape")
    return []


def _primitive(src, el, shape, T, num, ledger, label: str, kind: str) -> list[dict] | None:
    """A box, cylinder, sphere, capsule or ellipsoid as the recipe's shapes; None for another."""
    if shape.tag in PRIMITIVES:
        spec = {"box": lambda: {"size": num("size", "1 1 1")}, "sphere": lambda: {"radius": num("radius", "1")[0]},
                "cylinder": lambda: {"radius": num("radius", "1")[0], "length": num("length", "1")[0]}}
        return [_at({shape.tag: spec[shape.tag]()}, T)]
    if shape.tag == "capsule":
        r, h = num("radius", "0.5")[0], num("length", "1")[0]
        ends = [T @ np.array([0, 0, s * h / 2, 1.0]) for s in (-1, 1)]
        return [_at({"cylinder": {"radius": r, "length": h}}, T)] + [
            _at({"sphere": {"radius": r}}, _moved(e[:3])) for e in ends]
    if shape.tag == "ellipsoid":
        radii = num("radii", "1 1 1")
        ledger.add(src.where_el(kind, el), f"{label} (ellipsoid)", "all",
                   "approximated: the box of its half-axes " + " ".join(f"{r:g}" for r in radii))
        return [_at({"box": {"size": [2 * r for r in radii]}}, T)]
    return None


def _moved(p) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = p
    return T


def _at(shape: dict, T) -> dict:
    o = origin_of(T)
    return dict(shape, origin=o) if o else shape


def mesh_file(src, uri: str) -> Path | None:
    """The file a mesh URI names: ``model://NAME/...`` on the model path, ``file://``, or relative."""
    if uri.startswith("model://"):
        return (src.model_path / uri[len("model://"):]) if src.model_path else None
    if uri.startswith("file://"):
        return Path(uri[len("file://"):])
    return src.path.parent / uri if "://" not in uri else None


def _mesh(src, el, shape, T, out: Path, ledger, files, label: str, kind: str) -> list[dict]:
    uri = (shape.findtext("uri") or "").strip()
    file = mesh_file(src, uri)
    if file is None or not file.is_file():
        ledger.add(src.where_el(kind, el), f"{label} (mesh {uri})", "all", "dropped: its file is not found")
        return []
    if shape.find("submesh") is not None:
        ledger.add(src.where_el(kind, el), f"{label} (mesh {uri})", "all",
                   "approximated: the whole mesh file (the recipe names no submesh)")
    files.append(str(file.resolve()))
    out_shape = {"mesh": Path(os.path.relpath(file.resolve(), out.parent)).as_posix()}
    scale = [float(v) for v in (shape.findtext("scale") or "1 1 1").split()]
    if 0.0 in scale:  # a mesh flattened: libsdformat and Gazebo take it, the recipe does not
        ledger.add(src.where_el(kind, el), f"{label} (mesh {uri})", "all", f"approximated: its scale "
                   f"{' '.join(f'{v:g}' for v in scale)} written with {MIN_LENGTH:g} for 0")
        scale = [v or MIN_LENGTH for v in scale]
    if scale != [1.0, 1.0, 1.0]:
        out_shape["scale"] = scale[0] if len(set(scale)) == 1 else scale
    return [_at(out_shape, T)]


def _material(src, el, materials: dict, ledger) -> str | None:
    mat = el.find("material")
    if mat is None:
        return None
    script = (mat.findtext("script/name") or "").strip()
    text = mat.findtext("diffuse") or mat.findtext("ambient") or GAZEBO_COLOURS.get(script)
    if text is None and not script:
        return None
    if text is None and script not in src.unknown_scripts:
        src.unknown_scripts.add(script)
        ledger.add(src.where_el("visual", el), f"material script '{script}'",
                   "URDF, MJCF", "approximated: white (a Gazebo material script without a colour; model.sdf names it)")
    rgba = [float(v) for v in (text or "1 1 1 1").split()] + [1.0]
    rgba = [min(max(v, 0.0), 1.0) for v in rgba[:4]]
    value = {"rgba": rgba, **({"gazebo": script} if script else {})}
    for known, v in materials.items():
        if v == value:
            return known
    base = script.replace("/", "_") if script else "rgba_" + "_".join(f"{v:g}" for v in rgba).replace(".", "p")
    key = material_name(base, set(materials))
    materials[key] = value
    return key


def _inertial(src, name, link, O, entry: dict, collision, visual, ledger, repaired: dict, scaled: set) -> None:
    R, com = O[:3, :3], O[:3, :3] @ link.com + O[:3, 3]
    I = R @ link.inertia @ R.T
    given = {"mass": link.mass, "com": [float(v) for v in com], "inertia": {
        "ixx": I[0, 0], "iyy": I[1, 1], "izz": I[2, 2], "ixy": I[0, 1], "ixz": I[0, 2], "iyz": I[1, 2]}}
    given["inertia"] = {k: float(v) + 0.0 for k, v in given["inertia"].items()}
    prims = lambda shapes: shapes and all(any(k in s for k in PRIMITIVES) for s in shapes)  # noqa: E731
    source = "collision" if prims(collision) else "visual" if prims(visual) else None
    notes: dict[str, str] = {}
    if link.mass <= 0:
        return
    bound = MIN_MASS if link.mass < MIN_MASS else MAX_MASS if link.mass > MAX_MASS else None
    if bound is not None:  # libsdformat and Gazebo take any mass; the recipe takes 1e-9 to 1e6 kg
        given["mass"], scale = bound, bound / link.mass
        given["inertia"] = {k: v * scale for k, v in given["inertia"].items()}
        scaled.add(name)
        ledger.add(src.where("link", name), f"link '{name}' mass {link.mass:g} kg", "all", f"approximated: "
                   f"written {bound:g} kg, the {'least' if bound == MIN_MASS else 'largest'} the recipe takes (its "
                   "moments scaled alike)")
    spec = chosen_inertial(name, given, source, "recompute", notes)
    if spec is not None:
        entry["inertial"] = spec
    if name in notes:
        repaired[name] = notes[name]
        ledger.add(src.where("link", name), f"link '{name}' inertial", "all", notes[name])
