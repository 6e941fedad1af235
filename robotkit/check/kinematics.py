"""A neutral kinematic and inertial view of a robot, read back from each output format by
a parser that is not robotkit's emitter, and compared.

- URDF: MuJoCo's own URDF compiler (plus the XML for what MuJoCo ignores: velocity limits);
- MJCF: MuJoCo;
- SDF: an SDF frame-graph reader here (``relative_to``, ``attached_to``, ``expressed_in``),
  applied both to our model.sdf and to libsdformat's conversion of our URDF (`ign sdf -p`).

:func:`compare` reports every difference in links, joints, masses, centres of mass,
inertia tensors (link axes), limits, damping, friction, and link poses relative to the
root at random joint configurations.  MuJoCo (heavy) is imported by the readers that use it.
"""

from __future__ import annotations

import copy
import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import numpy as np

from robotkit import mj, urdfxml
from robotkit.check import programs

WORLD = "world"
NEGLIGIBLE = 1e-200  # kg: robotkit's URDF writes massless links as 1e-300 kg (see emit/urdf.py)
# libsdformat turns a pose's rpy into a quaternion and prints it back as rpy (`ign sdf -p`): at a
# pitch of +-pi/2 the asin loses half the digits (measured: 1.570796325 comes back 1.570796311893735,
# 1.5e-8 in the rotation matrix, 2e-9 m at 0.15 m), so a reading through libsdformat holds poses
# to sqrt(eps)
LIBSDFORMAT_PRECISION = 1e-7


def real_mass(m: float) -> float:
    """The mass, 0 for one below NEGLIGIBLE (robotkit's URDF marks a massless link with 1e-300 kg)."""
    return 0.0 if abs(m) < NEGLIGIBLE else m


@dataclass
class KLink:
    name: str
    mass: float = 0.0
    com: np.ndarray = field(default_factory=lambda: np.zeros(3))
    inertia: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))


@dataclass
class KJoint:
    name: str
    type: str  # revolute | continuous | prismatic | fixed | floating | planar
    parent: str
    child: str
    T_pj: np.ndarray  # parent link frame -> joint frame at q = 0
    T_jc: np.ndarray  # joint frame -> child link frame
    axis: np.ndarray  # in the joint frame
    lower: float | None = None
    upper: float | None = None
    effort: float | None = None
    velocity: float | None = None
    damping: float | None = None
    friction: float | None = None
    mimic: tuple[str, float, float] | None = None  # leader, multiplier, offset


@dataclass
class KModel:
    source: str
    links: dict[str, KLink]
    joints: dict[str, KJoint]  # by name; fixed joints may be unnamed in some readers
    kept: frozenset[str] = frozenset()  # fixed joints libsdformat keeps (<preserveFixedJoint>)

    def parent_of(self) -> dict[str, KJoint]:
        return {j.child: j for j in self.joints.values()}

    def root(self) -> str:
        children = {j.child for j in self.joints.values() if j.parent in self.links}
        roots = [n for n in self.links if n not in children]
        return roots[0]

    def fk(self, q: dict[str, float]) -> dict[str, np.ndarray]:
        """Every link frame in the model frame at joint values ``q`` (missing ones are 0);
        iterative, so chains of any length work."""
        parent_of = self.parent_of()
        out: dict[str, np.ndarray] = {}
        for name in self.links:
            chain = []
            link = name
            while link not in out:  # walk up to a link already placed (or the root)
                j = parent_of.get(link)
                if j is None:
                    out[link] = np.eye(4)
                    break
                chain.append(j)
                link = j.parent
            for j in reversed(chain):
                value = q.get(j.name, 0.0)
                if j.mimic is not None:
                    value = j.mimic[1] * q.get(j.mimic[0], 0.0) + j.mimic[2]
                M = np.eye(4)
                if j.type in ("revolute", "continuous"):
                    M[:3, :3] = axis_angle(j.axis, value)
                elif j.type == "prismatic":
                    M[:3, 3] = j.axis * value
                out[j.child] = out.get(j.parent, np.eye(4)) @ j.T_pj @ M @ j.T_jc
        return out


