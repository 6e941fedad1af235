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

import math
import os
import re
import xml.dom.minidom as minidom
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

from robotkit.model import inertia_policy
from robotkit.errors import Problem, RobotkitError, display_path
from robotkit.recipe.schema import FRAME_NAME_RE, NAME_RE, UNITS

GREY = [0.5, 0.5, 0.5, 1.0]
TOP_KEYS = ("robot", "units", "density", "ros", "metadata", "materials", "links", "joints", "urdf_extras")
MESH_FORMATS = (".stl", ".obj", ".dae")
CONTACT_KEYS = ("mu1", "mu2", "kp", "kd")


@dataclass
class MeshUse:
    """One mesh file named by the URDF: where it is and where the recipe points."""

    source: str  # absolute path of the file found
    recipe_path: str  # absolute path the recipe names (source, or its copy)
    scale: tuple[float, float, float]


@dataclass
class Converted:
    recipe: dict
    warnings: list[str] = field(default_factory=list)
    copies: dict[str, str] = field(default_factory=dict)  # destination -> source
    meshes: dict[tuple[str, str, int], MeshUse] = field(default_factory=dict)  # (link, kind, i)
    explicit: dict[str, dict] = field(default_factory=dict)  # link -> the given inertial
    extras: list[str] = field(default_factory=list)  # a short label per verbatim element
    invalid_inertias: set[str] = field(default_factory=set)  # links whose given inertia the build rejects
    repairs: dict[str, str] = field(default_factory=dict)  # link -> what was wrong and what the recipe does
    joint_notes: dict[str, str] = field(default_factory=dict)  # joint -> what the recipe changes from the original


def no_inertial_form():
    """The recipe value that says "this link has no inertial", if the schema has one."""
    from pydantic import ValidationError

    from robotkit.recipe.schema import Link

    for value in ("none",):
        try:
            Link.model_validate({"visual": {"box": {"size": [1, 1, 1]}}, "inertial": value})
            return value
        except ValidationError:
            continue
    return None


# ---------------------------------------------------------------- parsing helpers


class _Problems:
    def __init__(self, file: str):
        self.file = file
        self.items: list[Problem] = []

    def add(self, message: str):
        self.items.append(Problem(message, file=self.file))

    def raise_if_any(self):
        if self.items:
            raise RobotkitError(self.items)


def _floats(text: str | None, n: int, what: str, problems: _Problems, default=None):
    if text is None:
        return list(default) if default is not None else None
    parts = text.split()
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != n or not all(math.isfinite(v) for v in values):
        problems.add(f"{what}: '{text}' is not {n} finite number{'s' if n > 1 else ''}")
        return list(default) if default is not None else None
    return [v + 0.0 for v in values]  # no -0.0


def _float(text, what, problems, default=None):
    values = _floats(text, 1, what, problems, None if default is None else [default])
    return None if values is None else values[0]


