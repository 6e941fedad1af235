"""Robot -> MJCF (templates/mjcf/robot.xml.j2) and a scene that includes it (scene.xml.j2).

Body names are link names and joint names are joint names.  Each body's frame is its
link frame; inertials carry the full tensor (``fullinertia``); visual geoms neither collide
nor add mass; mesh assets carry their scale.  A root link named ``world`` becomes the
worldbody (its floating children get free joints); any other root is welded to the world.
What MJCF cannot express is listed by :func:`losses`.
"""

from __future__ import annotations

import math
import os

import numpy as np

from robotkit import mj
from robotkit.emit import layout
from robotkit.emit.controllers import joints_phrase
from robotkit.emit.env import render
from robotkit.geometry import rpy_quat
from robotkit.emit.formats import Format, Limit
from robotkit.errors import Problem, RecipeError
from robotkit.emit.meshfiles import collision_file, conversions, visual_file
from robotkit.emit.sdf import extras_losses
from robotkit.emit.sensors import losses as sensor_losses
from robotkit.emit.sensors import mjcf_context
from robotkit.model.robot import MJCF_MAX_DEPTH, Geom, Robot

WORLD = "world"
MJCF_MESH_EXT = (".stl", ".obj")
PYRAMID_MU = 1.0
"""Above this sliding friction the MJCF asks for MuJoCo's elliptic friction cone: the default
pyramidal cone softens the normal direction as the friction coefficient grows (Gazebo models
write mu 100000 for "never slips": pioneer2dx's wheels then sank 3.7 cm into the floor and it
tipped over by 10 degrees in 3 s; at mu 5, 5 degrees)."""


def mesh_file(mesh, role: str = "visual") -> str:
    """The mesh file MJCF reads, relative to the robot's meshes/ folder."""
    return collision_file(mesh) if role == "collision" else visual_file(mesh, "mjcf")


def losses(robot: Robot, facts: dict | None = None) -> list[str]:
    out = []
    for rel, (src, _) in conversions(robot).items():
        if not rel.startswith("mjcf/"):
            continue
        out.append(Limit(f"mesh '{os.path.basename(src)}': MuJoCo reads no {os.path.splitext(src)[1].upper()[1:]}; "
                   f"converted to {layout.MESHES}/{rel} (the file's own colours and textures are dropped, "
                   "the recipe's material is used)"))
    for j in robot.joints:
        if j.type == "planar":
            out.append(Limit(f"joint '{j.name}': MJCF has no planar joint; written as slides "
                             f"'{j.name}_x', '{j.name}_y' and hinge '{j.name}_rz'"))
        if j.type == "floating" and j.parent != WORLD:
            out.append(f"joint '{j.name}': MuJoCo allows free joints only on bodies of the world; "
                       f"link '{j.child}' is welded to '{j.parent}'")
    fast = [j for j in robot.joints if j.limit is not None and j.limit.velocity is not None and j.type != "fixed"]
    if fast:
        speeds = ", ".join(sorted({f"{j.limit.velocity:g}" for j in fast}, key=float))
        out.append(Limit(f"{joints_phrase([j.name for j in fast])}: MJCF has no velocity limit ({speeds} not enforced)"))
    for link in robot.links:
        c = link.contact
        if c is not None and (c.kp is not None or c.kd is not None):
            out.append(Limit(f"link '{link.name}': contact kp/kd are Gazebo (ODE) stiffness and damping; MuJoCo "
                             "keeps its own contact softness (solref is per unit mass there: copied, they bounce the "
                             "robot)"))
        if c is not None and c.mu2 is not None and c.mu1 is not None and c.mu2 != c.mu1:
            out.append(Limit(f"link '{link.name}': MuJoCo friction is isotropic; mu2 {c.mu2:g} dropped, mu1 "
                             f"{c.mu1:g} used"))
        for g in link.collisions_for("mjcf"):
            if g.shape.mesh is not None and facts is not None:
                f = facts.get(g.shape.mesh.key)
                if f is not None and not f.get("convex", True):
                    out.append(f"link '{link.name}': collision mesh '{g.shape.mesh.file_name}' is not convex; "
                               "MuJoCo collides with its convex hull")
    # urdf_extras are the URDF's and Gazebo's own vocabulary (<gazebo>, <transmission>), which
    # MuJoCo does not read: a limit of the format (report.json), not a warning
    return out + [Limit(x) for x in extras_losses(robot, "the MJCF")] + sensor_losses(robot)["mjcf"]


