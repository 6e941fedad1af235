"""MuJoCo bodies and joints as recipe links and joints.

A body is a link.  Its joints (hinge, slide) are the recipe's joints; a body with several
joints becomes a chain through links, one per joint but the last, as MuJoCo moves a body through
its joints in order, each with a point mass taken from the body where that changes nothing
(robotkit.importer.mjcf.chainmass).  A ball joint is three revolute joints (x, y, z of the body)
through two such links.  A free joint is the recipe's ``base: free`` (the only body of the
world) or a floating joint from ``world``; otherwise the recipe is rooted in a ``world`` link
(the robot stays where the file puts it: a robot rooted elsewhere stands on the floor in the
rebuilt MJCF).  A hinge about an axis that misses the body's origin
puts the link frame on the axis: the body's contents are written in that frame (``offset``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from robotkit.importer.mjcf.frames import clean, origin, quat_matrix
from robotkit.importer.names import valid_frame_name
from robotkit.model.inertia_policy import MIN_MOMENT
from robotkit.recipe.schema import MIN_MASS

FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3
WORLD = "world"
UNLIMITED_SLIDE = 1e3
UNLIMITED = 1e9
"""An effort or velocity limit the original leaves unlimited on a driven joint: a stated value no
motor reaches (the recipe has no unlimited form, and 0 is a passive joint: robotkit's rules read
it so, and Gazebo clamps a commanded force to 0)."""
CHAIN_MASS = 1e-6
"""The mass of a chain's link that cannot take its mass from its body (robotkit.importer.mjcf.chainmass),
as a fraction of the lightest body's (MuJoCo refuses a moving body without mass), not below the
least mass a recipe takes: a point mass, added, on the ledger."""


@dataclass
class Tree:
    links: dict = field(default_factory=dict)
    joints: dict = field(default_factory=dict)
    link_of: dict = field(default_factory=dict)  # body id -> link name
    offset: dict = field(default_factory=dict)  # body id -> link frame origin in the body frame
    joint_map: dict = field(default_factory=dict)  # MuJoCo joint id -> recipe joint names
    base: str = "fixed"
    chain_links: list = field(default_factory=list)
    chains: dict = field(default_factory=dict)  # body id -> (its chain links, its joint stages: see _stages)
    moved: dict = field(default_factory=dict)  # chain link -> the body id whose mass it carries (chainmass)
    notes: dict = field(default_factory=dict)  # joint name -> comment above it
    actuated: dict = field(default_factory=dict)  # MuJoCo actuator id -> the recipe joint it drives (kept ones)
    mimics: dict = field(default_factory=dict)  # MuJoCo equality id -> (mimic joint, leader) (kept ones)
    sites: dict = field(default_factory=dict)  # MuJoCo site id -> its frame link (robotkit.importer.mjcf.sites)
    kept_sensors: set = field(default_factory=set)  # MuJoCo sensor ids the recipe's sensors hold
    refused: dict = field(default_factory=dict)  # MuJoCo actuator id -> why the recipe's actuators cannot hold it
    verbatim: dict = field(default_factory=dict)  # kind -> {MuJoCo id: name} kept in mjcf_extras (verbatim.py)
    ledger: list = field(default_factory=list)


def names(model, kind: str, count: int, fallback: str) -> list[str]:
    """Every element's name: its own, or ``<fallback><id>`` when it has none or one the recipe refuses."""
    out, taken = [], set()
    for i in range(count):
        name = getattr(model, kind)(i).name
        if not valid_frame_name(name) or name in taken:
            name = f"{fallback}{i}"
        taken.add(name)
        out.append(name)
    return out


def build_tree(src, ledger) -> Tree:
    m = src.model
    tree = Tree(ledger=ledger)
    bodies = names(m, "body", m.nbody, "body")
    jnames = names(m, "joint", m.njnt, "joint")
    tops = [b for b in range(1, m.nbody) if m.body_parentid[b] == 0]
    single = len(tops) == 1
    top = tops[0] if single else None
    own_root = single and m.body_jntnum[top] == 1 and m.jnt_type[m.body_jntadr[top]] == FREE
    if own_root:
        tree.link_of[top] = bodies[top]
        tree.offset[top] = np.zeros(3)
        tree.links[bodies[top]] = {}
        if m.body_jntnum[top]:
            tree.base = "free"
            tree.joint_map[int(m.body_jntadr[top])] = [f"{bodies[top]}_free"]
    else:
        tree.links[WORLD] = {}
        tree.link_of[0] = WORLD
        tree.offset[0] = np.zeros(3)
    lightest = min((float(x) for x in m.body_mass[1:] if x > 0), default=1.0)
    for b in range(1, m.nbody):
        if b not in tree.link_of:
            _body(src, tree, b, bodies, jnames, max(lightest * CHAIN_MASS, MIN_MASS))
    return tree


def _stages(m, b, jnames: list[str]) -> list[tuple[str, int, np.ndarray, np.ndarray, int]]:
    """The body's joints as recipe joint stages: (name, type, axis, anchor on the axis, MuJoCo joint)."""
    out = []
    for j in range(m.body_jntadr[b], m.body_jntadr[b] + m.body_jntnum[b]):
        t, axis, pos = int(m.jnt_type[j]), np.array(m.jnt_axis[j], float), np.array(m.jnt_pos[j], float)
        if t == BALL:
            out.extend((f"{jnames[j]}_{a}", BALL, np.eye(3)[k], pos, j) for k, a in enumerate("xyz"))
        elif t == HINGE:
            out.append((jnames[j], HINGE, axis, pos - axis * float(pos @ axis), j))
        else:
            out.append((jnames[j], t, axis, np.zeros(3), j))
    return out


