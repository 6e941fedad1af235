"""The import proved by behaviour: the rebuilt MJCF against the original, both in MuJoCo.

At the original's keyframes, its zero configuration and :data:`SAMPLES` seeded random ones
(joints within their ranges, unlimited hinges within a turn, free and ball joints at random
orientations), each configuration set on both models (a ball joint as its three angles), and
compared: every original body's mass, centre of mass, inertia tensor (world axes) and frame
pose (with the point masses its chain's links took from it: robotkit.importer.mjcf.chainmass),
and every site's pose (its frame link's: :mod:`robotkit.importer.mjcf.sites`); the total mass
(the point masses added to chain links apart, on the ledger); the joint-space mass matrix
(``mj_fullM``, armature apart) and the bias forces at rest (gravity), the rebuilt ones mapped to
the original's velocities, and the bias forces at random joint velocities (Coriolis and
centrifugal forces too); the same mass matrix and gravity forces from the rebuilt URDF in
Pinocchio (:mod:`robotkit.importer.mjcf.pinocchio_mass`: joints matched by name); each hinge's
and slide's armature; each kept actuator's types, gain, bias and gear, and the actuator count;
each joint equality kept as a mimic joint, and the equality count; what ``mjcf_extras`` keeps
verbatim (:mod:`robotkit.importer.mjcf.verify_verbatim`: tendons' lengths, sensors' readings,
loops' anchors and couplings at every configuration, actuators, constraints); and a rollout of
0.5 s from each keyframe under one control sequence (:mod:`robotkit.importer.mjcf.rollout`; none
for a model with a ball joint, which says so).  Tolerances (:data:`TOL`): relative to the
largest value of the same kind, plus an absolute floor for lengths."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robotkit import mj
from robotkit.emit.layout import URDF, output_path
from robotkit.importer.mjcf.pinocchio_mass import PinocchioModel
from robotkit.importer.mjcf.rollout import rollouts
from robotkit.importer.mjcf.state import mapped, velocity_map
from robotkit.importer.mjcf import verify_verbatim

SAMPLES = 20
SEED = 0
TOL = {"mass": 1e-9, "pose": 1e-9, "inertia": 1e-9, "matrix": 1e-6, "bias": 1e-6, "pinocchio": 1e-6,
       "actuator": 1e-9, "equality": 1e-9, "tendon": 1e-9, "sensor": 1e-6, "rollout": 1e-4}
"""Relative tolerances (pose, tendon and rollout: metres and rotation-matrix entries, absolute).
The matrices' are looser: a chain link that cannot take its mass from its body carries an added
millionth of the lightest body's (on the ledger); the rollout's, as that millionth and the
solver's own tolerance grow over 0.5 s."""
FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3


@dataclass
class Verdict:
    configurations: int = 0
    worst: dict = field(default_factory=dict)  # quantity -> (relative error, where)
    failures: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    rollouts: int = 0

    @property
    def ok(self) -> bool:
        return not self.failures

    def lines(self) -> list[str]:
        head = (f"verified in MuJoCo against the original at {self.configurations} configurations and "
                f"{self.rollouts} rollout{'s' if self.rollouts != 1 else ''}: "
                + ("every quantity agrees" if self.ok else f"{len(self.failures)} disagreements"))
        worst = ", ".join(f"{k} {v[0]:.1e} (tol {TOL[k]:g})" for k, v in self.worst.items())
        return ([head, "  largest differences: " + worst] + [f"  DIFFERS: {f}" for f in self.failures[:20]]
                + [f"  note: {n}" for n in self.notes])


