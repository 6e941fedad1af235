"""Robot -> URDF text (templates/urdf/robot.urdf.j2)."""

from __future__ import annotations

from robotkit.emit.env import render
from robotkit.model.robot import Geom, Robot


def mesh_uri(robot: Robot, geom: Geom) -> str:
    return f"package://{robot.name}/meshes/{geom.shape.mesh.path}"


def urdf_geoms(geoms) -> list[Geom]:
    """URDF has no capsule: a cylinder and two spheres make the same shape."""
    from dataclasses import replace

    from robotkit.model.robot import Shape

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


def geom_context(robot: Robot, geom: Geom) -> dict:
    s = geom.shape
    pose = geom.pose
    ctx = {"xyz": pose.xyz, "rpy": pose.rpy, "kind": s.kind, "material": geom.material}
    if s.kind == "mesh":
        ctx["uri"] = mesh_uri(robot, geom)
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
            "collisions": [geom_context(robot, g) for g in urdf_geoms(link.collisions_for("urdf"))],
            "inertial": link.inertial,
            "gazebo_material": gazebo_material,
            "contact": link.contact if link.collisions else None,
        })
    from robotkit.emit.sensors import contexts

    return {
        "robot": robot,
        "sensors": contexts(robot),
        "actuators": actuator_contexts(robot),
        "materials": [materials[name] for name in used],
        "links": links,
        "joints": robot.joints,
    }


def actuator_contexts(robot: Robot) -> list[dict]:
    joints = {j.name: j for j in robot.joints}
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
        out.append({"joint": a.joint, "interface": a.interface, "min": lo, "max": hi, "p": a.p, "i": a.i, "d": a.d})
    return out


def render_urdf(robot: Robot) -> str:
    return render("urdf/robot.urdf.j2", **context(robot))
