"""What an SDF model holds beside links and joints: sensors and plugins (kept verbatim as
``<gazebo>`` blocks of the recipe's ``urdf_extras``, which the build carries into model.sdf and
the URDF: MJCF loses them, stated), ``<frame>``s (a massless link fixed where the frame is),
model.config's metadata, and every other element the recipe has no place for (stated)."""

from __future__ import annotations

import copy

import numpy as np

from robotkit.importer.sdf.frames import pose_of
from robotkit.importer.sdf.leftovers import joint_leftovers, script_uris, shape_leftovers
from robotkit.importer.sdf.model import children
from robotkit.importer.sdf.tree import origin_of
from robotkit.urdfxml import is_element

LINK_KEPT = {"pose", "inertial", "visual", "collision", "sensor"}
LINK_DEFAULTS = {"gravity": "true", "self_collide": "false", "kinematic": "false", "enable_wind": "false",
                 "must_be_base_link": "false"}
MODEL_KEPT = {"pose", "static", "link", "joint", "frame", "plugin", "model"}


def add_extras(src, m, tree, recipe: dict, ledger, surfaces: dict) -> None:
    extras: list[str] = []
    left: dict[tuple[str, ...], list[str]] = {}
    for name, link in m.links.items():
        O = np.linalg.inv(tree.offset(name, link.T))
        for sensor in children(link.el, "sensor"):
            extras.append(_block(sensor, O, name))
            ledger.add(src.where("sensor", sensor.get("name"), name), f"sensor '{sensor.get('name')}' "
                       f"({sensor.get('type')}) of link '{name}'", "MJCF",
                       "dropped (kept verbatim in a <gazebo> block of urdf_extras, for model.sdf and the URDF)")
        dropped = _other(link.el, surfaces.get(name, []))
        if dropped:
            left.setdefault(tuple(dropped), []).append(name)
    _grouped(src, ledger, "link", left)
    _scripts(src, m, ledger)
    _plugins(src, m, extras, ledger)
    for el in (c for c in src.model if is_element(c) and c.tag not in MODEL_KEPT):
        if not (el.tag in ("self_collide", "allow_auto_disable", "enable_wind") and (el.text or "").strip() in
                ("false", "0", *(("true", "1") if el.tag == "allow_auto_disable" else ()))):
            ledger.add(src.where(el.tag, el.get("name")), f"model <{el.tag}>", "all", "dropped: no place in the recipe")
    _frames(src, m, tree, ledger)
    joints: dict[tuple[str, ...], list[str]] = {}
    for name, j in m.joints.items():
        left = joint_leftovers(j.el)
        if left and name in tree.joint_map:
            joints.setdefault(tuple(left), []).append(name)
    _grouped(src, ledger, "joint", joints)
    for nested in src.model.iter("model"):
        for plugin in children(nested, "plugin") if nested is not src.model else ():
            ledger.add(str(src.path), f"plugin '{plugin.get('name')}' of included model '{nested.get('name')}'",
                       "all", "dropped (its names are the included model's)")
    _, P = pose_of(src.model)
    if not np.allclose(P, np.eye(4), rtol=0, atol=0) and not tree.world_pose:
        ledger.add(src.where("model", m.name), f"model '{m.name}' <pose>", "all", "dropped: where the model stands "
                   "in a world (the recipe describes the robot; a world places it)")
    if extras:
        recipe["urdf_extras"] = extras


def _plugins(src, m, extras: list, ledger) -> None:
    """The model's plugins, verbatim but for the names of nested models' elements, which the
    recipe writes with '/' (ArduPilot's 'dolly_ardupilot::dolly::back_motor_joint' names the
    joint the rebuild calls 'dolly/back_motor_joint'), stated."""
    names = set(m.links) | set(m.joints) | set(m.frames)
    for plugin in m.plugins:
        plugin = copy.deepcopy(plugin)
        renamed = _flat_references(plugin, names, m.name)
        extras.append(_block(plugin, None, None))
        said = (f"; the names in it of {renamed} nested model element{'s' if renamed > 1 else ''} written as the "
                "recipe's (a::b as a/b)") if renamed else ""
        ledger.add(src.where("plugin", plugin.get("name")), f"plugin '{plugin.get('name')}' "
                   f"({plugin.get('filename')})", "MJCF",
                   f"dropped (kept verbatim in a <gazebo> block of urdf_extras, for model.sdf and the URDF){said}")


