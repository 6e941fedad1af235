"""An SDF ``<model>`` (as libsdformat printed it, or its own XML) as plain data: links with their
pose in the model frame, inertial (SDF's defaults where it gives none: mass 1, unit moments),
shapes and sensors; joints with their frame and axes in the model frame; ``<frame>``s; plugins.
A nested model's names are ``model::name``.  The same reading serves the import and the
verification (the original and the rebuilt model.sdf)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from robotkit.importer.sdf.frames import MODEL, Frames, pose_of, scoped
from robotkit.urdfxml import is_element


@dataclass
class Link:
    name: str
    el: object
    T: np.ndarray  # pose in the model frame
    mass: float = 1.0
    com: np.ndarray = field(default_factory=lambda: np.zeros(3))  # in the link frame
    inertia: np.ndarray = field(default_factory=lambda: np.eye(3))  # about the com, link axes


@dataclass
class Joint:
    name: str
    el: object
    type: str
    parent: str
    child: str
    T: np.ndarray  # the joint frame in the model frame
    axes: list = field(default_factory=list)  # unit axes in the model frame


@dataclass
class Model:
    name: str
    static: bool = False
    links: dict = field(default_factory=dict)
    joints: dict = field(default_factory=dict)
    frames: dict = field(default_factory=dict)  # name -> (attached_to link, pose in the model frame)
    plugins: list = field(default_factory=list)
    prefixed: list = field(default_factory=list)  # (joint, its end as written, as read): see _own
    world: np.ndarray = field(default_factory=lambda: np.eye(4))  # the world frame in the model frame


def children(el, tag: str) -> list:
    return [c for c in el if is_element(c) and c.tag == tag]


def read_model(el, file: str) -> Model:
    m = Model(el.get("name") or "model", (el.findtext("static") or "").strip().lower() in ("true", "1"))
    frames = Frames(file, m.name)
    _, top = pose_of(el)
    frames.add("world", MODEL, np.linalg.inv(top))
    pending: list = []
    attached = {MODEL: _canonical(el, "")}
    _scope(el, "", m, frames, pending, attached)
    for kind, name, node in pending:
        if kind == "link":
            m.links[name] = _link(name, node, frames.get(name))
        elif kind == "joint":
            m.joints[name] = _joint(name, node, frames)
            attached[name] = m.joints[name].child
        else:
            m.frames[name] = node, frames.get(name)
    for j in m.joints.values():
        j.parent, j.child = (_link_of(_own(j, end, m, attached), m, attached) for end in (j.parent, j.child))
    m.frames = {name: (_link_of(a, m, attached), T) for name, (a, T) in m.frames.items()}
    m.plugins = children(el, "plugin")
    m.world = frames.get("world")
    _flat_names(m)
    return m


def _canonical(model, scope: str) -> str:
    """The frame a model is attached to: its canonical link (its ``canonical_link``, else its first
    link, else its first nested model's), as libsdformat's frame semantics have it."""
    if model.get("canonical_link"):
        return scope + model.get("canonical_link")
    links = children(model, "link")
    if links:
        return scope + links[0].get("name", "")
    nested = children(model, "model")
    return _canonical(nested[0], f"{scope}{nested[0].get('name', '')}::") if nested else scope[:-2] or MODEL


def _own(j, name: str, m: Model, attached: dict) -> str:
    """A joint's end named with the model's own name first (ArduPilot's models:
    'dolly_ardupilot::dolly::base_link'), which Gazebo classic finds and libsdformat does not: the
    name without it, noted in ``m.prefixed``."""
    known = lambda n: n in m.links or n in attached  # noqa: E731
    head = f"{m.name}::"
    if known(name) or not name.startswith(head) or not known(name[len(head):]):
        return name
    m.prefixed.append((j.name, name, name[len(head):]))
    return name[len(head):]


def _link_of(name: str, m: Model, attached: dict, seen: tuple = ()) -> str:
    """The link a frame is attached to (SDF 1.7: a joint's parent or child, or a frame's
    attached_to, may be a frame, a joint or a nested model): itself when it is a link, world, or
    nothing it can be followed to."""
    if name in m.links or name == "world" or name not in attached or name in seen:
        return name
    return _link_of(attached[name], m, attached, seen + (name,))


def _flat_names(m: Model) -> None:
    """A nested model's ``model::name`` as ``model/name`` (a ROS frame name the recipe takes)."""
    flat = lambda n: n.replace("::", "/")  # noqa: E731
    for lk in m.links.values():
        lk.name = flat(lk.name)
    for j in m.joints.values():
        j.name, j.parent, j.child = flat(j.name), flat(j.parent), flat(j.child)
    m.links = {flat(k): v for k, v in m.links.items()}
    m.joints = {flat(k): v for k, v in m.joints.items()}
    m.frames = {flat(k): (flat(a), T) for k, (a, T) in m.frames.items()}


def _scope(el, scope: str, m: Model, frames: Frames, pending: list, attached: dict) -> None:
    here = scope[:-2] if scope else MODEL
    for link in children(el, "link"):
        name = scope + link.get("name", "")
        base, T = pose_of(link)
        frames.add(name, scoped(scope, base, here), T)
        pending.append(("link", name, link))
    for joint in children(el, "joint"):
        name = scope + joint.get("name", "")
        base, T = pose_of(joint)
        frames.add(name, scoped(scope, base, scoped(scope, (joint.findtext("child") or "").strip(), here)), T)
        pending.append(("joint", name, (joint, scope)))
    for frame in children(el, "frame"):
        name = scope + frame.get("name", "")
        base, T = pose_of(frame)
        to = scoped(scope, frame.get("attached_to"), here)
        frames.add(name, scoped(scope, base, to), T)
        pending.append(("frame", name, to))
        attached[name] = to
    for nested in children(el, "model"):
        name = scope + nested.get("name", "")
        base, T = pose_of(nested)
        frames.add(name, scoped(scope, base, here), T)
        attached[name] = _canonical(nested, name + "::")
        _scope(nested, name + "::", m, frames, pending, attached)


def _link(name: str, el, T) -> Link:
    link = Link(name, el, T)
    inertial = el.find("inertial")
    if inertial is None:
        return link
    link.mass = float(inertial.findtext("mass") or 1.0)
    _, P = pose_of(inertial)
    t = inertial.find("inertia")
    get = lambda k, d: float(t.findtext(k) or d) if t is not None else d  # noqa: E731
    I = np.array([[get("ixx", 1.0), get("ixy", 0.0), get("ixz", 0.0)],
                  [get("ixy", 0.0), get("iyy", 1.0), get("iyz", 0.0)],
                  [get("ixz", 0.0), get("iyz", 0.0), get("izz", 1.0)]])
    link.com, link.inertia = P[:3, 3].copy(), P[:3, :3] @ I @ P[:3, :3].T
    return link


def _joint(name: str, node, frames: Frames) -> Joint:
    el, scope = node
    here = scope[:-2] if scope else MODEL
    parent = scoped(scope, (el.findtext("parent") or "").strip(), here)
    child = scoped(scope, (el.findtext("child") or "").strip(), here)
    T = frames.get(name)
    j = Joint(name, el, (el.get("type") or "").strip(), parent, child, T)
    for tag in ("axis", "axis2"):
        axis = el.find(tag)
        if axis is None:
            continue
        xyz = axis.find("xyz")
        v = np.array([float(x) for x in ((xyz.text if xyz is not None else None) or "0 0 1").split()][:3])
        frame = xyz.get("expressed_in") if xyz is not None else None
        if (axis.findtext("use_parent_model_frame") or "").strip().lower() in ("true", "1"):
            frame = MODEL
        R = frames.get(scoped(scope, frame, name) if frame else name)[:3, :3]
        v = R @ v
        j.axes.append(v / np.linalg.norm(v) if np.linalg.norm(v) else np.array([0.0, 0.0, 1.0]))
    return j
