"""Robot -> URDF text (templates/urdf/robot.urdf.j2)."""

from __future__ import annotations

from dataclasses import replace

from robotkit.emit import layout
from robotkit.emit.env import render
from robotkit.emit.formats import Format
from robotkit.emit.gazebo import kept_fixed_joints
from robotkit.emit.meshfiles import collision_file
from robotkit.emit.sensors import contexts
from robotkit.model.robot import Geom, Mimic, Robot, Shape


MASSLESS = 1e-300
"""The mass a URDF gives a massless link: every consumer reads it as massless (it vanishes in
any sum with a real mass), PyBullet does not replace it by 1 kg as it does a missing
``<inertial>``, and libsdformat can lump two of them (0 + 0 is a NaN centre of mass there)."""


def massless_mass(robot: Robot, link) -> float | None:
    """None for a link with mass; otherwise the mass its URDF ``<inertial>`` carries: 0 for a
    root fixed to the world (PyBullet then keeps the base static), else :data:`MASSLESS`."""
    if link.inertial is not None:
        return None
    if link.name == robot.root and (robot.base == "fixed" or link.name == "world"):
        return 0.0
    return MASSLESS


def typed_transmissions(text: str) -> tuple[str, list[tuple[str, str]]]:
    """``text`` with a ``<type>`` given to each ``<transmission>`` that names its class only in
    ``<plugin>`` (ros2_control's form): Drake refuses a transmission without ``<type>``, and the
    readers of ``<plugin>`` do not look at it.  Returns (text, [(transmission, type)])."""
    import re

    added = []

    def typed(m: re.Match) -> str:
        block = m.group(0)
        plugin = re.search(r"<plugin>\s*([^<]*?)\s*</plugin>", block)
        if re.search(r"<type[\s>]", block) or plugin is None:
            return block
        name = re.search(r'\bname\s*=\s*["\']([^"\']*)', m.group(1))
        added.append((name.group(1) if name else "", plugin.group(1)))
        return f"{m.group(1)}<type>{plugin.group(1)}</type>{block[len(m.group(1)):]}"

    return re.sub(r"(<transmission\b[^>]*>)[\s\S]*?</transmission>", typed, text), added


def mesh_uri(robot: Robot, geom: Geom, role: str = "visual") -> str:
    path = collision_file(geom.shape.mesh) if role == "collision" else geom.shape.mesh.path
    return f"package://{robot.name}/{layout.MESHES}/{path}"


def urdf_geoms(geoms) -> list[Geom]:
    """URDF has no capsule: a cylinder and two spheres make the same shape."""
    out = []
    for g in geoms:
        s = g.shape
        if s.kind != "capsule":
            out.append(g)
            continue
        out.append(replace(g, shape=Shape("cylinder", radius=s.radius, length=s.length)))
        for z in (-s.length / 2, s.length / 2):
            out.append(replace(g, shape=Shape("sphere", radius=s.radius), offset=(0.0, 0.0, z)))
    return out


def geom_context(robot: Robot, geom: Geom, role: str = "visual") -> dict:
    s = geom.shape
    pose = geom.pose
    ctx = {"xyz": pose.xyz, "rpy": pose.rpy, "kind": s.kind, "material": geom.material}
    if s.kind == "mesh":
        ctx["uri"] = mesh_uri(robot, geom, role)
        ctx["scale"] = s.mesh.out_scale if any(v != 1.0 for v in s.mesh.out_scale) else None
    elif s.kind == "box":
        ctx["size"] = s.size
    else:
        ctx["radius"] = s.radius
        ctx["length"] = s.length
    return ctx


def context(robot: Robot) -> dict:
    materials = {m.name: m for m in robot.materials}
    used = sorted({g.material for link in robot.links for g in link.visuals if g.material})
    links = []
    for link in robot.links:
        gazebo_material = None
        for g in link.visuals:
            if g.material and materials[g.material].gazebo:
                gazebo_material = materials[g.material].gazebo
                break
        links.append({
            "name": link.name,
            "visuals": [geom_context(robot, g) for g in link.visuals],
            "collisions": [geom_context(robot, g, "collision") for g in urdf_geoms(link.collisions_for("urdf"))],
            "inertial": link.inertial,
            "massless": massless_mass(robot, link),
            "gazebo_material": gazebo_material,
            "contact": link.contact if link.collisions else None,
        })
    return {
        "robot": robot,
        "extras": [typed_transmissions(x)[0] for x in robot.urdf_extras],
        "kept_fixed": kept_fixed_joints(robot),
        "massless_note": any(link["massless"] for link in links),
        "massless_mass": MASSLESS,
        "sensors": contexts(robot),
        "actuators": actuator_contexts(robot),
        "materials": [materials[name] for name in used],
        "links": links,
        "joints": robot.joints,
        "mimics": followed_mimics(robot),
    }


def followed_mimics(robot: Robot) -> dict[str, Mimic]:
    """Each mimic joint's line to the joint its chain starts from: a mimic of a mimic (a telescoping
    arm's segments) composed, since URDF readers (Drake's, libsdformat's, Pinocchio's) follow one
    mimic, not a chain.  The recipe and the MJCF keep the chain."""
    by_name, out = {j.name: j for j in robot.joints}, {}
    for j in robot.joints:
        if j.mimic is None:
            continue
        leader, multiplier, offset, seen = j.mimic.joint, j.mimic.multiplier, j.mimic.offset, {j.name}
        while by_name[leader].mimic is not None and leader not in seen:
            seen.add(leader)
            up = by_name[leader].mimic
            leader, multiplier, offset = up.joint, multiplier * up.multiplier, multiplier * up.offset + offset
        out[j.name] = Mimic(leader, multiplier, offset)
    return out


def actuator_contexts(robot: Robot) -> list[dict]:
    """Each actuator's command interface and range, its gains, and its joint's ``home`` value
    (ros2_control's ``initial_value``)."""
    joints = {j.name: j for j in robot.joints}
    home = dict(robot.home().values) if robot.home() is not None else {}
    out = []
    for a in robot.actuators:
        j = joints[a.joint]
        lim = j.limit
        lo = hi = None
        if a.interface == "position" and j.type != "continuous":
            lo, hi = lim.lower, lim.upper
        elif a.interface == "velocity" and lim is not None and lim.velocity:
            lo, hi = -lim.velocity, lim.velocity
        elif a.interface == "effort" and lim is not None and lim.effort:
            lo, hi = -lim.effort, lim.effort
        out.append({"joint": a.joint, "interface": a.interface, "min": lo, "max": hi, "p": a.p, "i": a.i, "d": a.d,
                    "initial": home.get(a.joint)})
    return out


def render_urdf(robot: Robot) -> str:
    return render("urdf/robot.urdf.j2", **context(robot))


TEMPLATES = ("urdf/robot.urdf.j2", "sensors/sdf.j2", "sensors/classic.j2")

FORMATS = [Format("urdf", render_urdf, layout.URDF, TEMPLATES, consumed=True)]
