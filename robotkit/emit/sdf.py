"""Robot -> SDF 1.9 model (templates/sdf/model.sdf.j2), the newest version Debian's libsdformat 12 validates.

Frames mirror URDF exactly: a joint's pose is relative to its parent link, a child link's
pose is the joint frame (``relative_to`` the joint), the axis is expressed in the joint
frame.  Fixed joints stay joints.  Massless links are ``<frame>``s where they can be (an SDF
link without an inertial weighs 1 kg in Gazebo and Drake): a massless link fixed to another is
a frame attached to it and its geometry and sensors move into the link that carries it; a
massless root with a fixed child is a frame on that child.  A massless link that must stay a
link (welded to the world, or moved by a joint) gets the URDF's explicit massless inertial.  Joints named like a link are
renamed (:func:`joint_names`).  The recipe's verbatim ``<gazebo>`` blocks (``urdf_extras``) are
carried as libsdformat's URDF conversion carries them (:func:`robotkit.emit.gazebo.carry`).
What SDF 1.9 cannot express is listed by :func:`losses`.
"""

from __future__ import annotations

from dataclasses import replace

from robotkit.emit import layout
from robotkit.emit.env import fmt, render
from robotkit.emit.formats import Format, Limit
from robotkit.emit.gazebo import carry
from robotkit.emit.meshfiles import collision_file
from robotkit.emit.urdf import MASSLESS, geom_context
from robotkit.emit.sensors import contexts, host_of
from robotkit.emit.controllers import armature_losses, gravcomp_losses
from robotkit.emit.sensors import losses as sensor_losses
from robotkit.geometry import matrix_rpy
from robotkit.model.selfcollision import solve_masks
from robotkit.model.robot import Inertial, Pose, Robot

SDF_VERSION = "1.9"
JOINT_TYPES = {"revolute": "revolute", "continuous": "continuous", "prismatic": "prismatic", "fixed": "fixed"}
SPECULAR = (0.1, 0.1, 0.1, 1.0)


def losses(robot: Robot) -> list[str]:
    out = []
    names = joint_names(robot)
    for j in robot.joints:
        if names[j.name] != j.name:
            out.append(f"joint '{j.name}' is named '{names[j.name]}' in model.sdf: SDF needs link, joint "
                       "and frame names unique within a model")
        if j.type == "floating" and j.parent == "world":  # the same free body
            out.append(Limit(f"joint '{j.name}': SDF has no floating joint; link '{j.child}' is a free body "
                             "placed at the joint's pose"))
        elif j.type == "floating":
            out.append(f"joint '{j.name}': SDF has no floating joint; link '{j.child}' is a free body "
                       "placed at the joint's pose")
        elif j.type == "planar":
            out.append(f"joint '{j.name}': SDF has no planar joint; link '{j.child}' is a free body "
                       "placed at the joint's pose")
        if j.mimic is not None:
            out.append(f"joint '{j.name}': SDF {SDF_VERSION} cannot express mimic joints (SDF 1.11 can); "
                       f"it moves independently of '{j.mimic.joint}' in Gazebo")
    out += armature_losses(robot, "SDF")
    out += self_collide(robot)[2]
    out += carry(robot).losses
    out += gravcomp_losses(robot, "model.sdf's joint controllers (Gazebo Sim)")
    return out + sensor_losses(robot)["sdf"]


def self_collide(robot: Robot) -> tuple[bool, dict[str, int], list[str]]:
    """Gazebo's ``self_collide``, each link's ``collide_bitmask`` and the loss: the self-collision
    matrix expressed by bit masks (two collisions touch when their masks share a bit; Gazebo itself
    skips links joined by a joint and the geometry of one link) when 16 bits can, exactly."""
    m = robot.collision_matrix
    if robot.self_collide is False or m is None:
        return bool(robot.self_collide), {}, []
    carrier = {name: host_of(robot, name)[0] for name in robot.frame_links()}
    sdf_link = {link.name: carrier.get(link.name, link.name) for link in robot.links}
    joined = {frozenset((sdf_link[j.parent], sdf_link[j.child])) for j in robot.joints if j.type in JOINT_TYPES}
    nodes = sorted({n for p in m.pairs for n in (p.a, p.b)} - {"world"})
    free = {frozenset((p.a, p.b)) for p in m.pairs if sdf_link[p.a] == sdf_link[p.b]
            or frozenset((sdf_link[p.a], sdf_link[p.b])) in joined}
    enabled = {frozenset((p.a, p.b)) for p in m.pairs if not p.disabled and "world" not in (p.a, p.b)}
    masks = solve_masks(nodes, enabled, free) if not enabled & free else None
    if masks is not None:
        return True, masks, []
    # Never pairs never come within 1 cm: letting them share a bit costs Gazebo time, not behaviour
    never = {frozenset((p.a, p.b)) for p in m.pairs if p.reason == "Never"}
    masks = solve_masks(nodes, enabled, free | never) if not enabled & free else None
    if masks is not None:
        shared = sorted(f"{p.a}-{p.b}" for p in m.pairs if p.reason == "Never" and frozenset((p.a, p.b)) not in free
                        and masks[p.a] & masks[p.b])
        return True, masks, [f"model.sdf's collide bit masks also check {len(shared)} pairs the matrix calls Never "
                             f"(16 masks cannot separate them; they never come within 1 cm): {_few(shared)}"]
    fight = sorted(f"{p.a}-{p.b}" for p in m.disabled() if p.reason in ("Default", "Always", "User")
                   and frozenset((p.a, p.b)) not in free)
    why = ("16 collide bit masks cannot express the self-collision matrix" if not enabled & free else
           "the matrix checks links Gazebo never collides (joined by a joint)")
    pairs = f" (Gazebo would make these disabled pairs fight: {_few(fight)})" if fight else ""
    if robot.self_collide:
        return True, {}, [f"self_collide: {why}; on with Gazebo's own filter{pairs}"]
    return False, {}, [f"self-collision is off in model.sdf: {why}{pairs}"]