def loop_sites(robot: Robot, link: str) -> list[dict]:
    """The sites of the loops that close on ``link``: ``<loop>_1`` on link1, ``<loop>_2`` on link2."""
    return [{"name": f"{loop.name}_{k}", "frame": True, "pos": pose.xyz, "quat": rpy_quat(pose.rpy)}
            for loop in robot.loops for k, (end, pose) in enumerate(((loop.link1, loop.pose1), (loop.link2, loop.pose2)), 1)
            if end == link]


def loop_losses(robot: Robot, where: str) -> list[str]:
    """The recipe's loops, which a tree (``where``: the URDF, model.sdf) leaves open."""
    if not robot.loops:
        return []
    names = ", ".join(f"'{loop.name}'" for loop in robot.loops)
    return [Limit(f"loop{'s' * (len(robot.loops) != 1)} {names}: {where} is a tree and leaves "
                  f"{'them' if len(robot.loops) != 1 else 'it'} open (the MJCF closes "
                  f"{'them' if len(robot.loops) != 1 else 'it'} with an equality constraint)")]


def mjcf_extras_losses(robot: Robot, where: str) -> list[str]:
    """``mjcf_extras`` go into the MJCF only: what ``where`` (another format) does not get."""
    if not robot.mjcf_extras:
        return []
    parts = [f"<{tag}> ({len(sec['children'])} element{'s' * (len(sec['children']) != 1)})" if sec["children"]
             else f"<{tag}>" for tag, sec in extras_sections(robot).items()]
    return [Limit(f"mjcf_extras {', '.join(parts)} are in the MJCF only, not in {where}")]


def extras_sections(robot: Robot) -> dict[str, dict]:
    """The ``mjcf_extras`` by section: its children (XML text, two levels indented) and attributes."""
    import xml.etree.ElementTree as ET

    out: dict[str, dict] = {}
    for text in robot.mjcf_extras:
        element = ET.fromstring(text)
        section = out.setdefault(element.tag, {"attrs": {}, "children": []})
        section["attrs"].update(element.attrib)
        for child in element:
            child.tail = None
            ET.indent(child, "  ", level=2)
            section["children"].append(ET.tostring(child, encoding="unicode").replace(" />", "/>"))
    return out


def refusal(xml: str) -> str | None:
    """Why MuJoCo refuses the MJCF ``xml`` (None: it loads it), each mesh a tetrahedron in place
    of its file (the build checks the MJCF before its meshes are read)."""
    mujoco = mj.load()
    try:
        spec = mujoco.MjSpec.from_string(xml)
        for mesh in spec.meshes:
            mesh.file = ""
            mesh.uservert = [0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1]
        spec.compile()
    except ValueError as exc:
        return " ".join(str(exc).replace("Error: ", "", 1).split())
    return None


def _geom(robot: Robot, geom: Geom, name: str, assets: dict, role: str = "visual") -> dict:
    s = geom.shape
    pose = geom.pose
    ctx = {"name": name, "pos": pose.xyz, "quat": rpy_quat(pose.rpy), "type": s.kind,
           "material": geom.material}
    if s.kind == "mesh":
        key = (mesh_file(s.mesh, role), s.mesh.out_scale)
        ctx["mesh"] = assets[key]["name"]
    elif s.kind == "box":
        ctx["size"] = tuple(v / 2 for v in s.size)
    elif s.kind in ("cylinder", "capsule"):
        ctx["size"] = (s.radius, s.length / 2)
    else:
        ctx["size"] = (s.radius,)
    return ctx


def _assets(robot: Robot) -> dict:
    assets: dict = {}
    used_names: set[str] = set()
    geoms = [(g, role) for link in robot.links
             for role, gs in (("visual", link.visuals), ("collision", link.collisions_for("mjcf"))) for g in gs]
    for g, role in geoms:
            m = g.shape.mesh
            if m is None:
                continue
            key = (mesh_file(m, role), m.out_scale)
            if key in assets:
                continue
            base = os.path.splitext(os.path.basename(key[0]))[0] + ("_collision" if role == "collision" else "")
            name, n = base, 1
            while name in used_names:
                n += 1
                name = f"{base}_{n}"
            used_names.add(name)
            # a visual mesh is copied as it is (open, misoriented or flat, as modellers draw them) and its
            # geom carries no mass: its inertia as a thin shell, which MuJoCo computes for any surface
            # (as a solid it refuses the mesh: "mesh volume is too small")
            assets[key] = {"name": name, "file": key[0], "scale": key[1] if any(v != 1 for v in key[1]) else None,
                           "shell": role == "visual"}
    return assets


