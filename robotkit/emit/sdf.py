"""Robot -> SDF 1.9 model (templates/sdf/model.sdf.j2), the newest version Debian's libsdformat 12 validates.

Frames mirror URDF exactly: a joint's pose is relative to its parent link, a child link's
pose is the joint frame (``relative_to`` the joint), the axis is expressed in the joint
frame.  Fixed joints stay joints.  What SDF 1.9 cannot express is listed by :func:`losses`.
"""

from __future__ import annotations

from robotkit.emit.env import render
from robotkit.emit.urdf import geom_context
from robotkit.model.robot import Robot

SDF_VERSION = "1.9"
JOINT_TYPES = {"revolute": "revolute", "continuous": "continuous", "prismatic": "prismatic", "fixed": "fixed"}
SPECULAR = (0.1, 0.1, 0.1, 1.0)


def losses(robot: Robot) -> list[str]:
    out = []
    for j in robot.joints:
        if j.type == "floating" and j.parent == "world":
            out.append(f"joint '{j.name}': SDF has no floating joint; link '{j.child}' is a free body "
                       "placed at the joint's pose")
        elif j.type == "floating":
            out.append(f"joint '{j.name}': SDF has no floating joint; link '{j.child}' is a free body "
                       "placed at the joint's pose")
        elif j.type == "planar":
            out.append(f"joint '{j.name}': SDF has no planar joint; link '{j.child}' is a free body "
                       "placed at the joint's pose")
        if j.mimic is not None:
            out.append(f"joint '{j.name}': SDF {SDF_VERSION} cannot express mimic joints (SDF 1.11 can); "
                       f"it moves independently of '{j.mimic.joint}' in Gazebo")
        if j.dynamics is not None and j.dynamics.armature:
            out.append(f"joint '{j.name}': armature is not written (SDF has no such joint property)")
    return out


def context(robot: Robot) -> dict:
    materials = {m.name: m for m in robot.materials}
    parent_joint = {j.child: j for j in robot.joints}
    links = []
    for link in robot.links:
        j = parent_joint.get(link.name)
        frame = None
        if j is not None:
            frame = j.name if j.type in JOINT_TYPES else f"{j.name}_frame"
        links.append({
            "name": link.name,
            "frame": frame,
            "visuals": [dict(geom_context(robot, g), uri=_uri(robot, g),
                             material=materials.get(g.material)) for g in link.visuals],
            "collisions": [dict(geom_context(robot, g), uri=_uri(robot, g)) for g in link.collisions],
            "inertial": link.inertial,
            "contact": link.contact,
        })
    joints = [{"j": j, "type": JOINT_TYPES.get(j.type)} for j in robot.joints]
    return {"robot": robot, "version": SDF_VERSION, "links": links, "joints": joints, "specular": SPECULAR}


def _uri(robot: Robot, geom) -> str | None:
    if geom.shape.mesh is None:
        return None
    return f"model://{robot.name}/meshes/visual/{geom.shape.mesh.file_name}"


def render_sdf(robot: Robot) -> str:
    return render("sdf/model.sdf.j2", **context(robot))