def _few(pairs: list[str], most: int = 5) -> str:
    """At most ``most`` pairs named, then how many more (report.json: self_collision has them all)."""
    more = f" and {len(pairs) - most} more (report.json: self_collision)" if len(pairs) > most else ""
    return ", ".join(pairs[:most]) + more


def extras_losses(robot: Robot, where: str) -> list[str]:
    """``urdf_extras`` go into the URDF only: say what another format does not get."""
    import re

    if not robot.urdf_extras:
        return []
    heads = [re.match(r"\s*(<[^>]*>)", x).group(1) if re.match(r"\s*(<[^>]*>)", x) else x[:40]
             for x in robot.urdf_extras]
    sensors = sum("<sensor" in x for x in robot.urdf_extras)
    what = f" ({sensors} sensor{'s' * (sensors != 1)} among them)" if sensors else ""
    return [f"{len(heads)} urdf_extras element{'s' * (len(heads) != 1)}{what} are in the URDF only, not in "
            f"{where}: {', '.join(heads[:5])}{', ...' if len(heads) > 5 else ''}"]


def joint_names(robot: Robot) -> dict[str, str]:
    """SDF name of each joint: links, joints and frames share one namespace in an SDF model,
    so a joint named like a link (ANYmal's ``LF_HAA``) gets ``_joint`` appended (then a number)."""
    return names_apart([link.name for link in robot.links], [j.name for j in robot.joints])


def names_apart(links, joints) -> dict[str, str]:
    """:func:`joint_names` on bare names (the import reports the renaming with them)."""
    taken = set(links)
    out = {}
    for joint in joints:
        name, n = joint, 1
        while name in taken:
            name = f"{joint}_joint" + (str(n) if n > 1 else "")
            n += 1
        taken.add(name)
        out[joint] = name
    return out


def _moved(geom, pose):
    """``geom`` of a frame link, re-posed into the link that carries it."""
    T = pose.matrix() @ geom.pose.matrix()
    return replace(geom, origin=Pose(tuple(float(v) for v in T[:3, 3]), matrix_rpy(T[:3, :3])),
                   offset=(0.0, 0.0, 0.0))