def _origin(el: ET.Element | None, what: str, problems: _Problems):
    """(xyz, rpy) of an <origin> child, zeros when absent."""
    if el is None:
        return [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    xyz = _floats(el.get("xyz"), 3, f"{what} origin xyz", problems, [0.0, 0.0, 0.0])
    rpy = _floats(el.get("rpy"), 3, f"{what} origin rpy", problems, [0.0, 0.0, 0.0])
    return xyz, rpy


def _origin_dict(xyz, rpy) -> dict | None:
    out = {}
    if any(xyz):
        out["xyz"] = list(xyz)
    if any(rpy):
        out["rpy"] = list(rpy)
    return out or None


def _valid_name(name: str | None) -> bool:
    return bool(name) and bool(NAME_RE.match(name))


def _valid_frame_name(name: str | None) -> bool:
    """Link and joint names may hold '/' between parts, as ROS frame names do."""
    return bool(name) and bool(FRAME_NAME_RE.match(name))


def _material_name(name: str, taken: set[str]) -> str:
    base = re.sub(r"[^A-Za-z0-9_.\-]", "_", name or "material")
    if not re.match(r"[A-Za-z_]", base):
        base = "_" + base
    out, i = base, 2
    while out in taken:
        out, i = f"{base}_{i}", i + 1
    return out


# ---------------------------------------------------------------- mesh files


class MeshResolver:
    def __init__(self, source: Path, recipe_dir: Path, packages: dict[str, str], copy: bool):
        self.source = source
        self.recipe_dir = recipe_dir
        self.packages = packages
        self.copy = copy
        self.copies: dict[str, str] = {}  # destination -> source
        self._dest_of: dict[str, str] = {}

    def locate(self, uri: str, link: str, problems: _Problems) -> str | None:
        """Absolute path of the file ``uri`` names, or None with a problem."""
        path = None
        m = re.match(r"^(package|model)://([^/]+)/(.+)$", uri)
        if m:
            pkg, rest = m.group(2), m.group(3)
            if pkg not in self.packages:
                problems.add(f"link '{link}': mesh '{uri}': package '{pkg}' not found; "
                             f"give --package-path {pkg}=DIR")
                return None
            path = os.path.join(self.packages[pkg], rest)
        elif uri.startswith("file://"):
            path = uri[len("file://"):]
            if not os.path.isabs(path):
                path = os.path.join(self.source.parent, path)
        elif re.match(r"^[A-Za-z][A-Za-z0-9+.\-]*://", uri):
            problems.add(f"link '{link}': mesh '{uri}': unsupported URI scheme "
                         "(use package://, file:// or a path)")
            return None
        else:
            path = uri if os.path.isabs(uri) else os.path.join(self.source.parent, uri)
        path = os.path.normpath(path)
        if not os.path.isfile(path):
            problems.add(f"link '{link}': mesh '{uri}' not found (looked for {display_path(path)})")
            return None
        if os.path.splitext(path)[1].lower() not in MESH_FORMATS:
            problems.add(f"link '{link}': mesh '{uri}' has an unsupported format (robotkit reads STL, OBJ and DAE)")
            return None
        return path

    def destination(self, path: str, uri: str) -> str:
        """Where the recipe points for the file at ``path`` (a copy below the recipe, or it)."""
        if not self.copy:
            return path
        if path in self._dest_of:
            return self._dest_of[path]
        m = re.match(r"^(package|model)://(.+)$", uri)
        rel = m.group(2) if m else os.path.basename(path)
        dest = os.path.normpath(os.path.join(self.recipe_dir, "meshes", rel))
        stem, ext = os.path.splitext(dest)
        i = 2
        while dest in self.copies and self.copies[dest] != path:
            dest, i = f"{stem}_{i}{ext}", i + 1
        self.copies[dest] = path
        self._dest_of[path] = dest
        return dest

    def recipe_text(self, dest: str) -> str:
        return Path(os.path.relpath(dest, self.recipe_dir)).as_posix()


# ---------------------------------------------------------------- the conversion


def urdf_to_recipe(text: str, source: str | os.PathLike, recipe_path: str | os.PathLike,
                   package_paths: dict[str, str] | None = None, copy_meshes: bool = False,
                   recompute_inertials: bool = False, density: float | None = None) -> Converted:
    """Map the URDF ``text`` (read from ``source``) to a recipe dict for ``recipe_path``.

    Raises RobotkitError with every problem found (one line each, naming links and URIs).
    """
    source = Path(source).absolute()
    recipe_dir = Path(recipe_path).absolute().parent
    problems = _Problems(str(source))
    warnings: list[str] = []
    try:
        root = ET.fromstring(text)
        dom = minidom.parseString(text)
    except Exception as exc:  # ET.ParseError, or expat's errors from minidom
        line = getattr(exc, "position", (None,))[0] if isinstance(exc, ET.ParseError) else getattr(exc, "lineno", None)
        raise RobotkitError(Problem(f"not well-formed XML: {exc}", file=str(source), line=line)) from None
    if _local(root.tag) != "robot":
        raise RobotkitError(Problem(f"the root element is <{_local(root.tag)}>, not <robot>: not a URDF",
                                    file=str(source)))
    dom_children = [n for n in dom.documentElement.childNodes if n.nodeType == n.ELEMENT_NODE]
    et_children = list(root)
    resolver = MeshResolver(source, recipe_dir, dict(package_paths or {}), copy_meshes)
    out = Converted(recipe={})

    robot_name = root.get("name") or source.name.split(".")[0]
    if not _valid_name(robot_name):
        fixed = _material_name(robot_name, set())
        warnings.append(f"robot name '{robot_name}' is not a valid recipe name; using '{fixed}'")
        robot_name = fixed

    # global materials (first definition of a name wins, as in urdfdom)
    global_materials: dict[str, ET.Element] = {}
    for el in et_children:
        if _local(el.tag) == "material" and el.get("name") and el.get("name") not in global_materials:
            global_materials[el.get("name")] = el

    materials: dict[str, dict] = {}  # recipe name -> {"rgba": ...}
    by_key: dict[tuple, str] = {}  # (urdf name, rgba) -> recipe name
    texture_warned: set[str] = set()

    def material_ref(vis_mat: ET.Element, link: str) -> str:
        name = vis_mat.get("name") or ""
        rgba = _rgba(vis_mat, f"link '{link}': material '{name}'", problems, warnings)
        texture = vis_mat.find("texture")
        if rgba is None and name in global_materials:
            g = global_materials[name]
            rgba = _rgba(g, f"material '{name}'", problems, warnings)
            texture = texture if texture is not None else g.find("texture")
        if texture is not None and name not in texture_warned:
            texture_warned.add(name)
            if rgba is None:
                warnings.append(f"material '{name}' has a texture ({texture.get('filename')}) and no colour; "
                                "the recipe keeps the name with a grey colour (textures of DAE meshes are kept)")
            else:
                warnings.append(f"material '{name}': its texture ({texture.get('filename')}) is dropped; "
                                "the colour is kept")
        elif rgba is None and name not in texture_warned:
            texture_warned.add(name)
            warnings.append(f"material '{name}' (link '{link}') has no colour; using grey")
        rgba = rgba or list(GREY)
        key = (name, tuple(rgba))
        if key not in by_key:
            recipe_name = _material_name(name, set(materials))
            if recipe_name != name:
                if any(k[0] == name for k in by_key):
                    warnings.append(f"material '{name}' is defined with different colours; "
                                    f"the colour {_fmt_list(rgba)} is named '{recipe_name}'")
                else:
                    warnings.append(f"material name '{name}' is not a valid recipe name; using '{recipe_name}'")
            by_key[key] = recipe_name
            materials[recipe_name] = {"rgba": rgba}
        return by_key[key]

    # ---- links
    links: dict[str, dict] = {}
    link_visual_materials: dict[str, list[str]] = {}
    link_has_collision: dict[str, bool] = {}
    no_inertial = no_inertial_form()
    for el in et_children:
        if _local(el.tag) != "link":
            continue
        name = el.get("name")
        if not _valid_frame_name(name):
            problems.add(f"link name '{name}' is not a valid recipe name ({_name_hint()})")
            continue
        if name in links:
            problems.add(f"link '{name}' is defined twice")
            continue
        link: dict = {}
        visuals, collisions, vis_materials = [], [], []
        for kind, items in (("visual", visuals), ("collision", collisions)):
            for i, g_el in enumerate(el.findall(kind)):
                made = _geometry(g_el, name, kind, len(items), resolver, problems, warnings, out)
                if made is None:
                    continue
                for geom in made if isinstance(made, list) else [made]:
                    if kind == "visual":
                        mat = g_el.find("material")
                        if mat is not None:
                            geom["material"] = material_ref(mat, name)
                            vis_materials.append(geom["material"])
                    items.append(geom)
        for child in el:
            if _local(child.tag) not in ("visual", "collision", "inertial"):
                warnings.append(f"link '{name}': <{_local(child.tag)}> is dropped (the recipe has no place for it)")
        link_visual_materials[name] = vis_materials
        link_has_collision[name] = bool(collisions)
        if visuals:
            link["visual"] = visuals[0] if len(visuals) == 1 else visuals
        if _same_shapes(visuals, collisions):
            pass  # collision: visual (the default)
        elif not collisions:
            if visuals:
                link["collision"] = "none"
        else:
            link["collision"] = collisions[0] if len(collisions) == 1 else collisions

        inertial_el = el.find("inertial")
        given = _inertial(inertial_el, name, problems) if inertial_el is not None else None
        if given is not None and given["mass"] > 0:
            out.explicit[name] = given
            geometry = visuals or collisions
            if recompute_inertials and geometry:
                spec: dict = {}  # at the recipe's density, or keeping the given mass
                if collisions and not _same_shapes(visuals, collisions):
                    spec["source"] = "collision"
                if density is None:
                    spec["mass"] = given["mass"]
                if spec:
                    link["inertial"] = spec
            else:
                if recompute_inertials:
                    warnings.append(f"link '{name}' has no geometry to compute an inertial from; "
                                    "its inertial is kept as given")
                wrong = inertia_policy.defects(given["mass"], _tensor(given["inertia"]))
                if wrong:
                    fixed = inertia_policy.repair(given["mass"], _tensor(given["inertia"]), given["mass"])
                    t = fixed.inertia
                    given = dict(given, inertia={k: float(v) + 0.0 for k, v in {"ixx": t[0, 0], "ixy": t[0, 1], "ixz": t[0, 2],
                                                 "iyy": t[1, 1], "iyz": t[1, 2], "izz": t[2, 2]}.items()})
                    out.repairs[name] = (f"the original's {'; '.join(wrong)}: repaired ({'; '.join(fixed.changes)})")
                link["inertial"] = _explicit_dict(given)
        else:
            if given is not None and given["mass"] < 0:
                problems.add(f"link '{name}': negative mass {given['mass']!r}")
            if visuals:  # robotkit would compute an inertial from the visual geometry
                if no_inertial is not None:
                    link["inertial"] = no_inertial
                else:
                    why = "a zero mass" if given is not None else "no inertial"
                    warnings.append(f"link '{name}' has {why} in the URDF, but the recipe cannot say 'no inertial' "
                                    "for a link with visual geometry: the build computes one from its geometry, "
                                    "which adds mass the original does not have")
        links[name] = link

    # ---- joints
    joints: dict[str, dict] = {}
    joint_types: dict[str, str] = {}
    for el in et_children:
        if _local(el.tag) != "joint":
            continue
        name = el.get("name")
        if not _valid_frame_name(name):
            problems.add(f"joint name '{name}' is not a valid recipe name ({_name_hint()})")
            continue
        if name in joints:
            problems.add(f"joint '{name}' is defined twice")
            continue
        joint = _joint(el, name, problems, warnings)
        if joint is None:
            continue
        for end in ("parent", "child"):
            if joint[end] not in links and _valid_frame_name(joint[end]):
                problems.add(f"joint '{name}': {end} link '{joint[end]}' is not defined")
        joints[name] = joint
        joint_types[name] = joint["type"]
    for name, joint in joints.items():
        note = joint.pop("__note", None)
        if note:
            out.joint_notes[name] = note
    for name, joint in joints.items():
        mimic = joint.get("mimic")
        if mimic and mimic["joint"] not in joints:
            problems.add(f"joint '{name}': mimics joint '{mimic['joint']}', which is not defined")
        elif mimic and joints[mimic["joint"]]["type"] == "fixed":
            note = (f"mimicked fixed joint '{mimic['joint']}' in the original: a fixed joint has no position to "
                    "follow, so the mimic is dropped and the joint moves on its own")
            del joint["mimic"]
            out.joint_notes[name] = note
            warnings.append(f"joint '{name}': {note}")

    # ---- everything else: gazebo blocks (partly mapped), transmissions, ... verbatim
    extras: list[str] = []
    gazebo_links: dict[str, list[tuple[int, ET.Element]]] = {}
    for idx, el in enumerate(et_children):
        if _local(el.tag) == "gazebo" and el.get("reference") in links:
            gazebo_links.setdefault(el.get("reference"), []).append((idx, el))
    remove: dict[int, set[str]] = {}  # element index -> child tags handled by the recipe
    _map_gazebo_materials(gazebo_links, link_visual_materials, materials, remove)
    _map_contacts(gazebo_links, link_has_collision, links, remove)
    for idx, el in enumerate(et_children):
        tag = _local(el.tag)
        if tag in ("link", "joint", "material"):
            continue
        drop = set(remove.get(idx, ()))
        if tag == "gazebo" and joint_types.get(el.get("reference")) == "fixed":
            pes = el.find("preserveFixedJoint")
            if pes is not None and (pes.text or "").strip().lower() in ("true", "1"):
                drop.add("preserveFixedJoint")  # robotkit writes it for every fixed joint
        xml_text = _verbatim(dom_children[idx], drop, dom.documentElement)
        if xml_text is None:
            continue
        extras.append(xml_text)
        out.extras.append(_label(el))
    if out.extras:
        warnings.append(f"{len(out.extras)} element{'s' if len(out.extras) > 1 else ''} the recipe cannot "
                        f"express yet {'are' if len(out.extras) > 1 else 'is'} carried through verbatim in "
                        f"urdf_extras: {', '.join(out.extras)}")

    problems.raise_if_any()
    _give_moving_links_mass(links, joints, out)
    for link, why in out.repairs.items():
        warnings.append(f"link '{link}': {why}")
    recipe: dict = {"robot": robot_name, "units": "m", "density": density if density is not None else 1000.0}
    if materials:
        recipe["materials"] = materials
    recipe["links"] = links
    if joints:
        recipe["joints"] = joints
    if extras:
        recipe["urdf_extras"] = extras
    out.recipe = recipe
    out.warnings = warnings
    out.copies = dict(resolver.copies)
    return out


def _name_hint() -> str:
    from robotkit.recipe.schema import FRAME_NAME_HINT

    return FRAME_NAME_HINT


def _local(tag) -> str:
    if not isinstance(tag, str):
        return "#comment"
    return tag.rsplit("}", 1)[-1]


def _fmt_list(values) -> str:
    return "[" + ", ".join(fmt(v) for v in values) + "]"


def _rgba(el: ET.Element, what: str, problems: _Problems, warnings: list[str]):
    color = el.find("color")
    if color is None or color.get("rgba") is None:
        return None
    rgba = _floats(color.get("rgba"), 4, f"{what} colour", problems)
    if rgba is None:
        return None
    clamped = [min(1.0, max(0.0, v)) for v in rgba]
    if clamped != rgba:
        warnings.append(f"{what}: colour {color.get('rgba')} is outside 0..1; clamped")
    return clamped


def _geometry(el: ET.Element, link: str, kind: str, index: int, resolver: MeshResolver,
              problems: _Problems, warnings: list[str], out: Converted) -> dict | None:
    what = f"link '{link}' {kind}"
    geometry = el.find("geometry")
    shapes = [c for c in geometry] if geometry is not None else []
    if not shapes:
        problems.add(f"{what}: <geometry> holds no shape")
        return None
    shape = shapes[0]  # urdfdom reads the first element and ignores the rest
    tag = _local(shape.tag)
    if len(shapes) > 1:
        rest = ", ".join(f"<{_local(c.tag)}>" for c in shapes[1:])
        warnings.append(f"{what}: <geometry> holds more than one element; the first (<{tag}>) is used, as "
                        f"urdfdom does, and {rest} ignored")
    geom: dict = {}
    if tag == "mesh":
        uri = (shape.get("filename") or "").strip()
        if not uri:
            problems.add(f"{what}: <mesh> has no filename")
            return None
        path = resolver.locate(uri, link, problems)
        scale = _floats(shape.get("scale"), 3, f"{what} mesh scale", problems, [1.0, 1.0, 1.0])
        if path is None:
            return None
        if any(s == 0 for s in scale):
            problems.add(f"{what}: mesh '{uri}' has a zero scale ({shape.get('scale')})")
            return None
        dest = resolver.destination(path, uri)
        geom["mesh"] = resolver.recipe_text(dest)
        if scale[0] == scale[1] == scale[2]:
            s = scale[0]
            unit = next((u for u, f in UNITS.items() if f == s), None)
            if unit is not None and unit != "m":
                geom["units"] = unit
            elif unit is None:
                geom["scale"] = s
        else:
            geom["scale"] = list(scale)
        out.meshes[(link, kind, index)] = MeshUse(path, dest, tuple(scale))
    elif tag == "box":
        size = _floats(shape.get("size"), 3, f"{what} box size", problems)
        if size is None:
            return None
        if min(size) <= 0:
            warnings.append(f"{what}: box of size {shape.get('size')} has no volume; dropped")
            return None
        geom["box"] = {"size": size}
    elif tag == "cylinder":
        radius = _float(shape.get("radius"), f"{what} cylinder radius", problems)
        length = _float(shape.get("length"), f"{what} cylinder length", problems)
        if radius is None or length is None:
            return None
        if radius <= 0 or length <= 0:
            warnings.append(f"{what}: cylinder of radius {radius!r} and length {length!r} has no volume; dropped")
            return None
        geom["cylinder"] = {"radius": radius, "length": length}
    elif tag == "sphere":
        radius = _float(shape.get("radius"), f"{what} sphere radius", problems)
        if radius is None:
            return None
        if radius <= 0:
            warnings.append(f"{what}: sphere of radius {radius!r} has no volume; dropped")
            return None
        geom["sphere"] = {"radius": radius}
    elif tag == "capsule":  # PyBullet's extension: a cylinder along z with hemispherical ends
        radius = _float(shape.get("radius"), f"{what} capsule radius", problems)
        length = _float(shape.get("length"), f"{what} capsule length", problems)
        if radius is None or length is None:
            return None
        if radius <= 0 or length < 0:
            warnings.append(f"{what}: capsule of radius {radius!r} and length {length!r} has no volume; dropped")
            return None
        xyz, rpy = _origin(el.find("origin"), what, problems)
        warnings.append(f"{what}: <capsule> (PyBullet's, not in the URDF standard) is written as a cylinder "
                        "and two spheres, the same solid")
        return _capsule(radius, length, xyz, rpy)
    else:
        problems.add(f"{what}: <{tag}> geometry is not supported (use mesh, box, cylinder or sphere)")
        return None
    origin = _origin_dict(*_origin(el.find("origin"), what, problems))
    if origin:
        geom["origin"] = origin
    return geom


def _capsule(radius: float, length: float, xyz, rpy) -> list[dict]:
    """A capsule (the cylinder's ``length`` between the centres of its end spheres) as shapes."""
    import numpy as np

    from robotkit.model.robot import rpy_matrix

    axis = rpy_matrix(rpy) @ np.array([0.0, 0.0, length / 2])
    out = []
    if length > 0:
        cyl: dict = {"cylinder": {"radius": radius, "length": length}}
        origin = _origin_dict(xyz, rpy)
        if origin:
            cyl["origin"] = origin
        out.append(cyl)
    for sign in ((1.0, -1.0) if length > 0 else (1.0,)):
        centre = [float(c + sign * a) + 0.0 for c, a in zip(xyz, axis)]
        sph: dict = {"sphere": {"radius": radius}}
        origin = _origin_dict(centre, (0.0, 0.0, 0.0))
        if origin:
            sph["origin"] = origin
        out.append(sph)
    return out


def _same_shapes(visuals: list[dict], collisions: list[dict]) -> bool:
    if not visuals or len(visuals) != len(collisions):
        return False
    strip = lambda g: {k: v for k, v in g.items() if k != "material"}  # noqa: E731
    return all(strip(v) == strip(c) for v, c in zip(visuals, collisions))


def _inertial(el: ET.Element, link: str, problems: _Problems) -> dict | None:
    what = f"link '{link}' inertial"
    mass_el = el.find("mass")
    mass = _float(mass_el.get("value") if mass_el is not None else None, f"{what} mass", problems, 0.0)
    xyz, rpy = _origin(el.find("origin"), what, problems)
    t = el.find("inertia")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    values = {k: 0.0 for k in keys}
    if t is not None:
        for k in keys:
            v = _float(t.get(k), f"{what} {k}", problems, 0.0)
            values[k] = v if v is not None else 0.0
    if any(rpy):
        import numpy as np

        from robotkit.model.robot import rpy_matrix

        I = np.array([[values["ixx"], values["ixy"], values["ixz"]],
                      [values["ixy"], values["iyy"], values["iyz"]],
                      [values["ixz"], values["iyz"], values["izz"]]])
        R = rpy_matrix(rpy)
        I = R @ I @ R.T
        I = 0.5 * (I + I.T)
        scale = float(np.abs(I).max())
        I[np.abs(I) < 1e-14 * scale] = 0.0
        values = {"ixx": I[0, 0], "ixy": I[0, 1], "ixz": I[0, 2], "iyy": I[1, 1], "iyz": I[1, 2], "izz": I[2, 2]}
        values = {k: float(v) + 0.0 for k, v in values.items()}
    return {"mass": mass if mass is not None else 0.0, "com": xyz, "inertia": values, "rpy": rpy}


def _explicit_dict(given: dict) -> dict:
    out: dict = {"mass": given["mass"]}
    if any(given["com"]):
        out["com"] = list(given["com"])
    t = given["inertia"]
    inertia = {k: t[k] for k in ("ixx", "iyy", "izz")}
    for k in ("ixy", "ixz", "iyz"):
        if t[k] != 0.0:
            inertia[k] = t[k]
    out["inertia"] = inertia
    return out


def _has_mass(link: dict) -> bool:
    spec = link.get("inertial")
    return isinstance(spec, dict) or (spec is None and bool(link.get("visual")))


def _give_moving_links_mass(links: dict[str, dict], joints: dict[str, dict], out: "Converted") -> None:
    """A link the build refuses or SDF misreads for having no mass (it moves, or it is a root
    with moving joints below it and no mass welded to it) gets one: computed from its geometry at the
    recipe's density, or a point mass when it has none.  Each is recorded in ``out.repairs``."""
    moving = {"revolute", "continuous", "prismatic", "planar", "floating"}
    children: dict[str, list[dict]] = {}
    for j in joints.values():
        children.setdefault(j["parent"], []).append(j)

    def body_mass(name: str) -> bool:
        todo, seen = [name], set()
        while todo:
            n = todo.pop()
            if n in seen or n not in links:
                continue
            seen.add(n)
            if _has_mass(links[n]):
                return True
            todo += [j["child"] for j in children.get(n, []) if j["type"] == "fixed"]
        return False

    refused: dict[str, str] = {}
    for jname, j in joints.items():
        if j["type"] in moving and j["child"] in links and not body_mass(j["child"]):
            refused.setdefault(j["child"], f"no mass in the original, and it moves (joint '{jname}'): MuJoCo "
                                           "refuses a moving body without mass and Gazebo drops it")
        elif j["type"] in moving and j["child"] in links and not _has_mass(links[j["child"]]):
            refused.setdefault(j["child"], f"no mass in the original, and it moves (joint '{jname}'): SDF keeps "
                                           "it a link, which Gazebo and Drake give 1 kg without an inertial")
    child_links = {j["child"] for j in joints.values()}
    roots = [n for n in links if n not in child_links]
    for root in roots:
        below = children.get(root, [])
        if root != "world" and below and not body_mass(root):
            # the mass goes on the first link with geometry welded to the root, else on the root
            welded, todo = [], [root]
            while todo:
                welded += todo
                todo = [j["child"] for n in todo for j in children.get(n, []) if j["type"] == "fixed"]
            root = next((n for n in welded if links[n].get("visual") or isinstance(links[n].get("collision"),
                                                                                     (dict, list))), root)
            refused.setdefault(root, "no mass in the original (nor on the links welded to it), and it is (or is "
                                     "welded to) the root with moving joints below it: Gazebo's URDF conversion "
                                     "drops it and everything below it")
    given = [g["mass"] for g in out.explicit.values() if g["mass"] > 0]
    point = 1e-3 * min(given) if given else 1e-3
    for name, why in refused.items():
        link = links[name]
        if link.get("visual"):
            link.pop("inertial", None)
            out.repairs[name] = f"{why}; computed from its visual geometry at the recipe's density"
        elif isinstance(link.get("collision"), (dict, list)):
            link["inertial"] = {"source": "collision"}
            out.repairs[name] = f"{why}; computed from its collision geometry at the recipe's density"
        else:
            floor = inertia_policy.moment_floor(point)
            link["inertial"] = {"mass": point, "inertia": {"ixx": floor, "iyy": floor, "izz": floor}}
            out.repairs[name] = (f"{why}; it has no geometry: a point mass of {fmt(point)} kg (a thousandth of the "
                                 f"lightest link) with the smallest inertia a repair leaves")


def _tensor(t: dict):
    import numpy as np

    return np.array([[t["ixx"], t["ixy"], t["ixz"]], [t["ixy"], t["iyy"], t["iyz"]], [t["ixz"], t["iyz"], t["izz"]]])


def _inertia_problem(given: dict) -> str | None:
    """Why robotkit's resolver would reject the tensor (see model.resolve._check_explicit)."""
    import numpy as np

    t = given["inertia"]
    I = np.array([[t["ixx"], t["ixy"], t["ixz"]], [t["ixy"], t["iyy"], t["iyz"]], [t["ixz"], t["iyz"], t["izz"]]])
    if not np.all(np.isfinite(I)):
        return "is not finite"
    eig = np.linalg.eigvalsh(I)
    if eig.min() <= 0:
        return "is not positive definite"
    a, b, c = eig
    if a + b < c * (1 - 1e-9):
        return "violates the triangle inequality"
    return None


def _joint(el: ET.Element, name: str, problems: _Problems, warnings: list[str]) -> dict | None:
    from robotkit.recipe.schema import JOINT_TYPES

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
    origin = _origin_dict(*_origin(el.find("origin"), what, problems))
    if origin:
        joint["origin"] = origin
    if jtype not in ("fixed", "floating"):
        axis_el = el.find("axis")
        axis = _floats(axis_el.get("xyz") if axis_el is not None else None, 3, f"{what} axis", problems,
                       [1.0, 0.0, 0.0])
        if axis is not None and sum(a * a for a in axis) == 0:
            problems.add(f"{what}: axis must not be zero")
        elif axis is not None and axis != [1.0, 0.0, 0.0]:
            joint["axis"] = axis
    limit_el = el.find("limit")
    if limit_el is not None:
        if jtype in ("revolute", "prismatic"):
            limit = {}
            for key, default in (("lower", 0.0), ("upper", 0.0), ("effort", None), ("velocity", None)):
                v = _float(limit_el.get(key), f"{what} limit {key}", problems, default)
                if v is None:
                    problems.add(f"{what}: <limit> needs {key} (URDF requires effort and velocity)")
                    return None
                limit[key] = v
            if limit["lower"] == limit["upper"] and jtype == "revolute":
                # urdfdom's default limits are lower = upper = 0: files that mean "free" write that
                note = (f"limit lower == upper ({limit['lower']!r}) in the original: read as no position limit "
                        "(lower and upper default to 0 in URDF), the joint is continuous")
                warnings.append(f"{what}: {note}")
                joint["type"] = "continuous"
                joint["__note"] = note
                kept = {k: abs(limit[k]) for k in ("effort", "velocity")}
                joint["limit"] = kept
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
        elif jtype == "continuous":
            limit = {}
            for key in ("effort", "velocity"):
                v = _float(limit_el.get(key), f"{what} limit {key}", problems)
                if v is not None:
                    limit[key] = abs(v)
            if limit_el.get("lower") is not None or limit_el.get("upper") is not None:
                warnings.append(f"{what}: a continuous joint has no position limits; "
                                "its lower and upper are dropped (URDF ignores them too)")
            if limit:
                joint["limit"] = limit
        else:
            warnings.append(f"{what}: a {jtype} joint takes no <limit>; dropped (URDF ignores it too)")
    elif jtype in ("revolute", "prismatic"):
        problems.add(f"{what}: a {jtype} joint needs <limit> (lower, upper, effort, velocity)")
        return None
    dyn_el = el.find("dynamics")
    if dyn_el is not None:
        dyn = {}
        for key in ("damping", "friction"):
            v = _float(dyn_el.get(key), f"{what} dynamics {key}", problems)
            if v is not None:
                if v < 0:
                    problems.add(f"{what}: dynamics {key} must not be negative ({v!r})")
                else:
                    dyn[key] = v
        if dyn:
            joint["dynamics"] = dyn
    mimic_el = el.find("mimic")
    if mimic_el is not None:
        if not mimic_el.get("joint"):
            problems.add(f"{what}: <mimic> needs a joint")
        else:
            mimic: dict = {"joint": mimic_el.get("joint")}
            for key in ("multiplier", "offset"):
                v = _float(mimic_el.get(key), f"{what} mimic {key}", problems)
                if v is not None:
                    mimic[key] = v
            joint["mimic"] = mimic
    for child_el in el:
        tag = _local(child_el.tag)
        if tag not in ("parent", "child", "origin", "axis", "limit", "dynamics", "mimic"):
            warnings.append(f"{what}: <{tag}> is dropped (the recipe has no place for it)")
    return joint


# ---------------------------------------------------------------- gazebo blocks


def _simple_text(el: ET.Element) -> str | None:
    if len(el) or el.attrib:
        return None
    return (el.text or "").strip()


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
    and mu2 = mu1 when mu2 is not given)."""
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
            if v is None or not math.isfinite(v) or v < 0 or (key == "kp" and v == 0):
                ok = False
                break
            values[key] = v + 0.0
        if not ok or ("mu1" in values and "mu2" not in values):
            continue
        links[link]["contact"] = values
        remove.setdefault(idx, set()).update(values)


# ---------------------------------------------------------------- verbatim elements


def _label(el: ET.Element) -> str:
    tag = _local(el.tag)
    for attr in ("reference", "name"):
        if el.get(attr):
            return f"<{tag} {attr}=\"{el.get(attr)}\">"
    plugin = el.find("plugin")
    if plugin is not None and plugin.get("name"):
        return f"<{tag}> (plugin {plugin.get('name')})"
    return f"<{tag}>"


def _verbatim(node, drop: set[str], root) -> str | None:
    """The element's XML text as in the source, without the child elements named in
    ``drop``; None when nothing but whitespace and comments would remain."""
    node = node.cloneNode(True)
    if drop:
        for child in list(node.childNodes):
            if child.nodeType == child.ELEMENT_NODE and child.tagName in drop:
                prev = child.previousSibling
                if prev is not None and prev.nodeType == prev.TEXT_NODE and not prev.data.strip():
                    node.removeChild(prev)
                node.removeChild(child)
        if not any(c.nodeType == c.ELEMENT_NODE or (c.nodeType == c.TEXT_NODE and c.data.strip())
                   for c in node.childNodes):
            return None
    # namespace prefixes declared on <robot> (e.g. xmlns:xacro) that the element uses
    used = set(re.findall(r"</?([A-Za-z_][\w.\-]*):", node.toxml())) | {
        a.split(":")[0] for a in _all_attr_names(node) if ":" in a and not a.startswith("xmlns")}
    for prefix in sorted(used):
        decl = f"xmlns:{prefix}"
        if root.hasAttribute(decl) and not node.hasAttribute(decl):
            node.setAttribute(decl, root.getAttribute(decl))
    if _unformatted(node):  # xacro drops the whitespace between elements: indent for reading
        text = node.toprettyxml(indent="  ").strip()
    else:
        text = node.toxml()
    lines = [line.rstrip() for line in text.split("\n")]
    rest = [line for line in lines[1:] if line.strip()]
    if rest:
        indent = min(len(line) - len(line.lstrip(" ")) for line in rest)
        lines = [lines[0]] + [line[indent:] if line[:indent].strip() == "" else line for line in lines[1:]]
    text = "\n".join(lines)
    ET.fromstring(text)  # well-formed (the schema checks it too)
    return text


def _unformatted(node) -> bool:
    """True when the element has child elements, no whitespace between them, and no text
    mixed with elements anywhere (so indenting it changes no text)."""
    elements = [c for c in node.childNodes if c.nodeType == c.ELEMENT_NODE]
    if not elements:
        return False

    def plain(n) -> bool:
        kids = [c for c in n.childNodes if c.nodeType == c.ELEMENT_NODE]
        texts = [c for c in n.childNodes if c.nodeType in (c.TEXT_NODE, c.CDATA_SECTION_NODE)]
        if kids and texts:
            return False
        return all(plain(c) for c in kids)

    return plain(node)


def _all_attr_names(node):
    out = []
    if node.nodeType == node.ELEMENT_NODE:
        out.extend(node.attributes.keys())
        for c in node.childNodes:
            out.extend(_all_attr_names(c))
    return out


# ---------------------------------------------------------------- YAML


def fmt(x: float) -> str:
    """Shortest text that reads back as the same float64 (integral values without '.0')."""
    x = float(x)
    if x == 0:
        return "0"
    if x.is_integer() and abs(x) < 1e16:
        return str(int(x))
    text = repr(x)
    if "e" in text and "." not in text.split("e")[0]:
        mantissa, exp = text.split("e")
        text = f"{mantissa}.0e{exp}"
    return text


class _FlowList(list):
    pass


class _FlowMap(dict):
    pass


def _dumper():
    import yaml

    class Dumper(yaml.SafeDumper):
        pass

    def float_rep(dumper, value):
        text = fmt(value)
        tag = "tag:yaml.org,2002:int" if re.fullmatch(r"-?\d+", text) else "tag:yaml.org,2002:float"
        return dumper.represent_scalar(tag, text)

    def str_rep(dumper, value):
        if "\n" in value:
            return dumper.represent_scalar("tag:yaml.org,2002:str", value, style="|")
        return dumper.represent_scalar("tag:yaml.org,2002:str", value)

    Dumper.add_representer(float, float_rep)
    Dumper.add_representer(str, str_rep)
    Dumper.add_representer(_FlowList, lambda d, v: d.represent_sequence("tag:yaml.org,2002:seq", v, flow_style=True))
    Dumper.add_representer(_FlowMap, lambda d, v: d.represent_mapping("tag:yaml.org,2002:map", v.items(),
                                                                      flow_style=True))
    Dumper.add_representer(dict, lambda d, v: d.represent_mapping("tag:yaml.org,2002:map", v.items(),
                                                                  flow_style=False))
    Dumper.ignore_aliases = lambda self, data: True
    return Dumper


def _styled(value, width: int):
    """Flow style for number lists and for mappings short enough to read on one line."""
    if isinstance(value, list):
        if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
            return _FlowList(value)
        return [_styled(v, width - 2) for v in value]
    if isinstance(value, dict):
        inner = {k: _styled(v, width - 2) for k, v in value.items()}
        flat = all(not isinstance(v, (dict, list)) or isinstance(v, (_FlowList, _FlowMap)) for v in inner.values())
        if flat and all(not (isinstance(v, str) and "\n" in v) for v in inner.values()):
            candidate = _FlowMap(inner)
            if len(_dump_one(candidate)) <= width:
                return candidate
        return inner
    return value


def _dump_one(value) -> str:
    import yaml

    return yaml.dump(value, Dumper=_dumper(), default_flow_style=False, sort_keys=False, width=10**9,
                     allow_unicode=True).strip()


def dump_recipe(recipe: dict, header: list[str] | None = None,
                comments: dict[str, dict[str, str]] | None = None) -> str:
    """The recipe as readable YAML: top-level keys in order, a blank line between sections,
    flow style for short vectors and mappings; ``comments[section][name]`` goes above that
    entry (e.g. what an import repaired on a link)."""
    import yaml

    parts = []
    for line in header or []:
        parts.append(f"# {line}".rstrip() + "\n")
    keys = [k for k in TOP_KEYS if k in recipe] + [k for k in recipe if k not in TOP_KEYS]
    scalars = [k for k in keys if not isinstance(recipe[k], (dict, list))]
    sections = [k for k in keys if k not in scalars]
    dumper = _dumper()
    opts = dict(Dumper=dumper, default_flow_style=False, sort_keys=False, width=10**9, allow_unicode=True)
    parts.append(yaml.dump({k: recipe[k] for k in scalars}, **opts))
    for key in sections:
        value = recipe[key]
        if key == "materials":
            styled = {name: _styled(m, 200) for name, m in value.items()}
        elif key in ("links", "joints"):
            notes = (comments or {}).get(key, {})
            if notes:
                text = [f"\n{key}:\n"]
                for name, entry in value.items():
                    for line in _wrap(notes.get(name, "")):
                        text.append(f"  # {line}\n")
                    entry_text = yaml.dump({name: _styled_entry(entry)}, **opts)
                    text.append("".join(f"  {line}" if line.strip() else line
                                        for line in entry_text.splitlines(keepends=True)))
                parts.append("".join(text))
                continue
            styled = {name: _styled_entry(entry) for name, entry in value.items()}
        else:
            styled = _styled(value, 100)
        parts.append("\n" + yaml.dump({key: styled}, **opts))
    return "".join(parts)


def _wrap(text: str, width: int = 96) -> list[str]:
    import textwrap

    return textwrap.wrap(text, width, break_long_words=False, break_on_hyphens=False) if text else []


def _styled_entry(entry: dict) -> dict:
    """A link or joint: its own keys in block style, each value as compact as reads well."""
    return {k: _styled(v, 110 - len(k)) for k, v in entry.items()}
