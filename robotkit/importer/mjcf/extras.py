"""Keyframes as named poses, ``<contact><exclude>`` as self-collision pairs never checked,
joint equalities as mimic joints, and the ledger lines of everything the recipe has no key for
and ``mjcf_extras`` does not keep (cameras, lights, flexes, contact pairs, joint springs: the
tendons, other equality constraints and sensors are :mod:`robotkit.importer.mjcf.verbatim`'s)."""

from __future__ import annotations

import math

import numpy as np

from robotkit.importer.mjcf.frames import quat_matrix
from robotkit.importer.names import valid_name

FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3
EQ_KINDS = {0: "connect", 1: "weld", 2: "joint", 3: "tendon", 4: "flex"}


def ball_angles(q) -> list[float]:
    """The angles (x, y, z) of the three revolute joints a ball joint becomes: R = Rx Ry Rz."""
    R = quat_matrix(q)
    b = math.asin(max(-1.0, min(1.0, float(R[0, 2]))))
    return [math.atan2(-float(R[1, 2]), float(R[2, 2])), b, math.atan2(-float(R[0, 1]), float(R[0, 0]))]


def joint_values(m, tree, qpos) -> dict[str, float]:
    """The recipe joints' values at a MuJoCo configuration (free joints left out)."""
    out = {}
    for j, names in tree.joint_map.items():
        adr, t = int(m.jnt_qposadr[j]), int(m.jnt_type[j])
        if t in (HINGE, SLIDE):
            out[names[0]] = float(qpos[adr])
        elif t == BALL:
            out.update(zip(names, ball_angles(qpos[adr:adr + 4])))
    return out


def add_poses(src, tree, recipe: dict, ledger) -> None:
    m = src.model
    poses, keys = {}, list(src.spec.keys)
    for k in range(m.nkey):
        name = m.key(k).name
        name = name if valid_name(name) and name not in poses else f"key{k}"
        where = src.where(keys[k]) if k < len(keys) else src.where()
        values = joint_values(m, tree, m.key_qpos[k])
        _mimics_followed(tree, values, where, name, ledger)
        _within_limits(tree, values, where, name, ledger)
        poses[name] = {j: v for j, v in values.items() if v != 0}
        if any(int(m.jnt_type[j]) == FREE for j in range(m.njnt)):
            ledger.add(where, f"keyframe '{name}'", "all", "the free joint's position and orientation dropped "
                       "(a pose holds joint values)")
        if m.nu and not _ctrl_is_targets(m, tree, recipe, k):
            ledger.add(where, f"keyframe '{name}'", "all", "ctrl dropped (the MJCF keyframe's ctrl is the pose's "
                       "position targets)")
        if m.key_time[k] or m.na and any(m.key_act[k]) or m.nmocap:
            ledger.add(where, f"keyframe '{name}'", "all", "time, act or mocap dropped")
    if poses:
        recipe["poses"] = poses


def _mimics_followed(tree, values: dict, where: str, pose: str, ledger) -> None:
    """Drop the values of mimic joints (the pose's leaders set them); one that disagrees is on the ledger."""
    for name, joint in tree.joints.items():
        mimic = joint.get("mimic")
        if mimic is None or name not in values:
            continue
        given = values.pop(name)
        follows = mimic.get("multiplier", 1.0) * values.get(mimic["joint"], 0.0) + mimic.get("offset", 0.0)
        if abs(given - follows) > 1e-9:
            ledger.add(where, f"keyframe '{pose}'", "all", f"joint '{name}' at {given:g}, written as its mimic's "
                       f"{follows:g}")


def _within_limits(tree, values: dict, where: str, pose: str, ledger) -> None:
    """A value outside its joint's range (MuJoCo takes a keyframe there; a recipe's pose lies
    within the limits): the nearest limit, on the ledger."""
    for name, value in values.items():
        limit = tree.joints[name].get("limit") if name in tree.joints else None
        if not limit or "lower" not in limit or "upper" not in limit:
            continue
        inside = min(max(value, float(limit["lower"])), float(limit["upper"]))
        if inside != value:
            values[name] = inside
            ledger.add(where, f"keyframe '{pose}'", "all", f"joint '{name}' at {value:g}, outside its range "
                       f"[{float(limit['lower']):g}, {float(limit['upper']):g}]: written as {inside:g}")