def context(robot: Robot) -> dict:
    materials = {m.name: m for m in robot.materials}
    parent_joint = {j.child: j for j in robot.joints}
    frames = robot.frame_links()
    anchor = robot.anchor() if robot.root in frames else None
    names = joint_names(robot)
    sensors = contexts(robot)
    carried: dict[str, list] = {}  # link -> frame links whose geometry it carries, with their pose in it
    for name in sorted(frames):
        host, pose = host_of(robot, name)
        carried.setdefault(host, []).append((robot.link(name), pose))
    collide, masks, _ = self_collide(robot)
    gz = carry(robot, markup=True)
    links = []
    for link in robot.links:
        if link.name in frames or link.name == "world":
            continue
        j = parent_joint.get(link.name)
        ctx_pose = None  # (relative_to, pose)
        if link.name == anchor:  # the massless root is a frame on this link: the model frame
            ctx_pose = ("__model__", robot.anchor_pose())
        elif j is not None:
            if j.type in JOINT_TYPES:
                ctx_pose = (names[j.name], None)
            else:  # no SDF joint: a free body placed at the joint's pose
                ctx_pose = ("__model__" if j.parent == "world" else j.parent, j.origin)
        visuals = [(g, link.name) for g in link.visuals] + [
            (_moved(g, pose), f.name) for f, pose in carried.get(link.name, []) for g in f.visuals]
        collisions = [(g, link.name) for g in link.collisions_for("sdf")] + [
            (_moved(g, pose), f.name) for f, pose in carried.get(link.name, []) for g in f.collisions_for("sdf")]
        links.append({
            "name": link.name,
            "pose": ctx_pose,
            "sensors": [s for s in sensors if s["host"] == link.name],
            "visuals": [dict(geom_context(robot, g), uri=_uri(robot, g),
                             material=_material(materials.get(g.material), gz.materials.get(owner)))
                        for g, owner in visuals],
            "collisions": [dict(geom_context(robot, g, "collision"), uri=_uri(robot, g, "collision"),
                                surface=_surface(robot.link(owner).contact, gz.surfaces.get(owner, {}),
                                                 masks.get(owner)),
                                extras=gz.collision.get(owner, [])) for g, owner in collisions],
            "extras": gz.links.get(link.name, []),
            # a massless link SDF must keep a link (welded to the world, or moved by a joint): the
            # URDF emitter's explicit massless inertial, else Gazebo and Drake give it 1 kg
            "inertial": link.inertial if link.inertial is not None else Inertial(MASSLESS, (0.0, 0.0, 0.0),
                                                                                   (0.0,) * 6),
        })
    joints = [{"j": j, "name": names[j.name], "type": JOINT_TYPES.get(j.type), "extras": gz.joints.get(j.name, [])}
              for j in robot.joints if j.child not in frames and j.type in JOINT_TYPES and j.child != anchor]
    frame_list = [{"name": j.child, "attached_to": j.parent, "origin": j.origin}
                  for j in robot.joints if j.child in frames]
    if anchor is not None:
        frame_list.insert(0, {"name": robot.root, "attached_to": anchor, "origin": None})
    return {"robot": robot, "self_collide": collide, "version": SDF_VERSION, "links": links, "joints": joints, "frames": frame_list,
            "specular": SPECULAR, "controllers": controller_contexts(robot, names), "extras": gz.model}


def _material(material, script: str | None) -> dict | None:
    """A visual's material: the recipe's, its Gazebo script replaced by a <gazebo> block's
    <material> for the visual's link (libsdformat does the same; a script alone when the
    recipe gives no colour)."""
    if material is None and script is None:
        return None
    return {"rgba": material.rgba if material is not None else None,
            "gazebo": script or (material.gazebo if material is not None else None)}


def _surface(contact, carried: dict[str, str], bitmask: int | None) -> dict | None:
    """A collision's <surface>: friction (SDF's ODE names) and contact values, the recipe's
    ``contact`` then the <gazebo> blocks' (text as written, later ones win), and the collide
    bit mask."""
    own = {}
    if contact is not None:
        if contact.mu1 is not None:
            own |= {"mu": fmt(contact.mu1), "mu2": fmt(contact.mu2)}
        own |= {k: fmt(v) for k, v in (("kp", contact.kp), ("kd", contact.kd)) if v is not None}
    values = own | carried
    friction = [(k, values[k]) for k in ("mu", "mu2", "fdir1") if k in values]
    ode = [(k, values[k]) for k in ("kp", "kd", "max_vel", "min_depth") if k in values]
    if not friction and not ode and bitmask is None and contact is None:
        return None
    return {"friction": friction, "ode": ode, "bitmask": bitmask}


CONTROLLER_SYSTEMS = {
    "position": ("gz-sim-joint-position-controller-system", "gz::sim::systems::JointPositionController"),
    "velocity": ("gz-sim-joint-controller-system", "gz::sim::systems::JointController"),
    "effort": ("gz-sim-apply-joint-force-system", "gz::sim::systems::ApplyJointForce"),
}


def controller_contexts(robot: Robot, names: dict[str, str]) -> list[dict]:
    """Gazebo Sim's joint controller systems for the actuators, with the same gains as the MJCF
    and controllers.yaml (Gazebo Sim only: Gazebo classic knows none of them)."""
    if robot.gazebo != "sim":
        return []
    joints = {j.name: j for j in robot.joints}
    home = dict(robot.home().values) if robot.home() is not None else {}
    out = []
    for a in robot.actuators:
        lim = joints[a.joint].limit
        effort = lim.effort if lim is not None and lim.effort else None
        filename, name = CONTROLLER_SYSTEMS[a.interface]
        out.append({"filename": filename, "name": name, "joint": names.get(a.joint, a.joint),
                    "interface": a.interface, "p": a.p, "i": a.i, "d": a.d, "effort": effort,
                    "initial": home.get(a.joint, 0.0)})
    return out


def _uri(robot: Robot, geom, role: str = "visual") -> str | None:
    if geom.shape.mesh is None:
        return None
    path = collision_file(geom.shape.mesh) if role == "collision" else geom.shape.mesh.path
    return f"model://{robot.name}/{layout.MESHES}/{path}"


def render_sdf(robot: Robot) -> str:
    return render("sdf/model.sdf.j2", **context(robot))


FORMATS = [Format("sdf", render_sdf, layout.SDF, ("sdf/model.sdf.j2", "sensors/sdf.j2"), consumed=True)]