def _flat_references(el, names: set, own: str) -> int:
    """Each text of ``el`` naming a nested model's element ('a::b', after the model's own name if
    it begins with it) written 'a/b' (the rest after it kept: 'a::b::sensor' as 'a/b::sensor');
    how many."""
    count = 0
    for leaf in el.iter():
        text = (leaf.text or "").strip() if isinstance(leaf.tag, str) and not len(leaf) else ""
        head = f"{own}::" if text.startswith(f"{own}::") else ""
        parts = text[len(head):].split("::")
        k = next((k for k in range(len(parts), 1, -1) if "/".join(parts[:k]) in names), 0)
        if k:
            leaf.text = head + "::".join(["/".join(parts[:k]), *parts[k:]])
            count += 1
    return count


def _block(el, O, link: str | None) -> str:
    from lxml import etree  # heavy: only when the model has one

    el = copy.deepcopy(el)
    if O is not None and not np.allclose(O, np.eye(4)):
        _, P = pose_of(el)
        pose = el.find("pose")
        if pose is None:
            pose = etree.SubElement(el, "pose")
        o = origin_of(O @ P) or {}
        pose.text = " ".join(f"{v:.17g}" for v in list(o.get("xyz", [0, 0, 0])) + list(o.get("rpy", [0, 0, 0])))
        pose.attrib.pop("relative_to", None)
    block = etree.Element("gazebo", reference=link) if link else etree.Element("gazebo")
    block.append(el)
    etree.indent(block, space="  ")
    return etree.tostring(block, encoding="unicode").strip()


def _grouped(src, ledger, kind: str, groups: dict) -> None:
    """One ledger line for the links (joints) that drop the same (youbot's 21 surfaces, cessna's
    10 joints' <physics>), at the first one's line."""
    for dropped, names in groups.items():
        named = ", ".join(f"'{n}'" for n in names)
        ledger.add(src.where(kind, names[0]), f"{kind}{'s' if len(names) > 1 else ''} {named}", "all",
                   f"dropped (no place in the recipe): {', '.join(dropped)}")


def _other(el, dropped: list) -> list[str]:
    """What a link holds that the recipe has no place for (``dropped``: of its collisions' surfaces)."""
    dropped = list(dropped) + shape_leftovers(el)
    for child in el:
        if not is_element(child) or child.tag in LINK_KEPT:
            continue
        value = {"1": "true", "0": "false"}.get((child.text or "").strip().lower(), (child.text or "").strip().lower())
        if LINK_DEFAULTS.get(child.tag) != value:
            dropped.insert(0, f"<{child.tag}> {value}".strip())
    return dropped


def _scripts(src, m, ledger) -> None:
    """One line per set of material script <uri>s the recipe drops (the visuals' own scripts, not
    Gazebo's standard materials), naming the visuals that use it."""
    users: dict[tuple[str, ...], list[tuple[str, str]]] = {}
    for name, link in m.links.items():
        for visual, uris in script_uris(link.el):
            users.setdefault(uris, []).append((name, visual))
    for uris, where in users.items():
        link, visual = where[0]
        ledger.add(src.where("visual", visual, link), f"material script <uri> {', '.join(uris)}", "all",
                   f"dropped from {len(where)} visual{'s' if len(where) > 1 else ''} "
                   f"({', '.join(v for _, v in where)}): only Gazebo's standard materials are read")


def _frames(src, m, tree, ledger) -> None:
    for name, (attached, T) in m.frames.items():
        base = attached if attached in tree.frame else None
        if base is None or name in tree.links:
            ledger.add(src.where("frame", name), f"frame '{name}'", "all", f"dropped: attached to '{attached}', "
                       "not a link")
            continue
        tree.links[name] = {}
        tree.frame[name] = T
        joint = {"type": "fixed", "parent": base, "child": name}
        o = origin_of(np.linalg.inv(tree.frame[base]) @ T)
        if o:
            joint["origin"] = o
        tree.joints[f"{name}_frame"] = joint
        tree.link_notes[name] = f"SDF <frame> '{name}' (attached to '{attached}'): a massless link fixed there"