def verify(src, tree, rebuilt_path) -> Verdict:
    mujoco = mj.load()
    om, rm = src.model, mujoco.MjModel.from_xml_path(str(rebuilt_path))
    rm.opt.gravity[:] = om.opt.gravity  # the original's (a gravity the rebuild lacks is on the ledger)
    od, rd = mujoco.MjData(om), mujoco.MjData(rm)
    verdict = Verdict(worst={k: (0.0, "") for k in TOL})
    configs = _configurations(om)
    chain = sum(float(rm.body_mass[rm.body(n).id]) for n in tree.chain_links if n not in tree.moved)
    total_o, total_r = float(om.body_mass.sum()), float(rm.body_mass.sum()) - chain
    _check(verdict, "mass", abs(total_o - total_r) / total_o if total_o else 0.0, "total mass")
    urdf = Path(rebuilt_path).parent.parent / output_path(URDF, Path(rebuilt_path).stem)
    pin = _pinocchio(verdict, om, tree, urdf)
    rng = np.random.default_rng(SEED + 1)
    check = lambda kind, err, where: _check(verdict, kind, err, where)  # noqa: E731
    for label, q in configs:
        T = _at(mujoco, om, od, rm, rd, tree, q)
        _bodies(verdict, om, od, rm, rd, tree, label)
        _sites(verdict, od, rm, rd, tree, label)
        verify_verbatim.at_configuration(check, om, od, rm, rd, tree, label)
        _dynamics(verdict, mujoco, om, od, rm, rd, T, label)
        if pin is not None:
            _in_pinocchio(verdict, pin, om, od, rm, rd, T, label)
        _moving_bias(verdict, mujoco, om, od, rm, rd, T, rng, label)
    verdict.configurations = len(configs)
    kept = _actuators(verdict, om, rm, tree) | verify_verbatim.actuators(check, om, rm, tree)
    equalities = _equalities(verdict, om, rm, tree) | verify_verbatim.equalities(check, om, rm, tree)
    verify_verbatim.counts(check, om, rm, tree)
    balls = [om.joint(j).name for j in range(om.njnt) if int(om.jnt_type[j]) == BALL]
    if balls:  # Cassie's achilles rods part by 4e-6 m in 5 ms, 1 m in 0.5 s: the approximation, not a defect
        verdict.notes.append(f"no rollout: ball joint '{balls[0]}' is three revolute joints through chain links "
                             "in the rebuild (approximated, on the ledger), whose motion parts from the ball's")
        return verdict
    for label, err, where, note in rollouts(mujoco, om, rm, tree, kept, equalities):
        _check(verdict, "rollout", err, f"{label}: {where}" if where else label)
        if note:  # the original's own instability (Spot's arm under random controls, in free fall)
            verdict.notes.append(f"{label}: {note}")
    verdict.rollouts = max(om.nkey, 1)
    return verdict


def _at(mujoco, om, od, rm, rd, tree, q) -> np.ndarray:
    """Both models at rest at the original's configuration ``q``; the velocity map there."""
    od.qpos[:] = q
    rd.qpos[:] = mapped(om, rm, tree, q)
    for model, data in ((om, od), (rm, rd)):
        data.qvel[:] = 0
        mujoco.mj_forward(model, data)
    return velocity_map(om, rm, tree, q)


def _pinocchio(verdict: Verdict, om, tree, urdf):
    """The rebuilt URDF in Pinocchio, or None (not installed, or refused: a disagreement)."""
    try:
        model = PinocchioModel(urdf, tree.base == "free")
    except ImportError:
        verdict.notes.append("Pinocchio is not installed: the URDF's mass matrix not compared")
        return None
    except (ValueError, RuntimeError) as exc:
        verdict.failures.append(f"Pinocchio refuses the rebuilt URDF: {' '.join(str(exc).split())[:200]}")
        return None
    model.model.gravity.linear = np.array(om.opt.gravity)
    return model


def _in_pinocchio(verdict: Verdict, pin, om, od, rm, rd, T, label: str) -> None:
    Mp, gp, P = pin.matrices(rm, rd.qpos)
    A = T @ P  # Pinocchio's velocities to the original's
    Mo = np.zeros((om.nv, om.nv))
    mj.load().mj_fullM(om, od, Mo)
    expect = A.T @ (Mo - np.diag(om.dof_armature)) @ A
    _check(verdict, "pinocchio", float(np.abs(expect - Mp).max() / max(np.abs(expect).max(), 1e-300)),
           f"URDF mass matrix in Pinocchio at {label}")
    go = A.T @ od.qfrc_bias
    _check(verdict, "pinocchio", float(np.abs(go - gp).max() / max(np.abs(go).max(), force_floor(om))),
           f"URDF gravity forces in Pinocchio at {label}")