def _ctrl_is_targets(m, tree, recipe: dict, k: int) -> bool:
    """Whether a keyframe's ctrl is what the rebuilt keyframe writes: each position servo's joint value."""
    values = joint_values(m, tree, m.key_qpos[k])
    expected = []
    for a in range(m.nu):
        joint = tree.joint_map.get(int(m.actuator_trnid[a][0]), [None])[0] if m.actuator_trntype[a] == 0 else None
        act = recipe.get("actuators", {}).get(joint)
        verbatim = a in tree.verbatim.get("actuator", {})  # the rebuilt keyframe's ctrl is 0
        expected.append(values.get(joint, 0.0) if act and act["interface"] == "position" else
                        0.0 if verbatim else float(m.key_ctrl[k][a]))
    return bool(abs(np.array(expected) - m.key_ctrl[k]).max() <= 1e-9)


def add_excludes(src, tree, recipe: dict, ledger) -> None:
    m = src.model
    link_by_body = {m.body(b).name: tree.link_of[b] for b in range(m.nbody) if b in tree.link_of}
    pairs = []
    for e in src.spec.excludes:
        a, b = link_by_body.get(e.bodyname1), link_by_body.get(e.bodyname2)
        if a is None or b is None:
            ledger.add(src.where(e), f"exclude {e.bodyname1} {e.bodyname2}", "all", "dropped: a body not imported")
            continue
        pairs.append([a, b, "MJCF <contact><exclude>"])
    if pairs:
        recipe["self_collision"] = {"allow": pairs}


def add_equalities(src, tree, recipe: dict, ledger) -> None:
    m = src.model
    eqs = list(src.spec.equalities)
    for e in range(m.neq):
        t = int(m.eq_type[e])
        name = m.eq(e).name
        where = src.where(eqs[e]) if e < len(eqs) else src.where()
        a, b = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
        coef = [float(v) for v in m.eq_data[e][:5]]
        if t == 2 and b >= 0 and not any(coef[2:]) and bool(m.eq_active0[e]) and _one_dof(m, a, b):
            # MuJoCo couples the joints' moves from their refs: q1 - ref1 = c0 + c1 (q2 - ref2)
            coef[0] += float(m.qpos0[m.jnt_qposadr[a]]) - coef[1] * float(m.qpos0[m.jnt_qposadr[b]])
            actuated = set(recipe.get("actuators", {}))
            child, leader = tree.joint_map[a][0], tree.joint_map[b][0]
            if child in actuated and leader not in actuated and coef[1]:  # the driven joint leads
                child, leader, coef = leader, child, [-coef[0] / coef[1], 1 / coef[1]]
            if child not in actuated and "mimic" not in tree.joints[leader]:
                mimic = {"joint": leader}
                if coef[1] != 1:
                    mimic["multiplier"] = coef[1]
                if coef[0]:
                    mimic["offset"] = coef[0]
                tree.joints[child]["mimic"] = mimic
                tree.mimics[e] = (child, leader)
                if not np.allclose(m.eq_solref[e], SOLREF) or not np.allclose(m.eq_solimp[e], SOLIMP):
                    ledger.add(where, f"equality joint '{name}'" if name else f"equality joint #{e}", "all",
                               f"a mimic joint: solref {_numbers(m.eq_solref[e])}, solimp {_numbers(m.eq_solimp[e])} "
                               "dropped: the rebuilt MJCF has MuJoCo's defaults (the recipe has no constraint softness)")
                continue
        # the others are kept verbatim if they can be (robotkit.importer.mjcf.verbatim), on the ledger


def _one_dof(m, a: int, b: int) -> bool:
    return all(int(m.jnt_type[j]) in (HINGE, SLIDE) for j in (a, b))


