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
    from robotkit.emit.sensors import losses as sensor_losses

    out = []
    frames = robot.frame_links()
    children = {j.child for j in robot.joints}
    for link in robot.links:
        if (link.name not in frames and link.name != "world" and link.inertial is None
                and (link.name in children or len(robot.links) > 1)):
            out.append(f"link '{link.name}' has no inertial; Gazebo gives such a link a mass of 1 kg")
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
    return out + sensor_losses(robot)["sdf"]


def context(robot: Robot) -> dict:
    from robotkit.emit.sensors import contexts

    materials = {m.name: m for m in robot.materials}
    parent_joint = {j.child: j for j in robot.joints}
    frames = robot.frame_links()
    sensors = contexts(robot)
    links = []
    for link in robot.links:
        if link.name in frames or link.name == "world":
            continue
        j = parent_joint.get(link.name)
        ctx_pose = None  # (relative_to, pose)
        if j is not None:
            if j.type in JOINT_TYPES:
                ctx_pose = (j.name, None)
            else:  # no SDF joint: a free body placed at the joint's pose
                ctx_pose = ("__model__" if j.parent == "world" else j.parent, j.origin)
        links.append({
            "name": link.name,
            "pose": ctx_pose,
            "sensors": [s for s in sensors if s["host"] == link.name],
            "visuals": [dict(geom_context(robot, g), uri=_uri(robot, g),
                             material=materials.get(g.material)) for g in link.visuals],
            "collisions": [dict(geom_context(robot, g), uri=_uri(robot, g)) for g in link.collisions_for("sdf")],
            "inertial": link.inertial,
            "contact": link.contact,
        })
    joints = [{"j": j, "type": JOINT_TYPES.get(j.type)} for j in robot.joints
              if j.child not in frames and j.type in JOINT_TYPES]
    frame_list = [j for j in robot.joints if j.child in frames]
    return {"robot": robot, "version": SDF_VERSION, "links": links, "joints": joints, "frames": frame_list,
            "specular": SPECULAR}


def _uri(robot: Robot, geom) -> str | None:
    if geom.shape.mesh is None:
        return None
    return f"model://{robot.name}/meshes/{geom.shape.mesh.path}"


def render_sdf(robot: Robot) -> str:
    return render("sdf/model.sdf.j2", **context(robot))