def axis_angle(axis, angle) -> np.ndarray:
    x, y, z = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    c, s = math.cos(angle), math.sin(angle)
    C = 1 - c
    return np.array([[c + x * x * C, x * y * C - z * s, x * z * C + y * s],
                     [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
                     [z * x * C - y * s, z * y * C + x * s, c + z * z * C]])


# rpy_matrix and _quat_R are kept here on purpose, not taken from robotkit.geometry: an independent oracle.
def rpy_matrix(r, p, y) -> np.ndarray:
    return axis_angle((0, 0, 1), y) @ axis_angle((0, 1, 0), p) @ axis_angle((1, 0, 0), r)


def _T(xyz, R) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = xyz
    return T


def _quat_R(q) -> np.ndarray:
    w, x, y, z = (float(v) for v in q)
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


# ---------------------------------------------------------------- MuJoCo (MJCF and URDF)


def from_mujoco(model, source: str) -> KModel:
    mujoco = mj.load()  # rendering off where MUJOCO_GL cannot work: reading needs no GL

    links: dict[str, KLink] = {}
    joints: dict[str, KJoint] = {}
    names = {b: mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(model.nbody)}
    # the first body is the root, at the origin; where several bodies are welded to the world
    # (two arms on one table: ALOHA), each sits where it is in the world
    welded = [b for b in range(1, model.nbody) if model.body_parentid[b] == 0 and not model.body_jntnum[b]]
    for b in range(1, model.nbody):
        name = names[b]
        R = _quat_R(model.body_iquat[b])
        links[name] = KLink(name, float(model.body_mass[b]), np.array(model.body_ipos[b], dtype=float),
                            R @ np.diag(model.body_inertia[b]) @ R.T)
        parent = names[int(model.body_parentid[b])]
        T_pb = _T(model.body_pos[b], _quat_R(model.body_quat[b]))
        jids = [j for j in range(model.njnt) if model.jnt_bodyid[j] == b]
        if not jids:
            if parent != WORLD or b != 1 or len(welded) > 1:
                joints[f"(fixed {name})"] = KJoint(f"(fixed {name})", "fixed", parent, name, T_pb, np.eye(4),
                                                   np.array([1.0, 0, 0]))
            continue
        j = jids[0]
        jname = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)
        jtype = int(model.jnt_type[j])
        dof = int(model.jnt_dofadr[j])
        if jtype == mujoco.mjtJoint.mjJNT_FREE:
            joints[jname] = KJoint(jname, "floating", parent, name, T_pb, np.eye(4), np.array([1.0, 0, 0]))
            continue
        kind = "prismatic" if jtype == mujoco.mjtJoint.mjJNT_SLIDE else "revolute"
        limited = bool(model.jnt_limited[j])
        if kind == "revolute" and not limited:
            kind = "continuous"
        lower, upper = (float(model.jnt_range[j][0]), float(model.jnt_range[j][1])) if limited else (None, None)
        effort = None
        if model.jnt_actfrclimited[j]:
            effort = float(model.jnt_actfrcrange[j][1])
        T_jc = np.eye(4)
        T_jc[:3, 3] = -np.asarray(model.jnt_pos[j])
        T_pj = T_pb.copy()
        T_pj[:3, 3] = T_pb[:3, 3] + T_pb[:3, :3] @ np.asarray(model.jnt_pos[j])
        joints[jname] = KJoint(jname, kind, parent, name, T_pj, T_jc, np.array(model.jnt_axis[j], dtype=float),
                               lower, upper, effort, None, float(model.dof_damping[dof]),
                               float(model.dof_frictionloss[dof]))
    for e in range(model.neq):
        if model.eq_type[e] == mujoco.mjtEq.mjEQ_JOINT:
            j1 = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, int(model.eq_obj1id[e]))
            j2 = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, int(model.eq_obj2id[e]))
            data = model.eq_data[e]
            joints[j1].mimic = (j2, float(data[1]), float(data[0]))
    return KModel(source, links, joints)


def read_mjcf(path) -> KModel:
    mujoco = mj.load()  # rendering off where MUJOCO_GL cannot work: reading needs no GL

    return from_mujoco(mujoco.MjModel.from_xml_path(str(path)), f"MJCF {path}")