def ledger_rest(src, tree, ledger) -> None:
    """What the recipe has no key for, one line each."""
    spec, m = src.spec, src.model
    # tendons, sensors and custom data: robotkit.importer.mjcf.verbatim
    for kind, what in (("camera", "camera"), ("light", "light"), ("flex", "flex"), ("skin", "skin"),
                       ("pair", "contact pair"), ("hfield", "height field")):
        for e in getattr(spec, "flexes" if kind == "flex" else kind + "s", []):
            label = f"{what} '{e.name}'" if e.name else what
            ledger.add(src.where(e), label, "all", f"dropped: the recipe has no {what}s")
    for j in range(m.njnt):
        softness = _softness(m, j)
        if softness:
            ledger.add(src.where_named("joint", m.joint(j).name), f"joint '{m.joint(j).name}'", "all",
                       f"{softness} dropped: the rebuilt MJCF has MuJoCo's defaults (the recipe has no constraint "
                       "softness)")
        if m.jnt_stiffness[j]:
            ledger.add(src.where_named("joint", m.joint(j).name), f"joint '{m.joint(j).name}'", "all",
                       f"spring dropped (stiffness {float(m.jnt_stiffness[j]):g}): the recipe has no joint springs")
        if int(m.jnt_type[j]) == BALL:
            ledger.add(src.where_named("joint", m.joint(j).name), f"joint '{m.joint(j).name}' (ball)", "all",
                       "approximated: three revolute joints about the body's x, y, z through two "
                       + _ball_links(tree, int(m.jnt_bodyid[j])) + "; "
                       "its armature, damping and friction act on each angle, not on the angular velocity"
                       + (" (its cone limit as each angle's range)" if m.jnt_limited[j] else ""))
    _bodies(src, ledger)


def _bodies(src, ledger) -> None:
    """A mocap body (the recipe's link is fixed), a body's gravity compensation (``gravcomp``)
    and a joint's through its actuators (``actuatorgravcomp``): the recipe has none of them (the
    build's tuner alone sets gravity compensation)."""
    m = src.model
    for b in range(1, m.nbody):
        if m.body_mocapid[b] >= 0:
            ledger.add(src.where_named("body", m.body(b).name), f"body '{m.body(b).name}' (mocap)", "all",
                       "mocap dropped: a link fixed where the file puts it (the recipe has no mocap bodies)")
        if m.body_gravcomp[b]:
            ledger.add(src.where_named("body", m.body(b).name), f"body '{m.body(b).name}'", "all",
                       f"gravity compensation dropped (gravcomp {float(m.body_gravcomp[b]):g}): the recipe has no "
                       "gravity compensation")
    for j in range(m.njnt):
        if m.jnt_actgravcomp[j]:
            ledger.add(src.where_named("joint", m.joint(j).name), f"joint '{m.joint(j).name}'", "all",
                       "gravity compensation through its actuators dropped (actuatorgravcomp): the recipe has no "
                       "gravity compensation")


def _ball_links(tree, b: int) -> str:
    """The two links a ball joint's three revolute joints go through (robotkit.importer.mjcf.chainmass)."""
    links = tree.chains.get(b, ([], []))[0]
    if links and all(n in tree.moved for n in links):
        return "links, each a point mass taken from the body at the ball's centre (the dynamics unchanged)"
    return "massless links"


SOLREF, SOLIMP = (0.02, 1.0), (0.9, 0.95, 0.001, 0.5, 2.0)
"""MuJoCo's default constraint softness, which the rebuilt MJCF has."""


def _softness(m, j: int) -> str:
    """A hinge's or slide's limit and friction-loss softness that is not MuJoCo's default ('' if none)."""
    if int(m.jnt_type[j]) not in (HINGE, SLIDE):
        return ""
    d, out = int(m.jnt_dofadr[j]), []
    if m.jnt_limited[j]:
        if not np.allclose(m.jnt_solref[j], SOLREF) or not np.allclose(m.jnt_solimp[j], SOLIMP):
            out.append(f"solreflimit {_numbers(m.jnt_solref[j])}, solimplimit {_numbers(m.jnt_solimp[j])}")
        if m.jnt_margin[j]:
            out.append(f"margin {float(m.jnt_margin[j]):g}")
    if m.dof_frictionloss[d] and (not np.allclose(m.dof_solref[d], SOLREF) or not np.allclose(m.dof_solimp[d], SOLIMP)):
        out.append(f"solreffriction {_numbers(m.dof_solref[d])}, solimpfriction {_numbers(m.dof_solimp[d])}")
    return "; ".join(out)


def _numbers(values) -> str:
    return " ".join(f"{float(x):g}" for x in values)
