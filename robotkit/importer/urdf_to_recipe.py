"""URDF text -> recipe dict -> YAML text.

:func:`urdf_to_recipe` maps URDF semantics onto the recipe schema
(robotkit/recipe/schema.py) without losing what the equivalence check compares:

- ``<origin>`` of visuals, collisions and joints -> ``origin`` (left out when identity);
- an ``<inertial>`` -> an explicit inertial (``mass``, ``com``, ``inertia`` about the COM in
  link axes); an inertial origin with ``rpy`` rotates the tensor into the link frame,
  I_link = R I R^T;
- mesh ``scale`` -> ``units`` (uniform and equal to a known unit) or ``scale``;
  ``package://`` URIs through the package map, relative paths from the input file;
- materials, inline or global, deduplicated by name and colour;
- joints: type, axis (URDF default 1 0 0), limit, dynamics, mimic;
- ``<gazebo reference="LINK">`` material and contact values (mu1, mu2, kp, kd) -> the
  recipe's material ``gazebo`` name and the link's ``contact`` when the recipe can say
  exactly the same; every other top-level element (gazebo, transmission, ros2_control,
  unknown) -> ``urdf_extras``, verbatim.

Floats are kept as parsed and written with ``repr`` (shortest round trip).
"""

from __future__ import annotations

import copy
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robotkit import urdfxml
from robotkit.emit.urdf import MASSLESS
from robotkit.errors import Problem, RobotkitError, short_number
from robotkit.importer.inertials import chosen_inertial, give_moving_links_mass, no_inertial_form, read_inertial
from robotkit.importer import units as mesh_units
from robotkit.importer.meshes import MeshResolver, MeshUse
from robotkit.importer.names import (joints_apart_from_links, material_name, name_hint, valid_frame_name, valid_name,
                                     without_leading_slash)
from robotkit.importer.parsing import (Problems, fmt_list, shown, local_name, origin_dict, read_float, read_floats,
                                       read_origin)
from robotkit.importer.recipe_writer import fmt
from robotkit.geometry import rpy_matrix
from robotkit.recipe.schema import JOINT_TYPES, MAX_LENGTH, MAX_VALUE, MIN_MASS, UNITS

GREY = [0.5, 0.5, 0.5, 1.0]
CONTACT_KEYS = ("mu1", "mu2", "kp", "kd")
is_element = urdfxml.is_element


@dataclass
class Converted:
    recipe: dict
    warnings: list[str] = field(default_factory=list)
    copies: dict[str, str] = field(default_factory=dict)  # destination -> source
    meshes: dict[tuple[str, str, int], MeshUse] = field(default_factory=dict)  # (link, kind, i)
    explicit: dict[str, dict] = field(default_factory=dict)  # link -> the given inertial
    extras: list[str] = field(default_factory=list)  # a short label per verbatim element
    repairs: dict[str, str] = field(default_factory=dict)  # link -> what was wrong and what the recipe does
    joint_notes: dict[str, str] = field(default_factory=dict)  # joint -> what the recipe changes from the original
    left_out: list[str] = field(default_factory=list)  # elements of the original the recipe leaves out, and why


@dataclass
class _Reading:
    """What the stages of one conversion share: where problems and warnings go, the mesh
    resolver, the result being filled, and the inertial options."""

    problems: Problems
    warnings: list[str]
    resolver: MeshResolver
    out: Converted
    recompute_inertials: bool = False
    density: float | None = None
    inertia_policy: str = "repair"
    lines: bool = False  # whether the elements' lines are the input file's (a URDF, not an expanded xacro)
    overrides: dict[str, tuple[str, str]] = field(default_factory=dict)  # link -> (policy, why)
    notes: dict[str, list[str]] = field(default_factory=dict)  # link -> what else the recipe changes
    elements: dict[str, object] = field(default_factory=dict)  # link -> its <link> element

    def line(self, el) -> int | None:
        return el.sourceline if self.lines else None

    def where(self, el) -> str:
        """``file:line: `` of an element of the input, for a warning."""
        line = self.line(el)
        return f"{shown(self.problems.file)}{f':{line}' if line else ''}: "


@dataclass
class _Links:
    """The links read: recipe entries, the recipe materials of each link's visuals, and which
    links have collision geometry (what the Gazebo blocks are mapped against)."""

    links: dict[str, dict] = field(default_factory=dict)
    visual_materials: dict[str, list[str]] = field(default_factory=dict)
    has_collision: dict[str, bool] = field(default_factory=dict)


# ---------------------------------------------------------------- the conversion


def urdf_to_recipe(text: str, source: str | os.PathLike, recipe_path: str | os.PathLike,
                   package_paths: dict[str, str] | None = None, copy_meshes=False,
                   recompute_inertials: bool = False, density: float | None = None,
                   inertia_policy: str = "repair", lines: bool = False,
                   overrides: dict[str, tuple[str, str]] | None = None) -> Converted:
    """Map the URDF ``text`` (read from ``source``) to a recipe dict for ``recipe_path``.
    ``copy_meshes``: whether to copy every mesh below the recipe, or which (a predicate on its
    path).  ``inertia_policy``: what a link whose given tensor no real body has gets
    (:func:`robotkit.importer.inertials.chosen_inertial`); ``overrides``: link -> (policy, why)
    for links whose repaired tensor would not fit their geometry.  ``lines``: whether the
    elements' lines are ``source``'s (warnings and problems then name them).

    Raises RobotkitError with every problem found (one line each, naming links and URIs).
    """
    source = Path(source).absolute()
    recipe_dir = Path(recipe_path).absolute().parent
    root = _robot_element(text, source, lines)
    children = [el for el in root if is_element(el)]
    r = _Reading(Problems(str(source)), [], MeshResolver(source, recipe_dir, dict(package_paths or {}), copy_meshes),
                 Converted(recipe={}), recompute_inertials, density, inertia_policy, lines, dict(overrides or {}))
    robot_name = _robot_name(root.get("name") or source.name.split(".")[0], r.warnings)
    renamed = without_leading_slash(children)
    apart = joints_apart_from_links(children)
    materials = _Materials(children, r.problems, r.warnings)
    links = _links(children, materials, r)
    joints = _joints(children, links.links, r)
    _note_renamed(renamed, r)
    for old, new in apart.items():
        if new in joints:
            _note(new, f"named '{old}' in the original, like a link: links and joints share one namespace in SDF, "
                       "where libsdformat (Gazebo) reads the URDF, so it is renamed here and where mimics and "
                       "transmissions name it", r)
    extras = _extras(children, root, links, joints, materials.materials, r)
    _zero_limits(children, joints, r)
    r.problems.raise_if_any()
    give_moving_links_mass(links.links, joints, r.out)
    for link, why in r.out.repairs.items():
        where = r.where(r.elements[link]) if link in r.overrides else ""
        r.warnings.append(f"{where}link '{link}': {why}")
    for link, notes in r.notes.items():  # said in their own warnings
        r.out.repairs[link] = "; ".join([*notes, *([r.out.repairs[link]] if link in r.out.repairs else [])])
    recipe: dict = {"robot": robot_name, "units": "m", "density": density if density is not None else 1000.0}
    if materials.materials:
        recipe["materials"] = materials.materials
    recipe["links"] = links.links
    if joints:
        recipe["joints"] = joints
    if extras:
        recipe["urdf_extras"] = extras
    r.out.recipe, r.out.warnings, r.out.copies = recipe, r.warnings, dict(r.resolver.copies)
    return r.out


