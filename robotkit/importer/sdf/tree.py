"""SDF links and joints as recipe links and joints.

A link is a link.  A link a moving joint moves has its frame on the joint's frame (URDF puts a
joint's axis through its child's origin): when the SDF joint's pose in its child is not the
identity, the link's contents are written in that frame (``offset``).  revolute, prismatic,
continuous and fixed joints map one to one (a revolute joint with no limits, or SDF's ±1e16, is
continuous); a ball joint is three revolute joints (x, y, z of its frame) through two links, a
universal or revolute2 joint two, each link with a point mass taken from the joint's child at
the joint's centre (:func:`take_chain_masses`); a screw joint is a revolute joint (its translation is
stated); a gearbox joint, or any joint closing a loop, is dropped (stated).  A static model, or
a joint to ``world``, roots the recipe in a ``world`` link; any other model floats (``base:
free``)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from robotkit.importer.inertials import POINT_MASS_FLOOR
from robotkit.importer.mjcf.chainmass import carve, point_inertial
from robotkit.importer.mjcf.frames import clean, origin
from robotkit.importer.mjcf.tree import CHAIN_MASS, UNLIMITED, UNLIMITED_SLIDE, WORLD
from robotkit.recipe.schema import MAX_VALUE

HUGE = 1e10
"""A revolute joint's limit beyond this (SDF's default is ±1e16) means none: continuous."""
CHAINS = {"ball": 3, "universal": 2, "revolute2": 2}
CHAIN_FLOOR = POINT_MASS_FLOOR
"""The least mass (kg) of a joint chain's massless link: libsdformat's URDF reader drops a link of
1e-6 kg or less with everything below it (gz::math::equal's tolerance; sdformat #199), so Gazebo,
reading the rebuilt URDF, would lose the joint's child (the MJCF import's millionth of the lightest
body is below it on any model lighter than 1 kg)."""


@dataclass
class Tree:
    links: dict = field(default_factory=dict)  # recipe link name -> dict
    joints: dict = field(default_factory=dict)
    frame: dict = field(default_factory=dict)  # SDF link -> its recipe frame in the model frame (4x4)
    joint_map: dict = field(default_factory=dict)  # SDF joint -> recipe joint names
    chain_links: list = field(default_factory=list)
    chains: dict = field(default_factory=dict)  # SDF link -> the chain links of the joint that moves it
    moved: dict = field(default_factory=dict)  # chain link -> the SDF link whose mass it carries
    base: str = "fixed"
    notes: dict = field(default_factory=dict)  # joint -> comment above it
    link_notes: dict = field(default_factory=dict)
    used: dict = field(default_factory=dict)  # SDF link -> the SDF joint (turned round or not) the tree hangs it by
    world_pose: bool = False  # the model's <pose> kept in its joints to the world
    scaled: set = field(default_factory=set)  # links whose mass the recipe could not hold (on the ledger)

    def offset(self, link, T) -> np.ndarray:
        """The recipe frame of SDF link ``link`` in its own SDF frame ``T``."""
        return np.linalg.inv(T) @ self.frame[link]


def build_tree(src, m, ledger) -> Tree:
    tree = Tree()
    for joint, written, read in m.prefixed:
        ledger.add(src.where("joint", joint.replace("::", "/")), f"joint '{joint.replace('::', '/')}'", "all",
                   f"'{written}' read as '{read}' (the model's own name first: Gazebo classic finds it, "
                   "libsdformat does not)")
    lightest = min((lk.mass for lk in m.links.values() if lk.mass > 0), default=1.0)
    parent_of: dict[str, object] = {}
    for j in m.joints.values():
        why = _unmapped(j, m, parent_of)
        turned = _turned(j, m, parent_of) if why.startswith("dropped: it closes a loop") else None
        if turned is not None:
            ledger.add(src.where("joint", j.name), f"joint '{j.name}' ({j.type})", "all", f"written from "
                       f"'{j.child}' to '{j.parent}' (its child already has joint '{parent_of[j.child].name}'; a joint "
                       "that cannot move is the same either way)")
            j, why = turned, ""
        if why:
            ledger.add(src.where("joint", j.name), f"joint '{j.name}' ({j.type})", "all", why)
            continue
        parent_of[j.child] = j
    tree.used = parent_of
    roots = [n for n in m.links if n not in parent_of]
    jointed = [j.name for j in parent_of.values() if j.parent == WORLD]
    world = m.static or bool(jointed)
    if world:  # jointed to the world, where the model stands is physics (gravity on a pendulum): kept
        tree.links[WORLD] = {}
        tree.frame[WORLD] = m.world if jointed else np.eye(4)
        tree.world_pose = bool(jointed) and not np.allclose(m.world, np.eye(4), rtol=0, atol=0)
    else:
        tree.base = "free"
    for name, link in m.links.items():
        j = parent_of.get(name)
        tree.frame[name] = j.T if j is not None and j.type not in ("fixed",) else link.T
        tree.links[name] = {}
    for k, name in enumerate(roots):
        if world:
            tree.joints[_free(tree.joints, f"{name}_fixed")] = _fixed(tree, WORLD, name)
        elif k:
            tree.joints[_free(tree.joints, f"{name}_floating")] = dict(_fixed(tree, roots[0], name), type="floating")
            ledger.add(src.where("link", name), f"link '{name}'", "all", f"a second free body: joined to "
                       f"'{roots[0]}' by a floating joint (the recipe is one tree)")
    for name, j in parent_of.items():
        _joint(src, tree, j, max(lightest * CHAIN_MASS, CHAIN_FLOOR), ledger)
    return tree


def _unmapped(j, m, parent_of) -> str:
    if j.type == "gearbox":
        return "dropped: a gearbox couples two joints the recipe keeps apart (no gear constraint in the recipe)"
    if j.child not in m.links:
        return f"dropped: its child '{j.child}' is not a link of the model"
    if j.parent not in m.links and j.parent != WORLD:
        return f"dropped: its parent '{j.parent}' is not a link of the model"
    if j.child in parent_of:
        return f"dropped: it closes a loop (link '{j.child}' already has joint '{parent_of[j.child].name}')"
    up = j.parent
    while up in parent_of:
        up = parent_of[up].parent
        if up == j.child:
            return f"dropped: it closes a loop (link '{j.parent}' already hangs from link '{j.child}')"
    if j.parent == j.child:
        return f"dropped: its parent and child are one link ('{j.child}')"
    if j.type not in ("fixed", "revolute", "continuous", "prismatic", "screw") and j.type not in CHAINS:
        return "dropped: the recipe has no such joint"
    return ""


def _turned(j, m, parent_of):
    """Joint ``j``, which closes a loop, with its parent and child swapped when it cannot move and
    its parent is still a free body (turtlebot: the included kinect's link fixed to the rack that
    the included create carries): the same model as one tree; None otherwise."""
    if j.parent not in m.links or j.parent in parent_of or not (j.type == "fixed" or _locked(j)):
        return None
    up = j.child
    while up in parent_of:
        up = parent_of[up].parent
        if up == j.parent:
            return None
    return replace(j, parent=j.child, child=j.parent, T=m.links[j.parent].T)


def _free(taken, base: str) -> str:
    name, n = base, 2
    while name in taken:
        name, n = f"{base}_{n}", n + 1
    return name


def _fixed(tree: Tree, parent: str, child: str) -> dict:
    out = {"type": "fixed", "parent": parent, "child": child}
    o = origin_of(np.linalg.inv(tree.frame[parent]) @ tree.frame[child])
    if o:
        out["origin"] = o
    return out


def origin_of(T) -> dict | None:
    return origin(T[:3, 3], T[:3, :3])


def _joint(src, tree: Tree, j, chain_mass: float, ledger) -> None:
    if j.type == "fixed":
        tree.joints[j.name] = _fixed(tree, j.parent, j.child)
        tree.joint_map[j.name] = [j.name]
        return
    where = src.where("joint", j.name)
    R = j.T[:3, :3]
    if j.type in CHAINS:
        n = CHAINS[j.type]
        axes = [np.eye(3)[k] for k in range(3)] if j.type == "ball" else [R.T @ a for a in j.axes[:2]]
        if len(axes) < n:  # a universal joint without its axes: x and y of its frame
            axes = [np.eye(3)[k] for k in range(n)]
        names = [f"{j.name}_{'xyz'[k]}" if j.type == "ball" else f"{j.name}_{k + 1}" for k in range(n)]
        how = ("three revolute joints about its frame's x, y, z" if j.type == "ball" else
               "two revolute joints, about its axis then its axis2")
        ledger.add(where, f"joint '{j.name}' ({j.type})", "all",
                   f"approximated: {how} ({', '.join(names)}), through massless links")
    else:
        axes, names = [R.T @ j.axes[0]] if j.axes else [np.array([0, 0, 1.0])], [j.name]
        if _locked(j):
            tree.joints[j.name] = _fixed(tree, j.parent, j.child)
            ledger.add(where, f"joint '{j.name}' ({j.type})", "all", "a fixed joint: its limits are equal (it "
                       "cannot move)")
            return
    if j.type == "screw":
        pitch = j.el.findtext("thread_pitch") or j.el.findtext("screw_thread_pitch") or "1"
        ledger.add(where, f"joint '{j.name}' (screw)", "all", f"approximated: a revolute joint (its translation "
                   f"along the axis, thread pitch {pitch.strip()}, dropped)")
    parent = j.parent
    for k, (name, axis) in enumerate(zip(names, axes)):
        last = k == len(names) - 1
        child = j.child if last else _free(tree.links, f"{j.child}_{name}_link")
        if not last:
            tree.chain_links.append(child)
            i = max(chain_mass * 1e-6, 1e-9)
            tree.links[child] = {"inertial": {"mass": chain_mass, "inertia": {"ixx": i, "iyy": i, "izz": i}}}
            tree.frame[child] = j.T
        out = _fixed(tree, parent, child)
        out.update(_motion(src, tree, j, axis, k, ledger, name))
        tree.joints[name] = out
        parent = child
    tree.joint_map[j.name] = names
    if len(names) > 1:
        tree.chains[j.child] = tree.chain_links[-(len(names) - 1):]


def take_chain_masses(src, tree: Tree, ledger) -> None:
    """Each chain link's point mass taken from the link its joint moves, at the joint's centre
    (the origin of both frames), where every axis of the joint passes: the dynamics unchanged
    (robotkit.importer.mjcf.chainmass); a link whose inertial the import repaired or recomputed, or
    too light to give it, keeps its own and its chain links an added one (on the ledger)."""
    for child, links in tree.chains.items():
        inertial = tree.links[child].get("inertial")
        rest = carve(inertial, [np.zeros(3)] * len(links))
        if rest is None:
            mass = tree.links[links[0]]["inertial"]["mass"]
            named = ", ".join(f"'{n}'" for n in links)
            why = ("it is too light to give it (what would be left is not a physical body)" if carve(inertial, [])
                   else "its inertial is the build's to compute from its geometry" if inertial
                   else "it has no mass to give")
            ledger.add(src.where("link", child), f"link '{child}' (joint chain)", "all",
                       f"approximated: chain link{'s' if len(links) > 1 else ''} {named} "
                       f"carr{'y' if len(links) > 1 else 'ies'} an added point mass of {mass:.3g} kg, not taken from "
                       f"the link: {why}")
            continue
        tree.links[child]["inertial"] = rest
        for link in links:
            tree.links[link]["inertial"] = point_inertial(np.zeros(3))
            tree.moved[link] = child


def _locked(j) -> bool:
    lim = j.el.find("axis/limit")
    lo, hi = (lim.findtext(k) if lim is not None else None for k in ("lower", "upper"))
    return j.type in ("revolute", "prismatic") and lo is not None and hi is not None and float(lo) == float(hi)


def _motion(src, tree: Tree, j, axis, k: int, ledger, name: str) -> dict:
    """type, axis, limit, dynamics of one revolute/prismatic stage of SDF joint ``j``."""
    el = j.el.find("axis2" if k == 1 and j.type in ("universal", "revolute2") else "axis")
    lim = el.find("limit") if el is not None else None
    num = lambda node, tag: float(node.findtext(tag)) if node is not None and node.findtext(tag) else None  # noqa
    lo, hi = num(lim, "lower"), num(lim, "upper")
    prismatic = j.type == "prismatic"
    if lo is not None and hi is not None and lo == hi:  # an axis that cannot move
        ledger.add(src.where("joint", j.name), f"joint '{j.name}' ({j.type}), axis {k + 1}", "all",
                   "a fixed joint: its limits are equal (it cannot move)")
        return {"type": "fixed"}
    out: dict = {"type": "prismatic" if prismatic else "revolute", "axis": clean(axis / np.linalg.norm(axis))}
    unlimited = lo is None or hi is None or abs(lo) >= HUGE or abs(hi) >= HUGE or j.type == "continuous"
    if unlimited and not prismatic:
        out["type"] = "continuous"
        if j.type == "revolute":
            tree.notes[j.name] = "revolute in the SDF, without limits (±1e16 or none): continuous"
    elif unlimited:
        lo, hi = -UNLIMITED_SLIDE, UNLIMITED_SLIDE
        ledger.add(src.where("joint", j.name), f"joint '{j.name}' (prismatic)", "all", f"unlimited: written with "
                   f"limits -{UNLIMITED_SLIDE:g} to {UNLIMITED_SLIDE:g} m (a prismatic joint has limits)")
    limit = {"lower": lo, "upper": hi} if out["type"] != "continuous" else {}
    unbounded = []
    for key in ("effort", "velocity"):
        value = num(lim, key)
        limit[key] = value if value is not None and 0 <= value < HUGE else UNLIMITED
        if limit[key] == UNLIMITED:
            unbounded.append(key)
    if unbounded:
        said = f"no {' or '.join(unbounded)} limit in the SDF (unlimited): {UNLIMITED:g}"
        tree.notes[name] = f"{tree.notes[name]}; {said}" if name in tree.notes else said
    out["limit"] = limit
    dyn = el.find("dynamics") if el is not None else None
    values = {"damping": num(dyn, "damping") or 0.0, "friction": num(dyn, "friction") or 0.0}
    values = {key: v for key, v in values.items() if v > 0}
    for key in [k for k, v in values.items() if v > MAX_VALUE]:
        ledger.add(src.where("joint", j.name), f"joint '{j.name}' {key} {values[key]:g}", "all",
                   f"approximated: written {MAX_VALUE:g}, the largest the recipe takes")
        values[key] = MAX_VALUE
    if values:
        out["dynamics"] = values
    return out