def _plane_axes(normal) -> tuple[tuple, tuple]:
    n = np.asarray(normal, dtype=float)
    helper = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    u = np.cross(n, helper)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    return tuple(u), tuple(v)


def joints_of(j, gravcomp: frozenset = frozenset()) -> list[dict]:
    """The MJCF joints of a URDF joint (none for a fixed one; three for a planar one);
    ``gravcomp``: the joints whose actuators carry gravity compensation."""
    if j.type in ("revolute", "continuous", "prismatic"):
        d = {"name": j.name, "type": "slide" if j.type == "prismatic" else "hinge", "axis": j.axis,
             "gravcomp": j.name in gravcomp}
        if j.type != "continuous":
            d["range"] = (j.limit.lower, j.limit.upper)
        if j.limit is not None and j.limit.effort:
            d["frcrange"] = j.limit.effort
        if j.dynamics is not None:
            d.update(damping=j.dynamics.damping, friction=j.dynamics.friction, armature=j.dynamics.armature)
        return [d]
    if j.type == "planar":
        u, v = _plane_axes(j.axis)
        return [{"name": f"{j.name}_x", "type": "slide", "axis": u},
                {"name": f"{j.name}_y", "type": "slide", "axis": v},
                {"name": f"{j.name}_rz", "type": "hinge", "axis": j.axis}]
    if j.type == "floating" and j.parent == WORLD:
        return [{"name": j.name, "type": "free"}]
    return []


def body(robot: Robot, link, joint, assets: dict, sens: dict, children: list[str],
         gravcomp: tuple[frozenset, frozenset] = (frozenset(), frozenset())) -> dict:
    """The context of one body: its place, joints, inertial, geoms, cameras and sites, and its
    ``children`` (link names); ``gravcomp``: (bodies whose weight is compensated, joints whose
    actuators carry it)."""
    name = link.name
    extras = sens["bodies"].get(name, {"cameras": [], "sites": []})
    for site in extras["sites"]:
        if site.get("touch"):
            site["size"], site["pos"] = _touch_volume(link)
    c = link.contact
    friction = c.mu1 if c is not None else None
    return {
        "name": name,
        "pos": joint.origin.xyz if joint is not None else (0.0, 0.0, 0.0),
        "quat": rpy_quat(joint.origin.rpy) if joint is not None else (1.0, 0.0, 0.0, 0.0),
        "joints": joints_of(joint, gravcomp[1]) if joint is not None else [],
        "gravcomp": name in gravcomp[0],
        "inertial": link.inertial,
        "visuals": [_geom(robot, g, f"{name}_visual_{i}", assets) for i, g in enumerate(link.visuals)],
        "collisions": [dict(_geom(robot, g, f"{name}_collision_{i}", assets, "collision"), friction=friction)
                       for i, g in enumerate(link.collisions_for("mjcf"))],
        "children": children,
        "cameras": extras["cameras"],
        "sites": extras["sites"],
    }


def frame_sites(links: dict, parent_joint: dict, children: list[str], sens: dict) -> list[dict]:
    """A site of each child link that is a frame (no mass, no shape, fixed to this one), of its
    name, at its pose, in this body: what an MJCF site was (robotkit.importer.mjcf.sites), in the
    body that carries it, so that tendons, sensors, actuators and constraints of ``mjcf_extras``
    name it and act on that body as they did on the site's.  None where a sensor's site has that
    name already."""
    if "site_names" not in sens:
        sens["site_names"] = {s["name"] for b in sens["bodies"].values() for s in b["sites"]}
    out = []
    for name in children:
        link, joint = links[name], parent_joint[name]
        if (link.inertial is None and not link.visuals and not link.collisions_for("mjcf") and joint.type == "fixed"
                and name not in sens["site_names"]):
            out.append({"name": name, "frame": True, "pos": joint.origin.xyz, "quat": rpy_quat(joint.origin.rpy)})
    return out