def _note_renamed(renamed: dict[str, tuple[str, str]], r: _Reading) -> None:
    """Each link and joint that lost its leading '/' (robotkit.importer.names.without_leading_slash),
    stated above it in the recipe and in a warning."""
    for old, (kind, new) in renamed.items():
        where = "its joints and gazebo blocks" if kind == "link" else "mimics and transmissions"
        note = (f"named '{old}' in the original: a recipe name cannot start with '/' (the old tf_prefix style), "
                f"so the '/' is dropped here and where {where} name it")
        if kind == "joint":
            _note(new, note, r)
        else:
            r.notes.setdefault(new, []).append(note)
            r.warnings.append(f"link '{new}': {note}")


def _robot_element(text: str, source: Path, lines: bool = False):
    """The <robot> element of the URDF ``text`` (comments kept: verbatim elements keep theirs);
    ``lines``: whether its lines are ``source``'s."""
    try:
        root = urdfxml.parse_text(text, comments=True).getroot()
    except urdfxml.MalformedXML as exc:  # in the words of expat, which read it before lxml
        raise RobotkitError(Problem(f"not well-formed XML: {exc.expat or exc}", file=str(source),
                                    line=exc.expat_line if exc.expat else exc.line)) from None
    if local_name(root.tag) != "robot":
        raise RobotkitError(Problem(f"the root element is <{local_name(root.tag)}>, not <robot>: not a URDF",
                                    file=str(source)))
    if not any(local_name(el.tag) == "link" for el in root if isinstance(el.tag, str)):
        raise RobotkitError(Problem("<robot> defines no <link>: nothing to import", file=str(source),
                                    line=root.sourceline if lines else None))  # example-robot-data's ur3.urdf: an empty xacro output
    return root


def _robot_name(name: str, warnings: list[str]) -> str:
    if valid_name(name):
        return name
    fixed = material_name(name, set())
    warnings.append(f"robot name '{name}' is not a valid recipe name; using '{fixed}'")
    return fixed


class _Materials:
    """The recipe's materials, named as the links' visuals reference them: global ones (the first
    definition of a name wins, as in urdfdom; a definition inside a link's visual joins them for
    the name-only references of the links after it), deduplicated by name and colour."""

    def __init__(self, children: list, problems: Problems, warnings: list[str]):
        self.problems, self.warnings = problems, warnings
        self.global_materials: dict = {}
        for el in children:
            if local_name(el.tag) == "material" and el.get("name") and el.get("name") not in self.global_materials:
                self.global_materials[el.get("name")] = el
        self.materials: dict[str, dict] = {}  # recipe name -> {"rgba": ...}
        self.by_key: dict[tuple, str] = {}  # (urdf name, rgba) -> recipe name
        self.texture_warned: set[str] = set()

    def ref(self, vis_mat, link: str) -> str:
        """The recipe name of a visual's <material>."""
        name = vis_mat.get("name") or ""
        rgba = _rgba(vis_mat, f"link '{link}': material '{name}'", self.problems, self.warnings)
        texture = vis_mat.find("texture")
        if (rgba is not None or texture is not None) and name:  # urdfdom: a link's definition serves later links
            self.global_materials.setdefault(name, vis_mat)
        if rgba is None and name in self.global_materials:
            g = self.global_materials[name]
            rgba = _rgba(g, f"material '{name}'", self.problems, self.warnings)
            texture = texture if texture is not None else g.find("texture")
        self._warn_colour(name, link, rgba, texture)
        rgba = rgba or list(GREY)
        key = (name, tuple(rgba))
        if key not in self.by_key:
            self.by_key[key] = self._new_name(name, rgba)
            self.materials[self.by_key[key]] = {"rgba": rgba}
        return self.by_key[key]

    def _warn_colour(self, name: str, link: str, rgba, texture) -> None:
        """Once per material name: a dropped texture, or no colour at all."""
        if name in self.texture_warned:
            return
        if texture is not None:
            self.texture_warned.add(name)
            if rgba is None:
                self.warnings.append(f"material '{name}' has a texture ({texture.get('filename')}) and no colour; "
                                     "the recipe keeps the name with a grey colour (textures of DAE meshes are kept)")
            else:
                self.warnings.append(f"material '{name}': its texture ({texture.get('filename')}) is dropped; "
                                     "the colour is kept")
        elif rgba is None:
            self.texture_warned.add(name)
            self.warnings.append(f"material '{name}' (link '{link}') has no colour; using grey")

    def _new_name(self, name: str, rgba: list[float]) -> str:
        recipe_name = material_name(name, set(self.materials))
        if recipe_name != name:
            if any(k[0] == name for k in self.by_key):
                self.warnings.append(f"material '{name}' is defined with different colours; "
                                     f"the colour {fmt_list(rgba)} is named '{recipe_name}'")
            else:
                self.warnings.append(f"material name '{name}' is not a valid recipe name; using '{recipe_name}'")
        return recipe_name


# ---------------------------------------------------------------- links