def read_urdf(path) -> KModel:
    """Our URDF through MuJoCo's URDF compiler (fixed joints kept), plus velocity limits
    and names from the XML, which MuJoCo ignores."""
    mujoco = mj.load()  # rendering off where MUJOCO_GL cannot work: reading needs no GL

    text = open(path, encoding="utf-8").read()
    # geometry plays no part in the comparison; meshes (DAE among them) need not load
    text = re.sub(r"<mesh\b[^>]*/>", '<sphere radius="0.001"/>', text)
    extension = ('<mujoco><compiler fusestatic="false" discardvisual="false" balanceinertia="false" '
                 'inertiafromgeom="false"/></mujoco>')
    text = re.sub(r"(<robot[^>]*>)", r"\1" + extension, text, count=1)
    model = from_mujoco(mujoco.MjModel.from_xml_string(text), f"URDF {path} (MuJoCo)")
    root = urdfxml.parse_text(text).getroot()
    for j in root.iter("joint"):
        name = j.get("name")
        limit = j.find("limit")
        if name in model.joints and limit is not None and limit.get("velocity") is not None:
            model.joints[name].velocity = float(limit.get("velocity"))
        if name in model.joints and limit is not None and limit.get("effort") is not None:
            model.joints[name].effort = float(limit.get("effort"))
    # name fixed joints as the URDF does
    fixed = {j.find("child").get("link"): j.get("name") for j in root.iter("joint") if j.get("type") == "fixed"}
    for key in [k for k, v in model.joints.items() if v.type == "fixed"]:
        j = model.joints.pop(key)
        j.name = fixed.get(j.child, key)
        model.joints[j.name] = j
    model.kept = kept_fixed(root)
    return model


def kept_fixed(root) -> frozenset[str]:
    """The joints a URDF (its parsed root element) asks libsdformat not to lump."""
    return frozenset(g.get("reference") for g in root.iter("gazebo") if g.get("reference") and
                     (g.findtext("preserveFixedJoint") or "").strip() in ("true", "1"))


def extension_parts(path) -> tuple[set[str], set[str]]:
    """Names of the links and joints a URDF's model-level <gazebo> blocks add to what Gazebo
    simulates (the PR2's parallel-gripper linkage): not the robot's description."""
    blocks = [g for g in urdfxml.parse_file(path).getroot().iter("gazebo") if not g.get("reference")]
    return ({el.get("name") for g in blocks for el in g.iter("link")},
            {el.get("name") for g in blocks for el in g.iter("joint")})


# ---------------------------------------------------------------- SDF


def _pose(el) -> tuple[np.ndarray, str | None]:
    p = el.find("pose") if el is not None else None
    if p is None:
        return np.eye(4), None
    v = [float(x) for x in (p.text or "0 0 0 0 0 0").split()]
    return _T(v[:3], rpy_matrix(*v[3:6])), p.get("relative_to")


def read_sdf_text(text: str, source: str, leave_out: tuple[set[str], set[str]] = (set(), set())) -> KModel:
    """An SDF model (our model.sdf, or libsdformat's printout of a URDF) as a KModel: its links
    with SDF's inertial defaults, its frames as massless links fixed where they are attached,
    and its joints between link frames resolved through the pose graph; ``leave_out``: links and
    joints not read (:func:`extension_parts`)."""
    # libsdformat prints namespaced elements (<ignition::corrected_offsets>, the PR2's Gazebo 1
    # <sensor:contact>) without their namespace declaration, which no XML parser accepts
    model = ET.fromstring(re.sub(r"(</?|\s)(\w+)::?(?=\w)", r"\1\2__", text)).find("model")
    link_els = {lk.get("name"): lk for lk in model.findall("link")}
    joint_els = {j.get("name"): j for j in model.findall("joint")}
    world = _frame_graph(link_els, joint_els, model.findall("frame"), source)
    links = {name: _sdf_link(name, lk) for name, lk in link_els.items() if name not in leave_out[0]}
    joints = {}
    for f in model.findall("frame"):  # a frame is a massless link fixed where it is attached
        links[f.get("name")] = KLink(f.get("name"))
        joint = _sdf_frame_joint(f, world)
        if joint is not None:
            joints[joint.name] = joint
    welded = []  # fixed joints to the world: the model's placement, unless there are several
    for name, j in joint_els.items():
        if name in leave_out[1]:
            continue
        joint = _sdf_joint(name, j, world)
        if joint is not None:
            joints[name] = joint
        elif j.find("child").text.strip() in links:
            welded.append(name)
    if len(welded) > 1:  # two arms on one table (ALOHA): each where it stands in the world
        for name in welded:
            X_j, child = world(name), joint_els[name].find("child").text.strip()
            joints[name] = KJoint(name, "fixed", WORLD, child, X_j, np.linalg.inv(X_j) @ world(child),
                                  np.array([1.0, 0, 0]))
    return KModel(source, links, joints)