def body_tree(robot: Robot, lift: float, assets: dict, sens: dict) -> tuple[list[dict], list[dict]]:
    """(geoms of the worldbody, the body tree as opening and closing steps, depth first, without
    recursion: chains of 1000 links)."""
    links = {link.name: link for link in robot.links}
    children: dict[str, list[str]] = {}
    for j in robot.joints:
        children.setdefault(j.parent, []).append(j.child)
    parent_joint = {j.child: j for j in robot.joints}

    comp = gravcomp_sets(robot)

    def make(name: str, joint) -> dict:
        b = body(robot, links[name], joint, assets, sens, children.get(name, []), comp)
        b["sites"] = b["sites"] + frame_sites(links, parent_joint, b["children"], sens) + loop_sites(robot, name)
        return b

    root = robot.root
    if root == WORLD:
        world = make(root, None)
        world_geoms = world["visuals"] + world["collisions"] + [s for s in world["sites"] if s.get("frame")]
        tops = [make(name, parent_joint[name]) for name in world["children"]]
    else:
        world_geoms = []
        tops = [make(root, None)]
        tops[0]["pos"] = (0.0, 0.0, lift) if lift else tops[0]["pos"]
        if robot.base == "free":
            tops[0]["joints"] = [{"name": f"{root}_free", "type": "free"}]
    tree = []
    stack = [(b, 2) for b in reversed(tops)]
    while stack:
        b, depth = stack.pop()
        if b is None:
            tree.append({"body": None, "indent": "  " * depth})
            continue
        tree.append({"body": b, "indent": "  " * depth})
        stack.append((None, depth))
        stack.extend((make(c, parent_joint[c]), depth + 1) for c in reversed(b["children"]))
    return world_geoms, tree


def gravcomp_sets(robot: Robot) -> tuple[frozenset, frozenset]:
    """(the bodies below an actuated joint, the actuated joints) when the tuner asked for gravity
    compensation (:mod:`robotkit.model.gains`): each such body's weight is compensated
    (``gravcomp="1"``) and routed through the joints' actuators (``actuatorgravcomp``), so the
    compensation counts against their force limits as a feed-forward would."""
    actuated = {a.joint for a in robot.actuators if a.gravcomp}
    if not actuated:
        return frozenset(), frozenset()
    children: dict[str, list] = {}
    for j in robot.joints:
        children.setdefault(j.parent, []).append(j)
    bodies, stack = set(), [(robot.root, False)]
    while stack:
        name, below = stack.pop()
        if below:
            bodies.add(name)
        stack.extend((j.child, below or j.name in actuated) for j in children.get(name, []))
    return frozenset(bodies), frozenset(actuated)


def keyframes(robot: Robot, tree: list[dict], actuators: list[dict], lift_at) -> list[dict]:
    """One MJCF keyframe per named pose (``home`` first): qpos in the file's joint order (a free
    joint at the body's place, raised to stand at that pose: ``lift_at(values)``), ctrl at the pose."""
    poses = sorted(robot.poses, key=lambda p: p.name != "home") if robot.home() is not None else []
    mimics = {j.name: j.mimic for j in robot.joints if j.mimic is not None}
    out = []
    for pose in poses:
        values = dict(pose.values)
        for name, m in mimics.items():
            values[name] = m.multiplier * values.get(m.joint, 0.0) + m.offset
        qpos = []
        for step in tree:
            b = step["body"]
            for j in (b["joints"] if b else []):
                if j["type"] == "free":
                    pos = b["pos"][:2] + (lift_at(values),)
                    qpos.extend(pos + tuple(b["quat"]))
                else:
                    qpos.append(values.get(j["name"], 0.0))
        ctrl = [values.get(a["joint"], 0.0) if a["kind"] == "position" else 0.0 for a in actuators]
        out.append({"name": pose.name, "qpos": tuple(qpos), "ctrl": tuple(ctrl)})
    return out


def actuator_contexts(robot: Robot) -> list[dict]:
    """One MJCF actuator per recipe actuator: position and velocity servos, motors."""
    joint_by_name = {j.name: j for j in robot.joints}
    actuators = []
    for a in robot.actuators:
        j = joint_by_name[a.joint]
        effort = j.limit.effort if j.limit is not None and j.limit.effort else None
        act = {"name": f"{a.joint}_{a.interface}", "joint": a.joint, "effort": effort}
        if a.interface == "position":
            act.update(kind="position", kp=a.p, kv=a.d,
                       ctrlrange=(j.limit.lower, j.limit.upper) if j.type != "continuous" else None)
        elif a.interface == "velocity":
            act.update(kind="velocity", kv=a.p, ctrlrange=(-j.limit.velocity, j.limit.velocity)
                       if j.limit is not None and j.limit.velocity else None)
        else:
            act.update(kind="motor", ctrlrange=(-effort, effort))
        actuators.append(act)
    return actuators