def _body(src, tree: Tree, b: int, bodies, jnames, chain_mass: float) -> None:
    m = src.model
    name = bodies[b]
    parent = int(m.body_parentid[b])
    pos, R = np.array(m.body_pos[b], float) - tree.offset[parent], quat_matrix(m.body_quat[b])
    stages = _stages(m, b, jnames)
    if not stages:
        tree.link_of[b], tree.offset[b] = name, np.zeros(3)
        tree.links[name] = {}
        tree.joints[_joint_name(tree, name)] = _joint("fixed", tree.link_of[parent], name, pos, R)
        return
    prev_link, prev_anchor = tree.link_of[parent], None
    for k, (jname, t, axis, anchor, j) in enumerate(stages):
        last = k == len(stages) - 1
        child = name if last else _free_name(tree, f"{name}_{jname}")
        if t == FREE:  # a free joint below the world's own bodies: floating from world
            tree.joints[jname] = _joint("floating", prev_link, child, pos, R)
        else:
            at, turn = (pos + R @ anchor, R) if prev_anchor is None else (anchor - prev_anchor, np.eye(3))
            tree.joints[jname] = _moving(src, tree, t, prev_link, child, at, turn, axis, j)
        _note(src, tree, jname, t, j, anchor)
        tree.links.setdefault(child, {})
        if not last:
            tree.chain_links.append(child)
            tree.links[child] = {"inertial": {"mass": chain_mass, "inertia": _point(chain_mass)}}
        prev_link, prev_anchor = child, anchor
    for jname, *_, j in stages:
        tree.joint_map.setdefault(j, []).append(jname)
    if len(stages) > 1:
        tree.chains[b] = (tree.chain_links[-(len(stages) - 1):], stages)
    tree.link_of[b], tree.offset[b] = name, stages[-1][3]


def _note(src, tree: Tree, name: str, t: int, j: int, anchor) -> None:
    """The comment above a joint the recipe writes otherwise than the file."""
    m = src.model
    notes = []
    if t == BALL:
        notes.append(f"one of the three revolute joints ball joint '{m.joint(j).name}' becomes (x, y, z of its body)")
    if t == HINGE and np.any(anchor):
        notes.append("the link frame is on the joint's axis (MJCF joint pos " +
                     " ".join(f"{v:g}" for v in m.jnt_pos[j]) + "): the body's shapes, inertial and children are "
                     "written in that frame")
    ref = float(m.qpos0[m.jnt_qposadr[j]]) if t in (HINGE, SLIDE) else 0.0
    if ref:
        notes.append(f"MJCF ref {ref:g}: the origin takes the body back to the joint's zero, so joint values "
                     "(limits, poses) are MuJoCo's")
    if notes:
        tree.notes[name] = "; ".join(notes)


def _point(mass: float) -> dict:
    # ten times the least moment the build writes into an MJCF (inertia_policy.MIN_MOMENT)
    i = max(mass * 1e-6, 10 * MIN_MOMENT)
    return {"ixx": i, "iyy": i, "izz": i}


def _free_name(tree: Tree, base: str) -> str:
    name, n = base, 2
    while name in tree.links:
        name, n = f"{base}_{n}", n + 1
    return name


def _joint_name(tree: Tree, child: str) -> str:
    name, n = f"{child}_fixed", 2
    while name in tree.joints:
        name, n = f"{child}_fixed_{n}", n + 1
    return name


def _joint(kind: str, parent: str, child: str, pos, R) -> dict:
    out = {"type": kind, "parent": parent, "child": child}
    o = origin(pos, R)
    if o:
        out["origin"] = o
    return out


def _axis_rotation(axis, angle: float) -> np.ndarray:
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _moving(src, tree: Tree, t: int, parent: str, child: str, pos, R, axis, j: int) -> dict:
    """A hinge or slide (or one angle of a ball).  MuJoCo places the body as the file does at the
    joint's ``ref`` (qpos0), and moves it by the value minus ``ref``: the origin takes the move back
    to the value 0, so the recipe's joint values are MuJoCo's (limits, keyframes)."""
    m = src.model
    ref = float(m.qpos0[m.jnt_qposadr[j]]) if t in (HINGE, SLIDE) else 0.0
    if ref and t == HINGE:
        R = R @ _axis_rotation(axis, -ref)
    elif ref:
        pos = pos - R @ np.asarray(axis, float) * ref
    limited = bool(m.jnt_limited[j])
    lo, hi = (float(v) for v in m.jnt_range[j])
    if t == BALL:
        kind = "revolute" if limited else "continuous"
        lo, hi = -hi, hi
    else:
        kind = {HINGE: "revolute" if limited else "continuous", SLIDE: "prismatic"}[t]
    out = _joint(kind, parent, child, pos, R)
    out["axis"] = clean(axis)
    if kind != "continuous":
        if not limited:  # an unlimited slide: the recipe's prismatic joint needs limits
            lo, hi = -UNLIMITED_SLIDE, UNLIMITED_SLIDE
            tree.ledger.add(src.where_named("joint", m.joint(j).name), f"joint '{m.joint(j).name}' (slide)", "all",
                            f"unlimited: written with limits -{UNLIMITED_SLIDE:g} to {UNLIMITED_SLIDE:g} m (a "
                            "prismatic joint has limits)")
        out["limit"] = {"lower": lo, "upper": hi}
    d = int(m.jnt_dofadr[j])
    dyn = {"damping": float(m.dof_damping[d]), "friction": float(m.dof_frictionloss[d]),
           "armature": float(m.dof_armature[d])}
    dyn = {k: v for k, v in dyn.items() if v}
    if dyn:
        out["dynamics"] = dyn
    return out