def _frame_graph(link_els: dict, joint_els: dict, frame_els: list, source: str):
    """``world(name)``: the pose of a link, joint or frame of an SDF model in the model frame,
    following ``relative_to`` (SDF's defaults: a link's pose is relative to the model, a joint's
    to its child link, a frame's to the frame it is attached to)."""
    frames: dict[str, tuple[np.ndarray, str]] = {}  # name -> (pose, relative_to)
    for name, lk in link_els.items():
        T, rel = _pose(lk)
        frames[name] = (T, rel or "__model__")
    for name, j in joint_els.items():
        T, rel = _pose(j)
        frames[name] = (T, rel or j.find("child").text.strip())
    for f in frame_els:
        T, rel = _pose(f)
        frames[f.get("name")] = (T, rel or f.get("attached_to") or "__model__")
    resolved: dict[str, np.ndarray] = {"__model__": np.eye(4)}

    def world(name: str, depth=0) -> np.ndarray:
        if name in resolved:
            return resolved[name]
        if depth > 100:
            raise ValueError(f"{source}: frame cycle at '{name}'")
        if name not in frames:
            raise ValueError(f"{source}: a pose is relative to '{name}', which the model does not define")
        T, rel = frames[name]
        resolved[name] = world(rel, depth + 1) @ T
        return resolved[name]

    return world