def _links(children: list, materials: _Materials, r: _Reading) -> _Links:
    """Every <link>: its geometry, materials and inertial as recipe entries."""
    found = _Links()
    no_inertial = no_inertial_form()
    for el in children:
        if local_name(el.tag) != "link":
            continue
        name = el.get("name")
        if not valid_frame_name(name):
            r.problems.add(f"link name '{name}' is not a valid recipe name ({name_hint()})")
            continue
        if name in found.links:
            r.problems.add(f"link '{name}' is defined twice")
            continue
        r.elements[name] = el
        visuals, collisions, vis_materials = _link_geometry(el, name, materials, r)
        _mesh_units(el, name, visuals, collisions, r)
        for child in el:
            if is_element(child) and local_name(child.tag) not in ("visual", "collision", "inertial"):
                r.warnings.append(f"link '{name}': <{local_name(child.tag)}> is dropped (the recipe has no place for it)")
        found.visual_materials[name] = vis_materials
        found.has_collision[name] = bool(collisions)
        link: dict = {}
        if visuals:
            link["visual"] = visuals[0] if len(visuals) == 1 else visuals
        if _same_shapes(visuals, collisions):
            pass  # collision: visual (the default)
        elif not collisions:
            if visuals:
                link["collision"] = "none"
        else:
            link["collision"] = collisions[0] if len(collisions) == 1 else collisions
        inertial = _link_inertial(el, name, visuals, collisions, no_inertial, r)
        if inertial is not None:
            link["inertial"] = inertial
        found.links[name] = link
    return found


def _link_geometry(el, name: str, materials: _Materials, r: _Reading) -> tuple[list, list, list]:
    """(visual shapes, collision shapes, recipe materials of the visuals) of a <link>."""
    visuals, collisions, vis_materials = [], [], []
    for kind, items in (("visual", visuals), ("collision", collisions)):
        for g_el in el.findall(kind):
            made = _geometry(g_el, name, kind, len(items), r)
            if made is None:
                continue
            for geom in made if isinstance(made, list) else [made]:
                if kind == "visual":
                    mat = g_el.find("material")
                    if mat is not None:
                        geom["material"] = materials.ref(mat, name)
                        vis_materials.append(geom["material"])
                items.append(geom)
    return visuals, collisions, vis_materials


def _mesh_units(el, name: str, visuals: list, collisions: list, r: _Reading) -> None:
    """A mesh the URDF scales into an implausible part (robotkit.importer.units): the recipe's
    ``units`` when only one unit fits, said in a warning naming the <mesh>'s line either way."""
    mass = _number(el.find("inertial/mass"), "value")
    judged: dict[str, mesh_units.UnitFix | None] = {}
    for key, use in list(r.out.meshes.items()):
        link, kind, i = key
        if link != name:
            continue
        if use.source not in judged:
            alone = len(visuals) == 1 and kind == "visual"  # the link's mass is on this mesh only
            judged[use.source] = fix = mesh_units.judge(name, kind, use, mass if alone and mass else None)
            if fix is not None:
                r.warnings.append(r.where(use.element) + fix.warning)
                if fix.note:
                    r.notes.setdefault(name, []).append(fix.note)
        fix = judged[use.source]
        if fix is not None and fix.unit is not None:
            r.out.meshes[key] = mesh_units.apply(fix, use, visuals + collisions, r.resolver.recipe_text(use.recipe_path))


def _number(el, attr: str) -> float | None:
    """A positive finite number in ``el``'s ``attr``, else None (what is wrong is said elsewhere)."""
    try:
        value = float(el.get(attr)) if el is not None else math.nan
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) and value > 0 else None


def _link_inertial(el, name: str, visuals: list, collisions: list, no_inertial, r: _Reading):
    """The recipe's ``inertial`` of a link, or None when the recipe's default (computed from its
    geometry) says it; the given inertial goes to ``r.out.explicit``."""
    inertial_el = el.find("inertial")
    given = read_inertial(inertial_el, name, r.problems) if inertial_el is not None else None
    if given is not None and 0 < given["mass"] < MIN_MASS and not any(given["inertia"].values()):
        # robotkit's own URDF writes a massless link as 1e-300 kg with no inertia: read back as massless
        if given["mass"] != MASSLESS:
            r.warnings.append(f"link '{name}': mass {given['mass']!r} kg with no inertia, below the smallest mass "
                              f"a recipe takes ({short_number(MIN_MASS)} kg): read as a massless link")
        given = dict(given, mass=0.0)
    if given is not None and given["mass"] > 0:
        r.out.explicit[name] = given
        return _given_inertial(name, given, visuals, collisions, r)
    if given is not None and given["mass"] < 0:
        r.problems.add(f"link '{name}': negative mass {given['mass']!r}")
    if visuals:  # robotkit would compute an inertial from the visual geometry
        if no_inertial is not None:
            return no_inertial
        why = "a zero mass" if given is not None else "no inertial"
        r.warnings.append(f"link '{name}' has {why} in the URDF, but the recipe cannot say 'no inertial' "
                          "for a link with visual geometry: the build computes one from its geometry, "
                          "which adds mass the original does not have")
    return None


def _given_inertial(name: str, given: dict, visuals: list, collisions: list, r: _Reading):
    """The recipe's inertial of a link whose original gives a positive mass: recomputed from its
    geometry (``--recompute-inertials``), else as given or by the inertia policy."""
    if r.recompute_inertials and (visuals or collisions):
        spec: dict = {}  # at the recipe's density, or keeping the given mass
        if collisions and not _same_shapes(visuals, collisions):
            spec["source"] = "collision"
        if r.density is None:
            spec["mass"] = given["mass"]
        return spec or None
    if r.recompute_inertials:
        r.warnings.append(f"link '{name}' has no geometry to compute an inertial from; "
                          "its inertial is kept as given")
    source = ("collision" if collisions and not (visuals and _same_shapes(visuals, collisions))
              else "visual" if visuals else None)
    policy, why = r.overrides.get(name, (r.inertia_policy, ""))
    return chosen_inertial(name, given, source, policy, r.out.repairs, why)


def _rgba(el, what: str, problems: Problems, warnings: list[str]):
    color = el.find("color")
    if color is None or color.get("rgba") is None:
        return None
    rgba = read_floats(color.get("rgba"), 4, f"{what} colour", problems)
    if rgba is None:
        return None
    clamped = [min(1.0, max(0.0, v)) for v in rgba]
    if clamped != rgba:
        warnings.append(f"{what}: colour {color.get('rgba')} is outside 0..1; clamped")
    return clamped


# ---------------------------------------------------------------- geometry


