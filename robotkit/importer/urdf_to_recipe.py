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

from robotkit.importer.inertials import (  # noqa: F401  (no_inertial_form: used by the tests)
    _give_moving_links_mass, _inertial, chosen_inertial, no_inertial_form,
)
from robotkit.importer.meshes import MeshResolver, MeshUse
from robotkit.importer.names import _material_name, _name_hint, _valid_frame_name, _valid_name
from robotkit.importer.parsing import _Problems, _float, _floats, _fmt_list, _local, _origin, _origin_dict
from robotkit.importer.recipe_writer import dump_recipe, fmt  # noqa: F401  (the import's writer)
from robotkit.errors import Problem, RobotkitError
from robotkit.emit.urdf import MASSLESS
from robotkit.errors import short_number
from robotkit.recipe.schema import MIN_MASS, UNITS

GREY = [0.5, 0.5, 0.5, 1.0]
CONTACT_KEYS = ("mu1", "mu2", "kp", "kd")




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




# ---------------------------------------------------------------- parsing helpers


















# ---------------------------------------------------------------- mesh files




# ---------------------------------------------------------------- the conversion


def urdf_to_recipe(text: str, source: str | os.PathLike, recipe_path: str | os.PathLike,
                   package_paths: dict[str, str] | None = None, copy_meshes: bool = False,
                   recompute_inertials: bool = False, density: float | None = None,
                   inertia_policy: str = "repair") -> Converted:
    """Map the URDF ``text`` (read from ``source``) to a recipe dict for ``recipe_path``.
    ``inertia_policy``: what a link whose given tensor no real body has gets
    (:func:`robotkit.importer.inertials.chosen_inertial`).

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

    # global materials (first definition of a name wins, as in urdfdom; a definition inside a link's
    # visual joins them for the name-only references of the links after it)
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
        if (rgba is not None or texture is not None) and name:  # urdfdom: a link's definition serves later links
            global_materials.setdefault(name, vis_mat)
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
        if given is not None and 0 < given["mass"] < MIN_MASS and not any(given["inertia"].values()):
            # robotkit's own URDF writes a massless link as 1e-300 kg with no inertia: read back as massless
            if given["mass"] != MASSLESS:
                warnings.append(f"link '{name}': mass {given['mass']!r} kg with no inertia, below the smallest mass "
                                f"a recipe takes ({short_number(MIN_MASS)} kg): read as a massless link")
            given = dict(given, mass=0.0)
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
                source = ("collision" if collisions and not (visuals and _same_shapes(visuals, collisions))
                          else "visual" if visuals else None)
                link["inertial"] = chosen_inertial(name, given, source, inertia_policy, out.repairs)
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
    from robotkit.emit.sdf import names_apart

    for name, sdf_name in names_apart(links, joints).items():
        if sdf_name != name:  # ROS accepts it; an SDF model has one namespace for links and joints
            note = f"named like a link in the original: SDF, where links and joints share names, calls it '{sdf_name}'"
            out.joint_notes[name] = "; ".join(filter(None, (out.joint_notes.get(name), note)))
            warnings.append(f"joint '{name}': {note}")
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
        out.joint_notes[name] = "; ".join(filter(None, (out.joint_notes.get(name), note)))
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
        missing = [j.get("name") for j in el.findall("joint") if j.get("name") not in joints] \
            if tag == "transmission" else []
        if missing:  # the Jackal's transmissions name joint 'front_left_wheel' for 'front_left_wheel_joint'
            note = (f"transmission '{el.get('name')}' is left out: it names joint '{missing[0]}', which the robot "
                    "does not have (Drake refuses the URDF, ros_control the transmission)")
            out.left_out.append(note)
            warnings.append(note)
            continue
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

    from robotkit.geometry import rpy_matrix

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
            elif limit["lower"] == limit["upper"]:  # prismatic
                # it can only be at that position: consumers that keep limits (Gazebo, Drake,
                # Pinocchio) hold it there; MuJoCo ignores equal limits and lets it slide away
                at = limit["lower"]
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
                el = _without_mimic(el, joint, what, warnings)
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


def _moved(at: float) -> str:
    return "" if at == 0 else f", its origin moved {fmt(at)} along the axis"


def _slid(el: ET.Element, what: str, problems: _Problems, axis: list[float], at: float) -> dict | None:
    """The joint's origin with the child slid ``at`` along the (unit) axis: where the prismatic
    joint puts it at position ``at``."""
    import numpy as np

    from robotkit.geometry import rpy_matrix

    xyz, rpy = _origin(el.find("origin"), what, problems)
    a = np.asarray(axis, dtype=float)
    moved = np.asarray(xyz, dtype=float) + rpy_matrix(rpy) @ (a / np.linalg.norm(a)) * at
    return _origin_dict([float(v) + 0.0 for v in moved], rpy)


def _without_mimic(el: ET.Element, joint: dict, what: str, warnings: list[str]) -> ET.Element:
    """A copy of the joint element without <mimic> when it has one (a fixed joint follows no joint)."""
    import copy

    mimic = el.find("mimic")
    if mimic is None:
        return el
    warnings.append(f"{what}: a fixed joint follows no other joint: its <mimic> is dropped")
    joint["__note"] += "; its mimic is dropped"
    el = copy.deepcopy(el)
    el.remove(el.find("mimic"))
    return el


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
    used = set(re.findall(r"</?([A-Za-z_][\w.\-]*):", _xml(node))) | {
        a.split(":")[0] for a in _all_attr_names(node) if ":" in a and not a.startswith("xmlns")}
    for prefix in sorted(used):
        decl = f"xmlns:{prefix}"
        if root.hasAttribute(decl) and not node.hasAttribute(decl):
            node.setAttribute(decl, root.getAttribute(decl))
    text = _xml(node, "" if _unformatted(node) else None)  # xacro drops the whitespace between elements:
    # indent for reading
    lines = [line.rstrip() for line in text.split("\n")]
    rest = [line for line in lines[1:] if line.strip()]
    if rest:
        indent = min(len(line) - len(line.lstrip(" ")) for line in rest)
        lines = [lines[0]] + [line[indent:] if line[:indent].strip() == "" else line for line in lines[1:]]
    text = "\n".join(lines)
    ET.fromstring(text)  # well-formed (the schema checks it too)
    return text


def _xml(node, indent: str | None = None) -> str:
    """The XML text of a minidom node, attributes in document order; with ``indent``, one element a
    line (for elements holding elements only).  minidom's own writer is not used: importing xacro
    replaces it for the whole process (sorted attributes, whitespace dropped), so the recipe
    would depend on whether a xacro file was read before."""
    def esc(text: str) -> str:
        return text.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;").replace(">", "&gt;")

    if node.nodeType == node.TEXT_NODE:
        return esc(node.data)
    if node.nodeType == node.COMMENT_NODE:
        return f"<!--{node.data}-->"
    if node.nodeType == node.CDATA_SECTION_NODE:
        return f"<![CDATA[{node.data}]]>"
    if node.nodeType != node.ELEMENT_NODE:
        return ""
    head = node.tagName + "".join(f' {a.name}="{esc(a.value)}"' for a in node.attributes.values())
    kids = list(node.childNodes)
    if not kids:
        return f"<{head}/>"
    if indent is None or (len(kids) == 1 and kids[0].nodeType == node.TEXT_NODE):
        return f"<{head}>" + "".join(_xml(k) for k in kids) + f"</{node.tagName}>"
    inner = [_xml(k, indent + "  ") for k in kids if not (k.nodeType == k.TEXT_NODE and not k.data.strip())]
    return f"<{head}>\n" + "".join(f"{indent}  {x}\n" for x in inner) + f"{indent}</{node.tagName}>"


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


