def _sdf_link(name: str, lk) -> KLink:
    """A ``<link>``'s mass, centre of mass and inertia (link axes), with SDF's defaults as
    libsdformat, Gazebo and Drake apply them: a link without ``<inertial>`` weighs 1 kg with a
    unit inertia (never 0: a massless thing must be a ``<frame>``)."""
    inertial = lk.find("inertial")
    if inertial is None:
        return KLink(name, 1.0, np.zeros(3), np.eye(3))
    T, _ = _pose(inertial)
    mass = float(inertial.findtext("mass", "1"))
    i = inertial.find("inertia")
    defaults = {"ixx": "1", "iyy": "1", "izz": "1"}
    g = {k: float(i.findtext(k, defaults.get(k, "0")) if i is not None else defaults.get(k, "0"))
         for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    I = np.array([[g["ixx"], g["ixy"], g["ixz"]],
                  [g["ixy"], g["iyy"], g["iyz"]],
                  [g["ixz"], g["iyz"], g["izz"]]])
    R = T[:3, :3]
    return KLink(name, mass, T[:3, 3].copy(), R @ I @ R.T)


def _sdf_frame_joint(f, world) -> KJoint | None:
    """The fixed joint holding a ``<frame>`` where it is attached (none on the model itself)."""
    name = f.get("name")
    attached = f.get("attached_to") or "__model__"
    if attached == "__model__":
        return None
    X_a, X_f = world(attached), world(name)
    return KJoint(f"(frame {name})", "fixed", attached, name, np.linalg.inv(X_a) @ X_f, np.eye(4),
                  np.array([1.0, 0, 0]))


def _sdf_joint(name: str, j, world) -> KJoint | None:
    """A ``<joint>`` between its parent's and child's frames: axis in the joint frame, limits
    (a revolute joint without them is continuous), damping and friction; None for a fixed joint
    to the world (the model's placement, not part of the robot).  A joint that moves a link
    against the world (Valkyrie's forearm descriptions) is the robot's: the world is taken
    where the model frame is, as a URDF's ``world`` link is."""
    parent, child = j.find("parent").text.strip(), j.find("child").text.strip()
    kind = j.get("type")
    if parent == WORLD and kind == "fixed":
        return None
    X_j = world(name)
    X_p, X_c = np.eye(4) if parent == WORLD else world(parent), world(child)
    axis_el = j.find("axis")
    axis = np.array([0, 0, 1.0])
    lower = upper = effort = velocity = damping = friction = None
    if axis_el is not None:
        xyz = axis_el.find("xyz")
        axis = np.array([float(v) for v in xyz.text.split()])
        expressed = xyz.get("expressed_in")
        if expressed:
            axis = np.linalg.inv(X_j[:3, :3]) @ (world(expressed)[:3, :3] @ axis)
        lim = axis_el.find("limit")
        if lim is not None:
            lo, hi = lim.findtext("lower"), lim.findtext("upper")
            if lo is not None and abs(float(lo)) < 1e15:
                lower, upper = float(lo), float(hi)
            if lim.findtext("effort") is not None:
                effort = float(lim.findtext("effort"))
            if lim.findtext("velocity") is not None:
                velocity = float(lim.findtext("velocity"))
        dyn = axis_el.find("dynamics")
        if dyn is not None:
            damping = float(dyn.findtext("damping", "0"))
            friction = float(dyn.findtext("friction", "0"))
    if kind == "revolute" and lower is None:
        kind = "continuous"
    return KJoint(name, kind, parent, child, np.linalg.inv(X_p) @ X_j, np.linalg.inv(X_j) @ X_c,
                  axis / np.linalg.norm(axis), lower, upper, effort, velocity, damping, friction)


def read_sdf(path) -> KModel:
    return read_sdf_text(open(path, encoding="utf-8").read(), f"SDF {path}")


def read_urdf_via_libsdformat(path) -> KModel:
    """libsdformat's own reading of the URDF (`ign sdf -p`), as SDF."""
    proc = programs.libsdformat(path)
    if proc.returncode != 0 or "<sdf" not in proc.stdout:
        raise RuntimeError(f"ign sdf -p {path} failed: {proc.stderr.strip() or proc.stdout.strip()}")
    return read_sdf_text(proc.stdout, f"URDF {path} (libsdformat)", extension_parts(path))


def lump(model: KModel, kept: frozenset[str] = frozenset(), world: bool = False) -> KModel:
    """``model`` as libsdformat's URDF conversion (Gazebo's spawn path) sees it: every link
    joined to its parent by a fixed joint merged into that parent (masses added, centres of
    mass combined, inertias moved by the parallel-axis theorem), the joints below re-attached;
    but the fixed joints ``kept`` (the URDF's ``<preserveFixedJoint>``: ``model.kept``).  With
    ``world`` (Pinocchio), the links welded to the world are one body too, named after the first."""
    parent_of = model.parent_of()
    to_world = [n for n in model.links if n in parent_of and parent_of[n].type == "fixed"
                and parent_of[n].parent == WORLD and parent_of[n].name not in kept] if world else []
    X = {n: parent_of[n].T_pj @ parent_of[n].T_jc for n in to_world}

    def carrier(name: str) -> tuple[str, np.ndarray]:
        T = np.eye(4)
        while True:
            j = parent_of.get(name)
            if name in X and name != to_world[0]:  # welded to the world: into the first welded link
                return to_world[0], np.linalg.inv(X[to_world[0]]) @ X[name] @ T
            if j is None or j.type != "fixed" or j.parent == WORLD or j.parent not in model.links or \
                    j.name in kept:
                return name, T
            T = j.T_pj @ j.T_jc @ T
            name = j.parent

    sums: dict[str, list] = {}
    for name, link in model.links.items():
        top, T = carrier(name)
        sums.setdefault(top, []).append((link, T))
    links = {}
    for top, parts in sums.items():
        m = sum(real_mass(p.mass) for p, _ in parts)
        if m <= 0:
            links[top] = KLink(top)
            continue
        com = sum(real_mass(p.mass) * (T[:3, :3] @ p.com + T[:3, 3]) for p, T in parts) / m
        inertia = np.zeros((3, 3))
        for p, T in parts:
            R, d = T[:3, :3], T[:3, :3] @ p.com + T[:3, 3] - com
            inertia += R @ p.inertia @ R.T + real_mass(p.mass) * (d @ d * np.eye(3) - np.outer(d, d))
        links[top] = KLink(top, m, com, inertia)
    joints = {}
    for name, j in model.joints.items():
        if j.type == "fixed" and j.parent != WORLD and j.parent in model.links and name not in kept:
            continue
        if j.child in X and j.child != to_world[0]:  # merged into the first welded link
            continue
        top, T = carrier(j.parent) if j.parent in model.links else (j.parent, np.eye(4))
        joints[name] = KJoint(**{**j.__dict__, "parent": top, "T_pj": T @ j.T_pj})
    return KModel(f"{model.source} lumped", links, joints)


# ---------------------------------------------------------------- comparison


def _close(a, b, tol, scale=1.0) -> bool:
    return bool(np.all(np.abs(np.asarray(a, dtype=float) - np.asarray(b, dtype=float)) <= tol * max(scale, 1e-300)))


def pose_difference(A: np.ndarray, B: np.ndarray, tol: float) -> str | None:
    """How frame ``B`` differs from ``A`` (4x4, same reference), or None when they agree: positions
    to ``tol`` relative to the larger of 1 m and the distance (absolute near the origin),
    orientations to ``tol`` in rotation-matrix entries."""
    size = max(1.0, float(np.abs(A[:3, 3]).max()))
    if not _close(A[:3, 3], B[:3, 3], tol, size):
        return f"{A[:3, 3].tolist()} vs {B[:3, 3].tolist()}"
    if not _close(A[:3, :3], B[:3, :3], tol):
        return f"at {A[:3, 3].tolist()}, turned by {turn(A, B):.3g} rad"
    return None


def turn(A: np.ndarray, B: np.ndarray) -> float:
    """The angle (rad) between the orientations of frames ``A`` and ``B``."""
    cos = (np.trace(A[:3, :3].T @ B[:3, :3]) - 1) / 2
    return math.acos(max(-1.0, min(1.0, float(cos))))


def followed_mimics(model: KModel) -> KModel:
    """``model`` with each mimic joint against the joint its chain starts from (a mimic of a
    mimic composed: robotkit's URDF writes them so, an MJCF keeps the chain of equalities)."""
    chained = [j for j in model.joints.values() if j.mimic and j.mimic[0] in model.joints
               and model.joints[j.mimic[0]].mimic]
    if not chained:
        return model
    model = copy.deepcopy(model)
    for j in model.joints.values():
        if not j.mimic:
            continue
        (leader, multiplier, offset), seen = j.mimic, {j.name}
        while leader in model.joints and model.joints[leader].mimic and leader not in seen:
            seen.add(leader)
            up = model.joints[leader].mimic
            leader, multiplier, offset = up[0], multiplier * up[1], multiplier * up[2] + offset
        j.mimic = (leader, multiplier, offset)
    return model


def compare(a: KModel, b: KModel, tol: float = 1e-9, configs: int = 100, seed: int = 0,
            ignore: tuple[str, ...] = (), pose_tol: float | None = None) -> list[str]:
    """Every difference between two readings of a robot, as sentences; [] when equivalent.

    ``ignore`` names joint attributes one side cannot hold (e.g. "velocity" for MJCF);
    ``pose_tol`` is what the readers can hold of a link's pose (default ``tol``)."""
    a, b = followed_mimics(a), followed_mimics(b)
    diffs: list[str] = []
    la = {n for n in a.links if n != WORLD}
    lb = {n for n in b.links if n != WORLD}
    if la != lb:
        diffs.append(f"links differ: only in {a.source}: {sorted(la - lb)}; only in {b.source}: {sorted(lb - la)}")
    pa, pb = a.parent_of(), b.parent_of()
    for name in sorted(la & lb):
        ja, jb = pa.get(name), pb.get(name)
        par_a = ja.parent if ja else None
        par_b = jb.parent if jb else None
        rigid = (ja is None or ja.type == "fixed") and (jb is None or jb.type == "fixed")
        # links rigidly attached may hang the other way round (a massless root is an SDF frame on
        # its child): their poses below say whether they sit in the same place
        if not rigid and (par_a or WORLD) != (par_b or WORLD) and not ({par_a, par_b} <= {None, WORLD}):
            diffs.append(f"link '{name}': parent '{par_a}' in {a.source}, '{par_b}' in {b.source}")
        A, B = a.links[name], b.links[name]
        mass_a, mass_b = real_mass(A.mass), real_mass(B.mass)
        if not _close(mass_a, mass_b, tol, abs(mass_a)):
            diffs.append(f"link '{name}': mass {A.mass!r} vs {B.mass!r}")
        size = max(1.0, float(np.abs(A.com).max()))
        if mass_a > 0 and not _close(A.com, B.com, tol, size):
            diffs.append(f"link '{name}': centre of mass {A.com.tolist()} vs {B.com.tolist()}")
        scale = float(np.abs(A.inertia).max())
        if mass_a > 0 and not _close(A.inertia, B.inertia, tol, scale):
            diffs.append(f"link '{name}': inertia tensor {A.inertia.tolist()} vs {B.inertia.tolist()}")
    movable = ("revolute", "continuous", "prismatic")
    ma = {n: j for n, j in a.joints.items() if j.type in movable}
    mb = {n: j for n, j in b.joints.items() if j.type in movable}
    if set(ma) != set(mb):
        diffs.append(f"movable joints differ: {sorted(ma)} in {a.source}, {sorted(mb)} in {b.source}")
    for name in sorted(set(ma) & set(mb)):
        A, B = ma[name], mb[name]
        if A.type != B.type:
            diffs.append(f"joint '{name}': type {A.type} vs {B.type}")
        for attr in ("lower", "upper", "effort", "velocity", "damping", "friction"):
            va, vb = getattr(A, attr), getattr(B, attr)
            if attr in ignore or va is None or vb is None:
                continue
            if not _close(va, vb, tol, max(abs(va), 1.0)):
                diffs.append(f"joint '{name}': {attr} {va!r} vs {vb!r}")
        if (A.mimic is None) != (B.mimic is None) and "mimic" not in ignore:
            diffs.append(f"joint '{name}': mimic {A.mimic} vs {B.mimic}")
        elif A.mimic and B.mimic and (A.mimic[0] != B.mimic[0] or not _close(A.mimic[1:], B.mimic[1:], tol)):
            diffs.append(f"joint '{name}': mimic {A.mimic} vs {B.mimic}")
    if diffs:
        return diffs
    if "mimic" in ignore:  # one side cannot hold mimic relations: move both by the other's
        b = copy.deepcopy(b)
        for name, j in b.joints.items():
            if j.mimic is None and name in a.joints and a.joints[name].mimic is not None:
                j.mimic = a.joints[name].mimic
    rng = np.random.default_rng(seed)
    names = sorted(ma)
    shared = sorted(la & lb)
    root_a, root_b = a.root(), b.root()
    for k in range(configs):
        q = {}
        for n in names:
            j = ma[n]
            lo, hi = (j.lower, j.upper) if j.lower is not None else ((-math.pi, math.pi) if j.type != "prismatic" else (-1, 1))
            q[n] = float(rng.uniform(lo, hi)) if k else 0.0
        Ta, Tb = a.fk(q), b.fk(q)
        ra, rb = np.linalg.inv(Ta[root_a]), np.linalg.inv(Tb[root_a if root_a in Tb else root_b])
        name = first_pose_difference(ra, Ta, rb, Tb, shared, tol if pose_tol is None else pose_tol)
        if name is not None:
            differs = pose_difference(ra @ Ta[name], rb @ Tb[name], tol if pose_tol is None else pose_tol)
            diffs.append(f"link '{name}': pose differs at configuration {q}: {differs}")
            return diffs
    return diffs


def first_pose_difference(ra: np.ndarray, Ta: dict, rb: np.ndarray, Tb: dict, names: list[str],
                          tol: float) -> str | None:
    """The first of ``names`` whose frame ``ra @ Ta[name]`` differs from ``rb @ Tb[name]`` as
    :func:`pose_difference` tells (None: every one agrees); all links at once, in numpy."""
    if not names:
        return None
    A = np.stack([ra @ Ta[n] for n in names])
    B = np.stack([rb @ Tb[n] for n in names])
    size = np.maximum(1.0, np.abs(A[:, :3, 3]).max(axis=1))
    position = (np.abs(A[:, :3, 3] - B[:, :3, 3]) <= (tol * np.maximum(size, 1e-300))[:, None]).all(axis=1)
    orientation = (np.abs(A[:, :3, :3] - B[:, :3, :3]) <= tol * max(1.0, 1e-300)).all(axis=(1, 2))
    bad = np.flatnonzero(~(position & orientation))
    return names[int(bad[0])] if len(bad) else None