def _geometry(el, link: str, kind: str, index: int, r: _Reading) -> dict | list[dict] | None:
    """The recipe shape (a list of them for a capsule) of a <visual> or <collision>, with its
    origin; None, with a problem or a warning, when it has none the recipe can take."""
    what = f"link '{link}' {kind}"
    geometry = el.find("geometry")
    shapes = [c for c in geometry if is_element(c)] if geometry is not None else []
    if not shapes:
        r.problems.add(f"{what}: <geometry> holds no shape")
        return None
    shape = shapes[0]  # urdfdom reads the first element and ignores the rest
    tag = local_name(shape.tag)
    if len(shapes) > 1:
        rest = ", ".join(f"<{local_name(c.tag)}>" for c in shapes[1:])
        r.warnings.append(f"{what}: <geometry> holds more than one element; the first (<{tag}>) is used, as "
                          f"urdfdom does, and {rest} ignored")
    if tag == "capsule":  # PyBullet's extension: a cylinder along z with hemispherical ends
        return _capsule_shapes(shape, el, what, r)
    if tag == "mesh":
        geom = _mesh(shape, what, link, (link, kind, index), r)
    elif tag in _SOLIDS:
        geom = _SOLIDS[tag](shape, what, r)
    else:
        r.problems.add(f"{what}: <{tag}> geometry is not supported (use mesh, box, cylinder or sphere)")
        return None
    if geom is None:
        return None
    origin = origin_dict(*read_origin(el.find("origin"), what, r.problems))
    if origin:
        geom["origin"] = origin
    return geom


def _mesh(shape, what: str, link: str, use: tuple[str, str, int], r: _Reading) -> dict | None:
    """A <mesh>: the file where the recipe finds it, its scale as ``units`` or ``scale``."""
    uri = (shape.get("filename") or "").strip()
    if not uri:
        r.problems.add(f"{what}: <mesh> has no filename")
        return None
    path = r.resolver.locate(uri, link, r.problems, r.line(shape))
    scale = read_floats(shape.get("scale"), 3, f"{what} mesh scale", r.problems, [1.0, 1.0, 1.0])
    if path is None:
        return None
    if any(s == 0 for s in scale):
        r.problems.add(f"{what}: mesh '{uri}' has a zero scale ({shape.get('scale')})")
        return None
    left = r.resolver.leaves_package(uri)
    if left is not None and r.resolver.copy(path):  # its copy would land outside meshes/
        r.problems.add(f"{what} mesh: {uri} leaves package '{left}'", r.line(shape))
        return None
    dest = r.resolver.destination(path, uri)
    geom: dict = {"mesh": r.resolver.recipe_text(dest)}
    if scale[0] == scale[1] == scale[2]:
        s = scale[0]
        unit = next((u for u, f in UNITS.items() if f == s), None)
        if unit is not None and unit != "m":
            geom["units"] = unit
        elif unit is None:
            geom["scale"] = s
    else:
        geom["scale"] = list(scale)
    r.out.meshes[use] = MeshUse(path, dest, tuple(scale), shape)
    return geom


def _box(shape, what: str, r: _Reading) -> dict | None:
    size = read_floats(shape.get("size"), 3, f"{what} box size", r.problems)
    if size is None:
        return None
    if min(size) <= 0:
        r.warnings.append(f"{what}: box of size {shape.get('size')} has no volume; dropped")
        return None
    return {"box": {"size": size}}


def _cylinder(shape, what: str, r: _Reading) -> dict | None:
    radius = read_float(shape.get("radius"), f"{what} cylinder radius", r.problems)
    length = read_float(shape.get("length"), f"{what} cylinder length", r.problems)
    if radius is None or length is None:
        return None
    if radius <= 0 or length <= 0:
        r.warnings.append(f"{what}: cylinder of radius {radius!r} and length {length!r} has no volume; dropped")
        return None
    return {"cylinder": {"radius": radius, "length": length}}


def _sphere(shape, what: str, r: _Reading) -> dict | None:
    radius = read_float(shape.get("radius"), f"{what} sphere radius", r.problems)
    if radius is None:
        return None
    if radius <= 0:
        r.warnings.append(f"{what}: sphere of radius {radius!r} has no volume; dropped")
        return None
    return {"sphere": {"radius": radius}}


_SOLIDS = {"box": _box, "cylinder": _cylinder, "sphere": _sphere}


def _capsule_shapes(shape, el, what: str, r: _Reading) -> list[dict] | None:
    """PyBullet's <capsule> (not in the URDF standard) as the same solid: a cylinder and spheres."""
    radius = read_float(shape.get("radius"), f"{what} capsule radius", r.problems)
    length = read_float(shape.get("length"), f"{what} capsule length", r.problems)
    if radius is None or length is None:
        return None
    if radius <= 0 or length < 0:
        r.warnings.append(f"{what}: capsule of radius {radius!r} and length {length!r} has no volume; dropped")
        return None
    xyz, rpy = read_origin(el.find("origin"), what, r.problems)
    r.warnings.append(f"{what}: <capsule> (PyBullet's, not in the URDF standard) is written as a cylinder "
                      "and two spheres, the same solid")
    return _capsule(radius, length, xyz, rpy)


def _capsule(radius: float, length: float, xyz, rpy) -> list[dict]:
    """A capsule (the cylinder's ``length`` between the centres of its end spheres) as shapes."""
    axis = rpy_matrix(rpy) @ np.array([0.0, 0.0, length / 2])
    out = []
    if length > 0:
        cyl: dict = {"cylinder": {"radius": radius, "length": length}}
        origin = origin_dict(xyz, rpy)
        if origin:
            cyl["origin"] = origin
        out.append(cyl)
    for sign in ((1.0, -1.0) if length > 0 else (1.0,)):
        centre = [float(c + sign * a) + 0.0 for c, a in zip(xyz, axis)]
        sph: dict = {"sphere": {"radius": radius}}
        origin = origin_dict(centre, (0.0, 0.0, 0.0))
        if origin:
            sph["origin"] = origin
        out.append(sph)
    return out


def _same_shapes(visuals: list[dict], collisions: list[dict]) -> bool:
    if not visuals or len(visuals) != len(collisions):
        return False
    strip = lambda g: {k: v for k, v in g.items() if k != "material"}  # noqa: E731
    return all(strip(v) == strip(c) for v, c in zip(visuals, collisions))


# ---------------------------------------------------------------- joints