def _moving_bias(verdict: Verdict, mujoco, om, od, rm, rd, T, rng, label: str) -> None:
    """The bias forces (Coriolis, centrifugal and gravity) at random joint velocities (a ball
    joint's at zero: its three angles' velocity map changes with them)."""
    free = [r for r in range(rm.nv) if np.count_nonzero(T[:, r]) == 1 and
            om.jnt_type[om.dof_jntid[int(np.flatnonzero(T[:, r])[0])]] != BALL]
    vr = np.zeros(rm.nv)
    vr[free] = rng.uniform(-1, 1, len(free))
    for model, data, v in ((om, od, T @ vr), (rm, rd, vr)):
        data.qvel[:] = v
        mujoco.mj_forward(model, data)
    go, gr = T.T @ od.qfrc_bias, rd.qfrc_bias
    _check(verdict, "bias", float(np.abs(go - gr).max() / max(np.abs(go).max(), force_floor(om))),
           f"bias forces at {label} (random velocities)")


def _actuators(verdict: Verdict, om, rm, tree) -> dict[int, int]:
    """Each original actuator the recipe kept (:attr:`Tree.actuated`; the others are on the
    ledger): the rebuilt one on its joint has its types (gain, bias, dynamics), gain, bias and gear
    (a motor's gear is in its control, which the ledger says); the rebuilt model has no other.
    {original actuator: rebuilt actuator}."""
    verbatim = set(tree.verbatim.get("actuator", {}).values())
    rebuilt = {rm.joint(int(rm.actuator_trnid[a][0])).name: a for a in range(rm.nu)
               if rm.actuator_trntype[a] == 0 and rm.actuator(a).name not in verbatim}
    kept = {}
    for a, joint in tree.actuated.items():
        where = f"actuator '{om.actuator(a).name}'" if om.actuator(a).name else f"actuator #{a}"
        r = rebuilt.get(joint)
        if r is None:
            _check(verdict, "actuator", 1.0, f"{where} missing from the rebuild")
            continue
        kept[a] = r
        types = [(int(m.actuator_gaintype[i]), int(m.actuator_biastype[i]), int(m.actuator_dyntype[i]))
                 for m, i in ((om, a), (rm, r))]
        _check(verdict, "actuator", float(types[0] != types[1]), f"{where} gain, bias and dynamics types")
        motor = types[0][1] == 0
        mine, theirs = (np.concatenate([m.actuator_gainprm[i][:3], m.actuator_biasprm[i][:3],
                                        [1.0 if motor else m.actuator_gear[i][0]]]) for m, i in ((om, a), (rm, r)))
        err = float(np.abs(mine - theirs).max() / max(np.abs(mine).max(), 1e-300))
        _check(verdict, "actuator", err, f"{where} gain, bias and gear")
    count = len(tree.actuated) + len(verbatim)
    _check(verdict, "actuator", float(rm.nu != count), f"actuator count: {rm.nu} rebuilt, {count} kept of the original's {om.nu}")
    return kept


