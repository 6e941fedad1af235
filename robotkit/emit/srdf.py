"""Robot -> SRDF (templates/srdf/robot.srdf.j2): what MoveIt's Setup Assistant writes.

- one group named after the robot holding its moving joints: a ``<chain>`` from the root to the
  tip when they form one serial chain (the tip followed on through fixed joints with one child,
  as ``flange`` -> ``tool0``), else every moving joint that is not a mimic;
- each named pose (``poses:``) as a ``group_state`` of that group (joints it does not name at 0);
- a virtual joint fixing the root to the world (``floating`` for a free base; none when the root
  is the ``world`` link itself);
- the self-collision matrix's disabled pairs with MoveIt's reasons (Adjacent, Default, Always,
  Never, User: :mod:`robotkit.model.selfcollision`).
"""

from __future__ import annotations

from robotkit.emit import layout
from robotkit.emit.env import render
from robotkit.emit.formats import Format
from robotkit.model.robot import Robot

MOVING = ("revolute", "continuous", "prismatic")


def moving_joints(robot: Robot) -> list:
    """The joints a planner sets: moving, not mimics, in the recipe's order."""
    return [j for j in robot.joints if j.type in MOVING and j.mimic is None]


def chain(robot: Robot) -> tuple[str, str] | None:
    """(base link, tip link) when the moving joints lie on one path from the root, else None."""
    joints = [j for j in robot.joints if j.type in MOVING]
    if not joints:
        return None
    by_child = {j.child: j for j in robot.joints}
    children: dict[str, list] = {}
    for j in robot.joints:
        children.setdefault(j.parent, []).append(j)
    deepest = max(joints, key=lambda j: _depth(j, by_child))
    path, link = set(), deepest.child
    while link in by_child:
        path.add(by_child[link].name)
        link = by_child[link].parent
    if any(j.name not in path for j in joints):
        return None
    tip = deepest.child
    while len(children.get(tip, [])) == 1 and children[tip][0].type == "fixed":
        tip = children[tip][0].child
    return robot.root, tip


def _depth(j, by_child) -> int:
    n, link = 0, j.parent
    while link in by_child:
        n, link = n + 1, by_child[link].parent
    return n


def group_states(robot: Robot) -> list[dict]:
    joints = moving_joints(robot)
    return [{"name": p.name, "joints": [(j.name, dict(p.values).get(j.name, 0.0)) for j in joints]}
            for p in robot.poses]


def render_srdf(robot: Robot) -> str:
    joints = moving_joints(robot)
    group = {"name": robot.name, "chain": chain(robot), "joints": [j.name for j in joints]} if joints else None
    virtual = None if robot.root == "world" else {"type": "floating" if robot.base == "free" else "fixed",
                                                  "child": robot.root}
    m = robot.collision_matrix
    disabled = sorted(m.disabled(), key=lambda p: (p.a, p.b)) if m is not None else []
    summary = (f"{len(m.pairs)} pairs of links with collision geometry, {len(disabled)} disabled, "
               f"{len(m.pairs) - len(disabled)} checked; {m.samples} configurations sampled (seed {m.seed})"
               if m is not None else "fewer than two links have collision geometry")
    return render("srdf/robot.srdf.j2", robot=robot, group=group, states=group_states(robot) if group else [],
                  virtual=virtual, disabled=disabled, summary=summary)


FORMATS = [Format("srdf", render_srdf, layout.SRDF, ("srdf/robot.srdf.j2",), reads="groups", needs=("urdf",))]