def _joints(children: list, links: dict[str, dict], r: _Reading) -> dict[str, dict]:
    """Every <joint> as a recipe entry; what the recipe changes from the original goes to
    ``r.out.joint_notes`` (and the warnings)."""
    joints: dict[str, dict] = {}
    for el in children:
        if local_name(el.tag) != "joint":
            continue
        name = el.get("name")
        if not valid_frame_name(name):
            r.problems.add(f"joint name '{name}' is not a valid recipe name ({name_hint()})")
            continue
        if name in joints:
            r.problems.add(f"joint '{name}' is defined twice")
            continue
        joint = _joint(el, name, r.problems, r.warnings)
        if joint is None:
            continue
        for end in ("parent", "child"):
            if joint[end] not in links and valid_frame_name(joint[end]):
                r.problems.add(f"joint '{name}': {end} link '{joint[end]}' is not defined")
        joints[name] = joint
    for name, joint in joints.items():
        note = joint.pop("__note", None)
        if note:
            r.out.joint_notes[name] = note
    _drop_dangling_mimics(joints, r)
    return joints


def _note(joint: str, note: str, r: _Reading) -> None:
    """Record what the recipe changes on ``joint`` (its comment in the recipe) and warn."""
    r.out.joint_notes[joint] = "; ".join(filter(None, (r.out.joint_notes.get(joint), note)))
    r.warnings.append(f"joint '{joint}': {note}")


def _drop_dangling_mimics(joints: dict[str, dict], r: _Reading) -> None:
    """A mimic of a joint the robot does not have, or of a fixed joint, is dropped."""
    for name, joint in joints.items():
        mimic = joint.get("mimic")
        if mimic and mimic["joint"] not in joints:  # check_urdf accepts it (Alex's hands: 'index_q1')
            note = (f"mimicked joint '{mimic['joint']}' in the original, which the robot does not have (Drake "
                    "refuses such a URDF): the mimic is dropped and the joint moves on its own")
        elif mimic and joints[mimic["joint"]]["type"] == "fixed":
            note = (f"mimicked fixed joint '{mimic['joint']}' in the original: a fixed joint has no position to "
                    "follow, so the mimic is dropped and the joint moves on its own")
        else:
            continue
        del joint["mimic"]
        _note(name, note, r)


def _joint(el, name: str, problems: Problems, warnings: list[str]) -> dict | None:
    """One <joint> as a recipe entry (with ``__note`` when the recipe changes it), or None with a
    problem."""
    what = f"joint '{name}'"
    jtype = el.get("type")
    if jtype not in JOINT_TYPES:
        problems.add(f"{what}: type '{jtype}' is not a URDF joint type ({', '.join(JOINT_TYPES)})")
        return None
    parent, child = el.find("parent"), el.find("child")
    if parent is None or child is None or not parent.get("link") or not child.get("link"):
        problems.add(f"{what}: needs <parent link=...> and <child link=...>")
        return None
    joint: dict = {"type": jtype, "parent": parent.get("link"), "child": child.get("link")}
    origin = origin_dict(*read_origin(el.find("origin"), what, problems))
    if origin:
        joint["origin"] = origin
    if jtype not in ("fixed", "floating"):
        _axis(el, joint, what, problems)
    limit_el = el.find("limit")
    if limit_el is not None:
        el = _limit(el, limit_el, joint, what, problems, warnings)
        if el is None:
            return None
    elif jtype in ("revolute", "prismatic"):
        problems.add(f"{what}: a {jtype} joint needs <limit> (lower, upper, effort, velocity)")
        return None
    _dynamics(el.find("dynamics"), joint, what, problems)
    _mimic(el.find("mimic"), joint, what, problems)
    if jtype in ("fixed", "floating", "planar") and joint.get("mimic"):  # TALOS reduced: locked gripper joints
        note = (f"a {jtype} joint mimicking joint '{joint.pop('mimic')['joint']}' in the original: a {jtype} joint "
                "follows no other joint, so the mimic is dropped")
        warnings.append(f"{what}: {note}")
        joint["__note"] = note
    for child_el in el:
        tag = local_name(child_el.tag)
        if is_element(child_el) and tag not in ("parent", "child", "origin", "axis", "limit", "dynamics", "mimic"):
            warnings.append(f"{what}: <{tag}> is dropped (the recipe has no place for it)")
    return joint


def _axis(el, joint: dict, what: str, problems: Problems) -> None:
    axis_el = el.find("axis")
    axis = read_floats(axis_el.get("xyz") if axis_el is not None else None, 3, f"{what} axis", problems,
                       [1.0, 0.0, 0.0])
    if axis is not None and sum(a * a for a in axis) == 0:
        problems.add(f"{what}: axis must not be zero")
    elif axis is not None and axis != [1.0, 0.0, 0.0]:
        joint["axis"] = axis


def _limit(el, limit_el, joint: dict, what: str, problems: Problems, warnings: list[str]):
    """The joint's <limit> into ``joint``.  Returns the joint element the rest is read from (a
    copy without <mimic> when the joint became fixed), None with a problem."""
    jtype = joint["type"]
    if jtype == "continuous":
        limit = {}
        for key in ("effort", "velocity"):
            v = read_float(limit_el.get(key), f"{what} limit {key}", problems)
            if v is not None:
                limit[key] = abs(v)
        if limit_el.get("lower") is not None or limit_el.get("upper") is not None:
            warnings.append(f"{what}: a continuous joint has no position limits; "
                            "its lower and upper are dropped (URDF ignores them too)")
        if limit:
            joint["limit"] = limit
    elif jtype not in ("revolute", "prismatic"):
        warnings.append(f"{what}: a {jtype} joint takes no <limit>; dropped (URDF ignores it too)")
    else:
        return _bounded_limit(el, limit_el, joint, what, problems, warnings)
    return el