def _equalities(verdict: Verdict, om, rm, tree) -> set[int]:
    """Each original joint equality the recipe kept as a mimic joint (:attr:`Tree.mimics`; the
    others are on the ledger): a rebuilt joint equality couples the same joints by the same line
    (mimic = offset + multiplier x leader, the original's possibly turned round); the rebuilt
    model has no other equality.  The original's kept equalities."""
    rebuilt, verbatim = {}, set(tree.verbatim.get("equality", {}).values())
    for e in range(rm.neq):
        if int(rm.eq_type[e]) == 2 and int(rm.eq_obj2id[e]) >= 0 and rm.eq(e).name not in verbatim:
            rebuilt[(rm.joint(int(rm.eq_obj1id[e])).name, rm.joint(int(rm.eq_obj2id[e])).name)] = _line(rm, e)
    for e, (child, leader) in tree.mimics.items():
        where = f"equality '{om.eq(e).name}'" if om.eq(e).name else f"equality #{e}"
        if (child, leader) not in rebuilt:
            _check(verdict, "equality", 1.0, f"{where} missing from the rebuild")
            continue
        c0, c1 = _line(om, e)
        if tree.joint_map[int(om.eq_obj1id[e])][0] != child:  # turned round: the driven joint leads
            c0, c1 = -c0 / c1, 1 / c1
        r0, r1 = rebuilt[(child, leader)]
        _check(verdict, "equality", max(abs(c0 - r0), abs(c1 - r1)) / max(abs(c0), abs(c1), 1e-300),
               f"{where} coupling")
    count = len(tree.mimics) + len(verbatim)
    _check(verdict, "equality", float(rm.neq != count), f"equality count: {rm.neq} rebuilt, {count} kept of the original's {om.neq}")
    return set(tree.mimics)


def _line(m, e: int) -> tuple[float, float]:
    """Joint equality ``e`` as the line q1 = c0 + c1 q2 in the joints' values: MuJoCo couples
    their moves from their refs (q1 - ref1 = a0 + a1 (q2 - ref2))."""
    a0, a1 = (float(v) for v in m.eq_data[e][:2])
    ref1, ref2 = (float(m.qpos0[m.jnt_qposadr[int(j)]]) for j in (m.eq_obj1id[e], m.eq_obj2id[e]))
    return a0 + ref1 - a1 * ref2, a1


def force_floor(m) -> float:
    """The least force scale that gravity and bias forces are compared against: a thousandth of
    the model's weight times its extent (in N m; N for a slide).  Where the forces vanish (a
    joint whose axis is vertical, a link balanced on its joint) both models give rounding noise,
    1e-16 N m, which a relative comparison alone would count as a disagreement."""
    weight = float(np.sum(m.body_mass)) * max(float(np.linalg.norm(m.opt.gravity)), 1.0)
    return max(1e-3 * weight * max(float(m.stat.extent), 1e-3), 1e-12)


def _check(verdict: Verdict, kind: str, err: float, where: str) -> None:
    if err > verdict.worst[kind][0]:
        verdict.worst[kind] = (err, where)
    if err > TOL[kind]:
        verdict.failures.append(f"{where}: {kind} off by {err:.2e} (tolerance {TOL[kind]:g})")


def _configurations(m) -> list[tuple[str, np.ndarray]]:
    rng = np.random.default_rng(SEED)
    out = [(f"keyframe '{m.key(k).name or k}'", np.array(m.key_qpos[k])) for k in range(m.nkey)]
    out.append(("the zero configuration", np.array(m.qpos0)))
    for i in range(SAMPLES):
        q = np.array(m.qpos0)
        for j in range(m.njnt):
            adr, t = int(m.jnt_qposadr[j]), int(m.jnt_type[j])
            if t in (HINGE, SLIDE):
                lo, hi = m.jnt_range[j] if m.jnt_limited[j] else ((-np.pi, np.pi) if t == HINGE else (-1.0, 1.0))
                q[adr] = rng.uniform(lo, hi)
            else:
                quat = rng.normal(size=4)
                q[adr + (3 if t == FREE else 0):adr + (7 if t == FREE else 4)] = quat / np.linalg.norm(quat)
                if t == FREE:
                    q[adr:adr + 3] = rng.uniform(-1, 1, 3)
        out.append((f"random configuration {i + 1}", q))
    return out


