"""Robot -> a xacro macro of its URDF (templates/urdf/robot.urdf.xacro.j2), so that a
generated robot or sensor can be included in a larger xacro assembly:

    <xacro:include filename="$(find ROBOT)/urdf/ROBOT.urdf.xacro"/>
    <xacro:ROBOT prefix="left_" parent="base_link">
      <origin xyz="0 0.2 0" rpy="0 0 0"/>
    </xacro:ROBOT>

The macro body is the URDF template's body (the template extends robot.urdf.j2) rendered
from a copy of the robot whose link, joint and material names carry ``${prefix}``; a
fixed joint attaches the root link to ``${parent}`` at the ``origin`` block.  In the raw
``urdf_extras`` blocks, attributes and texts that name a link or joint (``reference``,
``<joint name=...>`` of a transmission, a plugin's ``<leftJoint>``...) get the prefix too,
as do the names of transmissions and actuators,
and ``${``/``$(`` are escaped so that xacro copies them literally.
"""

from __future__ import annotations

import re
import xml.dom.minidom as minidom
from dataclasses import replace

from robotkit.emit import layout
from robotkit.emit.env import render
from robotkit.emit.formats import Format
from robotkit.emit.urdf import TEMPLATES, context
from robotkit.model.robot import Robot

PREFIX = "${prefix}"
NAME_ATTRS = ("reference", "link", "joint", "parent", "child")


def prefixed(robot: Robot, prefix: str = PREFIX) -> Robot:
    """The robot with ``prefix`` in front of every link, joint and material name."""
    def p(name):
        return None if name is None else prefix + name

    links = tuple(replace(link, name=p(link.name),
                          visuals=tuple(replace(g, material=p(g.material)) for g in link.visuals),
                          collisions=tuple(replace(g, material=p(g.material)) for g in link.collisions))
                  for link in robot.links)
    joints = tuple(replace(j, name=p(j.name), parent=p(j.parent), child=p(j.child),
                           mimic=replace(j.mimic, joint=p(j.mimic.joint)) if j.mimic else None)
                   for j in robot.joints)
    materials = tuple(replace(m, name=p(m.name)) for m in robot.materials)
    names = {link.name for link in robot.links} | {j.name for j in robot.joints}
    extras = tuple(_prefix_extra(x, names, prefix) for x in robot.urdf_extras)
    out = replace(robot, links=links, joints=joints, materials=materials, urdf_extras=extras)
    changes = {}
    if getattr(robot, "sensors", ()):  # sensor names, frames and relative topics are per instance
        changes["sensors"] = tuple(
            replace(s, name=p(s.name), link=p(s.link), optical_frame=p(s.optical_frame),
                    topic=s.topic if not s.topic or s.topic.startswith("/") else prefix + s.topic)
            for s in robot.sensors)
    if getattr(robot, "actuators", ()):
        changes["actuators"] = tuple(replace(a, joint=p(a.joint)) for a in robot.actuators)
    return replace(out, **changes) if changes else out


def _prefix_extra(text: str, names: set[str], prefix: str) -> str:
    node = minidom.parseString(text).documentElement

    def walk(el):
        for attr in list(el.attributes.keys()):
            value = el.getAttribute(attr)
            new = escape_dollars(value)
            if value in names and (attr in NAME_ATTRS or (attr == "name" and el.tagName in ("joint", "link"))):
                new = prefix + value
            elif attr == "name" and el.tagName in ("transmission", "actuator"):
                new = prefix + new  # unique per instance, as ros_control needs
            if new != value:
                el.setAttribute(attr, new)
        for child in el.childNodes:
            if child.nodeType == child.ELEMENT_NODE:
                walk(child)
            elif child.nodeType in (child.TEXT_NODE, child.CDATA_SECTION_NODE):
                stripped = child.data.strip()
                if stripped in names:
                    child.data = child.data.replace(stripped, prefix + stripped, 1)
                else:
                    child.data = escape_dollars(child.data)

    walk(node)
    # the URDF template indents an extra's first line by 2: match its other lines to it
    return node.toxml().replace("\n", "\n  ")


def escape_dollars(text: str) -> str:
    """``${``/``$(`` -> ``$${``/``$$(``: xacro copies them as written instead of evaluating."""
    return re.sub(r"\$+(?=[{(])", lambda m: m.group(0) + "$", text)


def render_xacro_macro(robot: Robot) -> str:
    """The text of ``urdf/<robot>.urdf.xacro``: a macro ``<robot>`` with params
    ``prefix parent *origin``."""
    p = prefixed(robot)
    joint_names = {j.name for j in robot.joints}
    mount = f"{robot.root}_mount_joint"
    i = 2
    while mount in joint_names:
        mount, i = f"{robot.root}_mount_joint_{i}", i + 1
    ctx = context(p)  # mesh URIs keep the package name: package://<robot>/meshes/...
    # what the body names after the robot (e.g. its <ros2_control> system) is per instance
    ctx["robot"] = replace(p, name=PREFIX + robot.name)
    return render("urdf/robot.urdf.xacro.j2", **ctx, package=robot.name, macro_name=robot.name,
                  root=p.root, root_name=robot.root, mount_joint=PREFIX + mount)


FORMATS = [Format("xacro", render_xacro_macro, layout.XACRO, ("urdf/robot.urdf.xacro.j2", *TEMPLATES),
                  needs=("urdf",))]  # the URDF as a macro: refused with it
