"""Name rules of the importer: which URDF names a recipe keeps as they are (links and joints may
hold '/' between parts, as ROS frame names do), and recipe-safe names for what it renames
(materials, a robot without a valid name)."""

from __future__ import annotations

import re

from robotkit.recipe.schema import FRAME_NAME_HINT, FRAME_NAME_RE, NAME_RE


def valid_name(name: str | None) -> bool:
    return bool(name) and bool(NAME_RE.match(name))


def valid_frame_name(name: str | None) -> bool:
    """Link and joint names may hold '/' between parts, as ROS frame names do."""
    return bool(name) and bool(FRAME_NAME_RE.match(name))


def material_name(name: str, taken: set[str]) -> str:
    base = re.sub(r"[^A-Za-z0-9_.\-]", "_", name or "material")
    if not re.match(r"[A-Za-z_]", base):
        base = "_" + base
    out, i = base, 2
    while out in taken:
        out, i = f"{base}_{i}", i + 1
    return out


def package_name(name: str) -> str:
    """``name`` as a ROS package name (REP 144; catkin refuses a '.' or a leading '_' or digit
    and warns of capitals): lower case letters, digits and '_', a letter first.  An imported
    robot's name is its ROS package's (``robotkit build`` names the package after the robot)."""
    out = re.sub(r"[^a-z0-9_]", "_", name.lower()).lstrip("_")
    return out if out[:1].isalpha() else f"robot_{out}".rstrip("_")


def renamed_robot(original: str, name: str, kind: str) -> list[str]:
    """The line that states :func:`package_name`'s change, if it made one (the recipe's header
    and the import's notes); ``kind`` is the original's format (MJCF, SDF)."""
    if original == name:
        return []
    return [f"robot '{original}' (the {kind}'s model name) named '{name}': the robot's name is its ROS package's, "
            "which holds lower case letters, digits and '_', a letter first (REP 144)"]


def name_hint() -> str:
    return FRAME_NAME_HINT


REFERENCES = (("joint", "parent", "link"), ("joint", "child", "link"), ("joint", "mimic", "joint"),
              ("transmission", "joint", "name"), ("ros2_control", "joint", "name"))
"""(top-level element, its child, attribute): where a URDF names a link or joint."""


def without_leading_slash(children: list) -> dict[str, tuple[str, str]]:
    """Link and joint names with a leading '/' (the old tf_prefix style: ``/base_link``, the
    Interbotix arms' ``${robot_name}/base_link`` with an empty name) lose it, in the elements
    ``children`` of <robot> (edited in place) and wherever they are named: joints' parent,
    child and mimic, gazebo references, transmissions and ros2_control, and a gazebo block's
    text that is exactly the name (a plugin's frame).  A name whose bare form is taken or
    still invalid keeps its slash (the import refuses it).  Returns old name -> (kind, new)."""
    named = {(el.tag, el.get("name")) for el in children if el.tag in ("link", "joint")}
    renamed: dict[str, tuple[str, str]] = {}
    for el in children:
        name = el.get("name")
        if el.tag not in ("link", "joint") or not name or not name.startswith("/"):
            continue
        bare = name.lstrip("/")
        if valid_frame_name(bare) and (el.tag, bare) not in named:
            renamed[name] = (el.tag, bare)
            named.add((el.tag, bare))
    if not renamed:
        return renamed
    for el in children:
        if el.tag in ("link", "joint") and el.get("name") in renamed:
            el.set("name", renamed[el.get("name")][1])
        if el.tag == "gazebo" and el.get("reference") in renamed:
            el.set("reference", renamed[el.get("reference")][1])
        for tag, child, attr in REFERENCES:
            for ref in el.findall(child) if el.tag == tag else ():
                if ref.get(attr) in renamed:
                    ref.set(attr, renamed[ref.get(attr)][1])
        for sub in el.iter() if el.tag == "gazebo" else ():
            if sub is not el and isinstance(sub.tag, str) and (sub.text or "").strip() in renamed and not len(sub):
                sub.text = renamed[sub.text.strip()][1]
    return renamed


JOINT_REFERENCES = (("joint", "mimic"), ("transmission", "joint"), ("ros2_control", "joint"))
"""(top-level element, its child): where a URDF names a joint (attribute ``name`` or ``joint``)."""


def joints_apart_from_links(children: list) -> dict[str, str]:
    """Joints named like a link (SO-ARM100's joint 'gripper' on its link 'gripper') get ``_joint``
    appended (then a number), as model.sdf names them (robotkit.emit.sdf.joint_names): links and
    joints share one namespace in SDF, and libsdformat, reading the URDF for Gazebo, refuses the
    pair.  Renamed in the elements ``children`` of <robot> (edited in place) and where mimics,
    transmissions and ros2_control name the joint; a gazebo block naming it is left to the link.
    Returns old name -> new."""
    links = {el.get("name") for el in children if el.tag == "link"}
    taken = links | {el.get("name") for el in children if el.tag == "joint"}
    renamed: dict[str, str] = {}
    for el in children:
        name = el.get("name")
        if el.tag != "joint" or name not in links or name in renamed:
            continue
        new, n = f"{name}_joint", 2
        while new in taken:
            new, n = f"{name}_joint{n}", n + 1
        taken.add(new)
        renamed[name] = new
    for el in children:
        if el.tag == "joint" and el.get("name") in renamed:
            el.set("name", renamed[el.get("name")])
        for tag, child in JOINT_REFERENCES:
            for ref in el.findall(child) if el.tag == tag else ():
                attr = "joint" if child == "mimic" else "name"
                if ref.get(attr) in renamed:
                    ref.set(attr, renamed[ref.get(attr)])
    return renamed