def context(robot: Robot, lift: float = 0.0, lift_at=None) -> dict:
    """``lift``: height of the root body (a robot not rooted in ``world`` stands on the floor);
    ``lift_at(joint values)``: its height at a named pose (keyframes)."""
    assets = _assets(robot)
    sens = mjcf_context(robot)
    world_geoms, tree = body_tree(robot, lift, assets, sens)
    actuators = actuator_contexts(robot)
    equalities = [{"name": f"{j.name}_mimic", "joint1": j.name, "joint2": j.mimic.joint,
                   "polycoef": (j.mimic.offset, j.mimic.multiplier, 0.0, 0.0, 0.0)}
                  for j in robot.joints if j.mimic is not None]
    collide, excludes = self_contacts(robot)
    extras = extras_sections(robot)
    more = len(extras.get("actuator", {}).get("children", []))  # the extras' actuators: ctrl 0 at every keyframe
    keys = [dict(k, ctrl=k["ctrl"] + (0.0,) * more if k["ctrl"] else ())
            for k in keyframes(robot, tree, actuators, lift_at or (lambda values: lift))]
    return {"robot": robot, "collide": collide, "excludes": excludes, "sensors": sens["sensors"], "actuators": actuators, "keys": keys,
            "assets": sorted(assets.values(), key=lambda a: a["name"]),
            "materials": robot.materials, "world_geoms": world_geoms, "tree": tree,
            "equalities": equalities, "cone": "elliptic" if _high_friction(robot) else None,
            "extras": extras, "loops": robot.loops}


def _high_friction(robot: Robot) -> bool:
    return any(link.contact is not None and (link.contact.mu1 or 0.0) > PYRAMID_MU for link in robot.links)


def self_contacts(robot: Robot) -> tuple[bool, list[tuple[str, str]]]:
    """Whether the robot's geoms collide with each other, and the body pairs excluded: the
    self-collision matrix's disabled pairs (every one, adjacent ones included: MuJoCo's parent
    filter does not act on a body welded to the world), on unless the recipe says
    ``self_collide: false``; without a matrix, only on when asked, the joined pairs excluded."""
    m = robot.collision_matrix
    if robot.self_collide is False:
        return False, []
    if m is not None:
        return True, sorted((p.a, p.b) for p in m.disabled())
    return bool(robot.self_collide), [(j.parent, j.child) for j in robot.joints if j.parent != WORLD]


def _touch_volume(link) -> tuple[tuple[float, ...], tuple[float, float, float]]:
    """A box site around the link's collision primitives (or a 5 cm cube) for a touch sensor."""
    pts = []
    for g in link.collisions:
        s = g.shape
        half = (tuple(v / 2 for v in s.size) if s.kind == "box" else
                (s.radius, s.radius, s.length / 2) if s.kind == "cylinder" else
                (s.radius,) * 3 if s.kind == "sphere" else None)
        if half is None:
            continue
        T = g.pose.matrix()
        for corner in np.array(np.meshgrid(*[(-h, h) for h in half])).T.reshape(-1, 3):
            pts.append(T[:3, :3] @ corner + T[:3, 3])
    if not pts:
        return (0.025, 0.025, 0.025), (0.0, 0.0, 0.0)
    pts = np.array(pts)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    # slightly larger than the geometry, so contacts on its surface fall inside
    return tuple(float(v) for v in (hi - lo) / 2 * 1.05 + 0.002), tuple(float(v) for v in (hi + lo) / 2)


def joint_motion(j, value: float) -> np.ndarray:
    """The child frame's motion in the joint frame at joint value ``value``."""
    T = np.eye(4)
    if not value or j.type not in ("revolute", "continuous", "prismatic"):
        return T
    axis = np.asarray(j.axis, dtype=float)
    if j.type == "prismatic":
        T[:3, 3] = axis * value
        return T
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    T[:3, :3] = np.eye(3) + math.sin(value) * K + (1 - math.cos(value)) * K @ K  # Rodrigues
    return T


def zero_pose_frames(robot: Robot, values: dict[str, float] | None = None) -> dict[str, np.ndarray]:
    """Every link frame in the root frame with the joints at ``values`` (default all zero; no recursion)."""
    values = values or {}
    frames = {robot.root: np.eye(4)}
    pending = list(robot.joints)
    while pending:
        rest = [j for j in pending if j.parent not in frames]
        for j in pending:
            if j.parent in frames:
                frames[j.child] = frames[j.parent] @ j.origin.matrix() @ joint_motion(j, values.get(j.name, 0.0))
        if len(rest) == len(pending):
            break
        pending = rest
    return frames