def _bounded_limit(el, limit_el, joint: dict, what: str, problems: Problems, warnings: list[str]):
    """A revolute or prismatic joint's limit.  lower == upper: a revolute joint is read as
    continuous (urdfdom's default limits are lower = upper = 0: files that mean "free" write
    that), a prismatic one as fixed at that position.  Returns as :func:`_limit` does."""
    limit = {}
    for key, default in (("lower", 0.0), ("upper", 0.0), ("effort", None), ("velocity", None)):
        v = read_float(limit_el.get(key), f"{what} limit {key}", problems, default)
        if v is None:
            problems.add(f"{what}: <limit> needs {key} (URDF requires effort and velocity)")
            return None
        limit[key] = v
    if _unlimited(limit, joint, what, warnings):
        return el
    if limit["lower"] == limit["upper"] and joint["type"] == "revolute":
        note = (f"limit lower == upper ({limit['lower']!r}) in the original: read as no position limit "
                "(lower and upper default to 0 in URDF), the joint is continuous")
        warnings.append(f"{what}: {note}")
        joint["type"] = "continuous"
        joint["__note"] = note
        joint["limit"] = {k: abs(limit[k]) for k in ("effort", "velocity")}
    elif limit["lower"] == limit["upper"]:  # prismatic
        return _fixed_at(el, joint, limit["lower"], what, problems, warnings)
    elif limit["lower"] >= limit["upper"]:
        problems.add(f"{what}: limit lower ({limit['lower']!r}) is not below upper ({limit['upper']!r}); "
                     "a recipe cannot express a locked revolute or prismatic joint (make it fixed)")
        return None
    else:
        for key in ("effort", "velocity"):
            if limit[key] < 0:
                warnings.append(f"{what}: negative {key} limit {limit[key]!r}; using its magnitude")
                limit[key] = -limit[key]
        joint["limit"] = limit
    return el


def _unlimited(limit: dict, joint: dict, what: str, warnings: list[str]) -> bool:
    """Position limits beyond the recipe's range (MAX_LENGTH: 10 km, 10000 rad) mean "unlimited"
    (the Iris drone's rotors and Neobotix's wheels: +-1e16): a revolute joint with both is read as
    continuous (True: ``joint`` is done), a bound beyond it otherwise is clamped to it."""
    beyond = [k for k in ("lower", "upper") if not abs(limit[k]) <= MAX_LENGTH]
    if not beyond:
        return False
    shown_limits = " and ".join(f"{k} {limit[k]!r}" for k in beyond)
    if joint["type"] == "revolute" and limit["lower"] < -MAX_LENGTH and limit["upper"] > MAX_LENGTH:
        note = (f"limit {shown_limits} in the original, beyond any physical range (a recipe's is "
                f"+-{short_number(MAX_LENGTH)}): read as no position limit, the joint is continuous")
        joint["type"] = "continuous"
        joint["limit"] = {k: abs(limit[k]) for k in ("effort", "velocity")}
    else:
        for k in beyond:
            limit[k] = math.copysign(MAX_LENGTH, limit[k])
        note = (f"limit {shown_limits} in the original, beyond any physical range (a recipe's is "
                f"+-{short_number(MAX_LENGTH)}): read as no limit on that side, clamped to the recipe's")
        for key in ("effort", "velocity"):
            limit[key] = abs(limit[key])
        joint["limit"] = limit
    warnings.append(f"{what}: {note}")
    joint["__note"] = note
    return True


def _fixed_at(el, joint: dict, at: float, what: str, problems: Problems, warnings: list[str]):
    """A prismatic joint with lower == upper can only be at that position: consumers that keep
    limits (Gazebo, Drake, Pinocchio) hold it there; MuJoCo ignores equal limits and lets it
    slide away.  The recipe makes it fixed there."""
    note = (f"limit lower == upper ({at!r}) in the original: the joint can only be at that position, "
            f"so it is fixed there{_moved(at)}; MuJoCo would ignore the equal limits and let it slide "
            "freely")
    warnings.append(f"{what}: {note}")
    axis = joint.pop("axis", [1.0, 0.0, 0.0])
    if at != 0:
        joint.pop("origin", None)
        origin = _slid(el, what, problems, axis, at)
        if origin:
            joint["origin"] = origin
    joint["type"] = "fixed"
    joint["__note"] = note
    return _without_mimic(el, joint, what, warnings)


def _dynamics(dyn_el, joint: dict, what: str, problems: Problems) -> None:
    if dyn_el is None:
        return
    dyn = {}
    for key in ("damping", "friction"):
        v = read_float(dyn_el.get(key), f"{what} dynamics {key}", problems)
        if v is not None:
            if v < 0:
                problems.add(f"{what}: dynamics {key} must not be negative ({v!r})")
            else:
                dyn[key] = v
    if dyn:
        joint["dynamics"] = dyn


def _mimic(mimic_el, joint: dict, what: str, problems: Problems) -> None:
    if mimic_el is None:
        return
    if not mimic_el.get("joint"):
        problems.add(f"{what}: <mimic> needs a joint")
        return
    mimic: dict = {"joint": mimic_el.get("joint")}
    for key in ("multiplier", "offset"):
        v = read_float(mimic_el.get(key), f"{what} mimic {key}", problems)
        if v is not None:
            mimic[key] = v
    joint["mimic"] = mimic


def _moved(at: float) -> str:
    return "" if at == 0 else f", its origin moved {fmt(at)} along the axis"


def _slid(el, what: str, problems: Problems, axis: list[float], at: float) -> dict | None:
    """The joint's origin with the child slid ``at`` along the (unit) axis: where the prismatic
    joint puts it at position ``at``."""
    xyz, rpy = read_origin(el.find("origin"), what, problems)
    a = np.asarray(axis, dtype=float)
    moved = np.asarray(xyz, dtype=float) + rpy_matrix(rpy) @ (a / np.linalg.norm(a)) * at
    return origin_dict([float(v) + 0.0 for v in moved], rpy)


def _without_mimic(el, joint: dict, what: str, warnings: list[str]):
    """A copy of the joint element without <mimic> when it has one (a fixed joint follows no joint)."""
    mimic = el.find("mimic")
    if mimic is None:
        return el
    warnings.append(f"{what}: a fixed joint follows no other joint: its <mimic> is dropped")
    joint["__note"] += "; its mimic is dropped"
    el = copy.deepcopy(el)
    el.remove(el.find("mimic"))
    return el


def _drivers(children: list) -> dict[str, tuple[str, object]]:
    """Joint -> (what drives it, that element): a <transmission> naming it, or a <ros2_control>
    joint with a command interface (as robotkit.check.lints reads the build)."""
    out: dict[str, tuple[str, object]] = {}
    for el in children:
        tag = local_name(el.tag)
        for j in el.findall("joint") if tag in ("transmission", "ros2_control") else ():
            if tag == "transmission" or j.find("command_interface") is not None:
                out.setdefault(j.get("name"), (f"{tag} '{el.get('name')}'", el))
    return out