def _bodies(verdict, om, od, rm, rd, tree, label: str) -> None:
    """Each original body against its link with the point masses its chain links took from it
    (robotkit.importer.mjcf.chainmass), all where they are at this configuration."""
    carried: dict[int, list[int]] = {}
    for link, b in tree.moved.items():
        carried.setdefault(b, []).append(rm.body(link).id)
    for b in range(1, om.nbody):
        name = tree.link_of[b]
        r = rm.body(name).id
        where = f"body '{name}' at {label}"
        mo, Io = float(om.body_mass[b]), _world_inertia(om.body_inertia[b], od.ximat[b])
        mr, cr, Ir = _composite(rm, rd, [r, *carried.get(b, [])])
        _check(verdict, "mass", abs(mo - mr) / max(mo, 1e-300) if mo else mr, where)
        frame = od.xpos[b] + od.xmat[b].reshape(3, 3) @ tree.offset[b]
        pose = max(np.abs(frame - rd.xpos[r]).max(), np.abs(od.xmat[b] - rd.xmat[r]).max(),
                   np.abs(od.xipos[b] - cr).max() if mo else 0.0)
        _check(verdict, "pose", float(pose), where)
        if mo:
            _check(verdict, "inertia", float(np.abs(Io - Ir).max() / max(np.abs(Io).max(), 1e-300)), where)


def _sites(verdict, od, rm, rd, tree, label: str) -> None:
    """Each site's pose against its frame link's (a body without mass in the rebuilt MJCF)."""
    for s, name in tree.sites.items():
        r = rm.body(name).id
        pose = max(np.abs(od.site_xpos[s] - rd.xpos[r]).max(), np.abs(od.site_xmat[s] - rd.xmat[r]).max())
        _check(verdict, "pose", float(pose), f"site '{name}' at {label}")


def _composite(m, d, ids: list[int]) -> tuple[float, np.ndarray, np.ndarray]:
    """(mass, centre of mass, inertia about it in world axes) of bodies ``ids`` together."""
    mass = float(sum(m.body_mass[i] for i in ids))
    if len(ids) == 1 or not mass:
        return mass, np.array(d.xipos[ids[0]]), _world_inertia(m.body_inertia[ids[0]], d.ximat[ids[0]])
    com = sum(float(m.body_mass[i]) * d.xipos[i] for i in ids) / mass
    inertia = np.zeros((3, 3))
    for i in ids:
        r = d.xipos[i] - com
        inertia += _world_inertia(m.body_inertia[i], d.ximat[i]) + m.body_mass[i] * (r @ r * np.eye(3) - np.outer(r, r))
    return mass, com, inertia


def _world_inertia(moments, ximat) -> np.ndarray:
    R = np.asarray(ximat).reshape(3, 3)
    return R @ np.diag(moments) @ R.T


def _dynamics(verdict, mujoco, om, od, rm, rd, T, label: str) -> None:
    """The rigid-body mass matrix (armature apart: a ball joint's acts on its angular velocity, the
    three joints' on their angles, which the ledger says) and the gravity forces, and the armature
    of every other joint."""
    Mo, Mr = np.zeros((om.nv, om.nv)), np.zeros((rm.nv, rm.nv))
    mujoco.mj_fullM(om, od, Mo)
    mujoco.mj_fullM(rm, rd, Mr)
    Mo -= np.diag(om.dof_armature)
    Mr -= np.diag(rm.dof_armature)
    expect = T.T @ Mo @ T
    scale = max(np.abs(expect).max(), 1e-300)
    _check(verdict, "matrix", float(np.abs(expect - Mr).max() / scale), f"mass matrix at {label}")
    go, gr = T.T @ od.qfrc_bias, rd.qfrc_bias
    _check(verdict, "matrix", float(np.abs(go - gr).max() / max(np.abs(go).max(), force_floor(om))),
           f"gravity forces at {label}")
    single = [(i, r) for i in range(om.nv) for r in np.flatnonzero(T[i]) if np.count_nonzero(T[:, r]) == 1
              and np.count_nonzero(T[i]) == 1 and om.jnt_type[om.dof_jntid[i]] in (SLIDE, HINGE)]
    for i, r in single:
        scale = max(float(om.dof_armature[i]), 1e-300)
        _check(verdict, "matrix", abs(float(om.dof_armature[i] - rm.dof_armature[r])) / scale if om.dof_armature[i]
               else float(rm.dof_armature[r]), f"armature of joint '{om.joint(int(om.dof_jntid[i])).name}'")