def collision_meshes(robot: Robot) -> list[str]:
    """The mesh files (below ``meshes/``) of the MJCF's collision geometry: the build reads their
    vertices for :func:`render_mjcf` (keyword ``points``)."""
    return sorted({mesh_file(g.shape.mesh, "collision") for link in robot.links
                   for g in link.collisions_for("mjcf") if g.shape.kind == "mesh"})


def lowest_point(robot: Robot, points: dict[str, np.ndarray] | None,
                 values: dict[str, float] | None = None) -> float | None:
    """Lowest z of the robot's MJCF collision geometry at its zero pose (or with the joints at
    ``values``), in the root frame (mesh geoms: the vertices of their files in ``points``, as
    MuJoCo collides with their convex hulls; none without ``points``); None without any."""
    frames = zero_pose_frames(robot, values)
    lows = []
    for link in robot.links:
        for g in link.collisions_for("mjcf"):
            T = frames[link.name] @ g.pose.matrix()
            R, c = T[:3, :3], T[:3, 3]
            s = g.shape
            if s.kind == "sphere":
                lows.append(c[2] - s.radius)
            elif s.kind in ("cylinder", "capsule"):
                axis = R[:, 2] * s.length / 2
                if s.kind == "capsule":
                    lows.append(c[2] - abs(axis[2]) - s.radius)
                else:
                    lows.append(c[2] - abs(axis[2]) - s.radius * math.sqrt(max(0.0, 1 - R[2, 2] ** 2)))
            elif s.kind == "box":
                lows.append(c[2] - float(np.abs(R[2, :]) @ (np.asarray(s.size) / 2)))
            elif s.kind == "mesh" and points is not None:
                v = points[mesh_file(s.mesh, "collision")] * np.asarray(s.mesh.out_scale)
                lows.append(float((v @ R[2, :]).min() + c[2]))
    return min(lows) if lows else None


def render_mjcf(robot: Robot, points: dict[str, np.ndarray] | None = None) -> str:
    """The robot's MJCF.  A robot not rooted in ``world`` stands on the floor at its zero pose:
    its root body is raised (or lowered) so that its lowest collision point is at z = 0
    (``points``: the vertices of :func:`collision_meshes`; without them, mesh geoms are left out)."""
    def lift_at(values: dict[str, float] | None = None) -> float:
        if robot.root == WORLD:
            return 0.0
        low = lowest_point(robot, points, values)
        # up to the next micrometre: never inside the floor, and no float32 noise in the file
        return math.ceil(-low * 1e6) / 1e6 if low is not None else 0.0

    xml = render("mjcf/robot.xml.j2", **context(robot, lift=lift_at(), lift_at=lift_at))
    why = refusal(xml) if robot.mjcf_extras else None
    if why is not None:
        raise RecipeError(Problem(f"MuJoCo refuses the MJCF with these elements: {why}", key="mjcf_extras"))
    return xml


def floor_height(robot: Robot, points: dict[str, np.ndarray] | None = None) -> float:
    """z of the scene's floor: 0, or for a robot fixed to the world that reaches below z = 0 at its
    zero pose (Valkyrie's forearm, hung from the world at its elbow) its lowest collision point,
    down to the micrometre: the robot stays where its description puts it, the floor makes room."""
    if robot.root != WORLD:
        return 0.0  # a free robot is raised onto the floor instead (render_mjcf)
    low = lowest_point(robot, points)
    return math.floor(low * 1e6) / 1e6 if low is not None and low < 0 else 0.0


def render_scene(robot: Robot, points: dict[str, np.ndarray] | None = None) -> str:
    return render("mjcf/scene.xml.j2", robot=robot, floor=floor_height(robot, points))


def too_deep(robot: Robot) -> str | None:
    """Why MuJoCo cannot load the robot's MJCF whatever the recipe says (a body per link,
    nested): a chain deeper than its XML reader goes.  None when it can."""
    depth, deepest = robot.depth()
    if depth <= MJCF_MAX_DEPTH:
        return None
    return (f"link '{deepest}' sits {depth} links deep and MuJoCo's XML reader stops at {MJCF_MAX_DEPTH} "
            "nested bodies (a body per link)")


FORMATS = [
    Format("mjcf", render_mjcf, layout.MJCF, ("mjcf/robot.xml.j2",), consumed=True, points=collision_meshes,
           limit=too_deep),
    Format("mjcf-scene", render_scene, layout.SCENE, ("mjcf/scene.xml.j2",), needs=("mjcf",),
           points=collision_meshes),
]