def _zero_limits(children: list, joints: dict[str, dict], r: _Reading) -> None:
    """An effort or velocity limit of 0 is kept: on a joint nothing drives, a passive joint (stated
    above it); on a driven one, a defect check reports (a warning naming the line)."""
    drivers = _drivers(children)
    elements = {el.get("name"): el for el in children if local_name(el.tag) == "joint"}
    for name, joint in joints.items():
        limit = joint.get("limit") or {}
        zero = [k for k in ("effort", "velocity") if limit.get(k) == 0]
        if joint["type"] not in ("revolute", "prismatic") or not zero:
            continue
        limits = f"{' and '.join(zero)} limit{'s' if len(zero) > 1 else ''} 0 in the original"
        if name in drivers:
            r.warnings.append(f"{r.where(elements[name])}joint '{name}': {limits}, and {drivers[name][0]} drives it: "
                              f"a driven joint with zero {zero[0]} cannot move (check reports it; give it the "
                              "motor's limit)")
        else:
            _note(name, f"{limits}: nothing drives it (no transmission or ros2_control command names it), so it "
                        "is kept as a passive joint", r)


# ---------------------------------------------------------------- everything else


def _extras(children: list, root, links: _Links, joints: dict[str, dict], materials: dict[str, dict],
            r: _Reading) -> list[str]:
    """Every other top-level element as XML text for ``urdf_extras``: gazebo blocks without what
    the recipe now says (materials, contacts, ``preserveFixedJoint``), transmissions, ... verbatim.
    A transmission naming a joint the robot does not have is left out."""
    extras: list[str] = []
    gazebo_links: dict[str, list[tuple[int, object]]] = {}
    for idx, el in enumerate(children):
        if local_name(el.tag) == "gazebo" and el.get("reference") in links.links:
            gazebo_links.setdefault(el.get("reference"), []).append((idx, el))
    remove: dict[int, set[str]] = {}  # element index -> child tags handled by the recipe
    _map_gazebo_materials(gazebo_links, links.visual_materials, materials, remove)
    _map_contacts(gazebo_links, links.has_collision, links.links, remove)
    for idx, el in enumerate(children):
        tag = local_name(el.tag)
        if tag in ("link", "joint", "material"):
            continue
        drop = set(remove.get(idx, ()))
        if tag == "gazebo" and joints.get(el.get("reference"), {}).get("type") == "fixed":
            pes = el.find("preserveFixedJoint")
            if pes is not None and _text(pes).strip().lower() in ("true", "1"):
                drop.add("preserveFixedJoint")  # robotkit writes it for every fixed joint
        missing = [j.get("name") for j in el.findall("joint") if j.get("name") not in joints] \
            if tag == "transmission" else []
        if missing:  # the Jackal's transmissions name joint 'front_left_wheel' for 'front_left_wheel_joint'
            note = (f"transmission '{el.get('name')}' is left out: it names joint '{missing[0]}', which the robot "
                    "does not have (Drake refuses the URDF, ros_control the transmission)")
            r.out.left_out.append(note)
            r.warnings.append(note)
            continue
        xml_text = _verbatim(el, drop, root)
        if xml_text is None:
            continue
        extras.append(xml_text)
        r.out.extras.append(_label(el))
    if r.out.extras:
        n = len(r.out.extras)
        r.warnings.append(f"{n} element{'s' if n > 1 else ''} the recipe cannot express yet "
                          f"{'are' if n > 1 else 'is'} carried through verbatim in urdf_extras: "
                          f"{', '.join(r.out.extras)}")
    return extras


# ---------------------------------------------------------------- gazebo blocks


def _text(el) -> str:
    """The element's text as ElementTree gives it: up to its first child element, comments skipped."""
    parts = [el.text or ""]
    for child in el:
        if is_element(child):
            break
        parts.append(child.tail or "")
    return "".join(parts)


def _simple_text(el) -> str | None:
    if any(is_element(c) for c in el) or el.attrib:
        return None
    return _text(el).strip()


def _map_gazebo_materials(gazebo_links, link_visual_materials, materials, remove):
    """Move ``<gazebo reference="L"><material>G</material>`` into the recipe material of
    L's visuals when the URDF emitter then writes exactly the same for every link."""
    desired: dict[str, tuple[int, str]] = {}
    for link, blocks in gazebo_links.items():
        found = [(idx, el.findall("material")) for idx, el in blocks]
        found = [(idx, mats) for idx, mats in found if mats]
        if len(found) != 1 or len(found[0][1]) != 1:
            continue
        text = _simple_text(found[0][1][0])
        if text:
            desired[link] = (found[0][0], text)
    assigned: dict[str, str] = {}
    conflict: set[str] = set()
    for link, (_, g) in desired.items():
        mats = link_visual_materials.get(link) or []
        if not mats:
            continue
        m = mats[0]
        if m in conflict:
            continue
        if assigned.get(m, g) != g:
            conflict.add(m)
            assigned.pop(m, None)
        else:
            assigned[m] = g

    def emitted(link):  # what robotkit's URDF emitter writes for the link
        for m in link_visual_materials.get(link) or []:
            if m in assigned:
                return m, assigned[m]
        return None, None

    changed = True
    while changed:
        changed = False
        for link in link_visual_materials:
            m, g = emitted(link)
            if m is not None and (link not in desired or desired[link][1] != g):
                assigned.pop(m)
                changed = True
    for m, g in assigned.items():
        materials[m]["gazebo"] = g
    for link, (idx, g) in desired.items():
        if emitted(link)[1] == g:
            remove.setdefault(idx, set()).add("material")


def _map_contacts(gazebo_links, link_has_collision, links, remove):
    """Move mu1, mu2, kp, kd of ``<gazebo reference="L">`` into L's ``contact`` when the
    emitter writes exactly those values back (it writes them only for links with collisions,
    and mu2 = mu1 when mu2 is not given) and the recipe takes them (at most MAX_VALUE: TIAGo
    Pro's kp of 1e13 stays in its block, carried through verbatim)."""
    for link, blocks in gazebo_links.items():
        if not link_has_collision.get(link):
            continue
        with_contact = [(idx, el) for idx, el in blocks if any(el.find(k) is not None for k in CONTACT_KEYS)]
        if len(with_contact) != 1:
            continue
        idx, el = with_contact[0]
        values = {}
        ok = True
        for key in CONTACT_KEYS:
            found = el.findall(key)
            if not found:
                continue
            text = _simple_text(found[0]) if len(found) == 1 else None
            try:
                v = float(text) if text is not None else None
            except ValueError:
                v = None
            if v is None or not math.isfinite(v) or v < 0 or v > MAX_VALUE or (key == "kp" and v == 0):
                ok = False
                break
            values[key] = v + 0.0
        if not ok or ("mu1" in values and "mu2" not in values):
            continue
        links[link]["contact"] = values
        remove.setdefault(idx, set()).update(values)


# ---------------------------------------------------------------- verbatim elements


def _label(el) -> str:
    tag = local_name(el.tag)
    for attr in ("reference", "name"):
        if el.get(attr):
            return f"<{tag} {attr}=\"{el.get(attr)}\">"
    plugin = el.find("plugin")
    if plugin is not None and plugin.get("name"):
        return f"<{tag}> (plugin {plugin.get('name')})"
    return f"<{tag}>"


# The writer below sees an element as the source wrote it: its child nodes are its text runs
# (str), child elements and comments, in order, as a DOM has them; qualified names keep their
# prefixes, and an element's own namespace declarations come first among its attributes.


def _verbatim(el, drop: set[str], root) -> str | None:
    """The element's XML text as in the source, without the child elements named in
    ``drop``; None when nothing but whitespace and comments would remain."""
    kids = _nodes(el)
    if drop:
        kept: list = []
        for kid in kids:
            if not isinstance(kid, str) and is_element(kid) and _qname(kid) in drop:
                if kept and isinstance(kept[-1], str) and not kept[-1].strip():
                    kept.pop()  # the whitespace before it
                continue
            kept.append(kid)
        kids = kept
        if not any((isinstance(k, str) and k.strip()) or (not isinstance(k, str) and is_element(k)) for k in kids):
            return None
    # namespace prefixes declared on <robot> (e.g. xmlns:xacro) that the element uses
    used = set(re.findall(r"</?([A-Za-z_][\w.\-]*):", _xml(el, kids=kids))) | {
        a.split(":")[0] for a in _all_attr_names(el, kids) if ":" in a and not a.startswith("xmlns")}
    own = _declarations(el)
    added = [(f"xmlns:{prefix}", root.nsmap[prefix]) for prefix in sorted(used)
             if prefix in root.nsmap and f"xmlns:{prefix}" not in own]
    text = _xml(el, "" if _unformatted(kids) else None, kids, added)  # xacro drops the whitespace between
    # elements: indent for reading
    lines = [line.rstrip() for line in text.split("\n")]
    rest = [line for line in lines[1:] if line.strip()]
    if rest:
        indent = min(len(line) - len(line.lstrip(" ")) for line in rest)
        lines = [lines[0]] + [line[indent:] if line[:indent].strip() == "" else line for line in lines[1:]]
    text = "\n".join(lines)
    urdfxml.parse_text(text)  # well-formed (the schema checks it too)
    return text


def _nodes(el) -> list:
    """The element's child nodes: text runs (str), elements, comments."""
    out = [el.text] if el.text else []
    for child in el:
        out.append(child)
        if child.tail:
            out.append(child.tail)
    return out


def _qname(el) -> str:
    """The element's name as written (``prefix:local``)."""
    local = el.tag.rsplit("}", 1)[-1]
    return f"{el.prefix}:{local}" if el.prefix else local


_XML_NS = "http://www.w3.org/XML/1998/namespace"


def _attributes(el) -> list[tuple[str, str]]:
    """(name as written, value) of the element's attributes, in document order."""
    prefixes = {uri: prefix for prefix, uri in reversed(list(el.nsmap.items())) if prefix}
    prefixes[_XML_NS] = "xml"
    out = []
    for name, value in el.attrib.items():
        if name.startswith("{"):
            uri, local = name[1:].split("}", 1)
            name = f"{prefixes.get(uri, '')}:{local}"
        out.append((name, value))
    return out


def _declarations(el) -> dict[str, str]:
    """The namespace declarations written on the element (``xmlns:p`` -> URI), in order."""
    parent = el.getparent()
    inherited = parent.nsmap if parent is not None else {}
    return {(f"xmlns:{p}" if p else "xmlns"): uri for p, uri in el.nsmap.items() if inherited.get(p) != uri}


def _xml(node, indent: str | None = None, kids: list | None = None, added=()) -> str:
    """The XML text of a node, attributes in document order; with ``indent``, one element a
    line (for elements holding elements only).  ``kids`` replaces an element's child nodes,
    ``added`` are attributes written after its own."""
    def esc(text: str) -> str:
        return text.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;").replace(">", "&gt;")

    if isinstance(node, str):
        return esc(node)
    if not is_element(node):
        return f"<!--{node.text or ''}-->" if node.tag is _comment_tag() else ""  # a processing instruction: nothing
    name = _qname(node)
    attributes = [*_declarations(node).items(), *_attributes(node), *added]
    head = name + "".join(f' {a}="{esc(v)}"' for a, v in attributes)
    kids = _nodes(node) if kids is None else kids
    if not kids:
        return f"<{head}/>"
    if indent is None or (len(kids) == 1 and isinstance(kids[0], str)):
        return f"<{head}>" + "".join(_xml(k) for k in kids) + f"</{name}>"
    inner = [_xml(k, indent + "  ") for k in kids if not (isinstance(k, str) and not k.strip())]
    return f"<{head}>\n" + "".join(f"{indent}  {x}\n" for x in inner) + f"{indent}</{name}>"


def _comment_tag():
    from lxml import etree  # heavy (urdfxml loads it when it reads a URDF)

    return etree.Comment


def _unformatted(kids: list) -> bool:
    """True when the element (child nodes ``kids``) has child elements, no whitespace between
    them, and no text mixed with elements anywhere (so indenting it changes no text)."""
    def elements(nodes):
        return [c for c in nodes if not isinstance(c, str) and is_element(c)]

    def plain(nodes) -> bool:
        if elements(nodes) and any(isinstance(c, str) for c in nodes):
            return False
        return all(plain(_nodes(c)) for c in elements(nodes))

    return bool(elements(kids)) and plain(kids)


def _all_attr_names(el, kids: list) -> list[str]:
    out = [name for name, _ in _attributes(el)]
    for child in kids:
        if not isinstance(child, str) and is_element(child):
            out.extend(_all_attr_names(child, _nodes(child)))
    return out
