"""The import proved by behaviour: the rebuilt MJCF against the original, both in MuJoCo.

At the original's keyframes, its zero configuration and :data:`SAMPLES` seeded random ones
(joints within their ranges, unlimited hinges within a turn, free and ball joints at random
orientations), each configuration set on both models (a ball joint as its three angles), and
compared: every original body's mass, centre of mass, inertia tensor (world axes) and frame
pose; the total mass (the point masses of joint chains' links apart); the joint-space mass
matrix (``mj_fullM``, armature apart) and the bias forces at rest (gravity), the rebuilt ones
mapped to the original's velocities; each hinge's and slide's armature; each kept actuator's
gain and bias (kp, kv).  Tolerances (:data:`TOL`):
relative to the largest value of the same kind, plus an absolute floor for lengths."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from robotkit import mj
from robotkit.importer.mjcf.extras import ball_angles

SAMPLES = 20
SEED = 0
TOL = {"mass": 1e-9, "pose": 1e-9, "inertia": 1e-9, "matrix": 1e-6, "actuator": 1e-9}
"""Relative tolerances (pose: metres and rotation-matrix entries, absolute). The mass matrix's is
looser: the massless links of joint chains carry a millionth of the lightest body's mass."""
FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3


@dataclass
class Verdict:
    configurations: int = 0
    worst: dict = field(default_factory=dict)  # quantity -> (relative error, where)
    failures: list = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.failures

    def lines(self) -> list[str]:
        head = (f"verified in MuJoCo against the original at {self.configurations} configurations: "
                + ("every quantity agrees" if self.ok else f"{len(self.failures)} disagreements"))
        worst = ", ".join(f"{k} {v[0]:.1e} (tol {TOL[k]:g})" for k, v in self.worst.items())
        return [head, "  largest differences: " + worst] + [f"  DIFFERS: {f}" for f in self.failures[:20]]


def verify(src, tree, rebuilt_path) -> Verdict:
    mujoco = mj.load()
    om, rm = src.model, mujoco.MjModel.from_xml_path(str(rebuilt_path))
    od, rd = mujoco.MjData(om), mujoco.MjData(rm)
    verdict = Verdict(worst={k: (0.0, "") for k in TOL})
    configs = _configurations(om)
    chain = sum(float(rm.body_mass[rm.body(n).id]) for n in tree.chain_links)
    total_o, total_r = float(om.body_mass.sum()), float(rm.body_mass.sum()) - chain
    _check(verdict, "mass", abs(total_o - total_r) / total_o if total_o else 0.0, "total mass")
    T = None
    for label, q in configs:
        od.qpos[:] = q
        rd.qpos[:] = _mapped(om, rm, tree, q)
        for model, data in ((om, od), (rm, rd)):
            data.qvel[:] = 0
            mujoco.mj_forward(model, data)
        _bodies(verdict, om, od, rm, rd, tree, label)
        T = _velocity_map(om, rm, tree, q)
        _dynamics(verdict, mujoco, om, od, rm, rd, T, label)
    verdict.configurations = len(configs)
    _actuators(verdict, om, rm, tree)
    return verdict


def _actuators(verdict: Verdict, om, rm, tree) -> None:
    """Each original actuator the recipe kept: the rebuilt one on its joint has its gain and bias."""
    rebuilt = {rm.joint(int(rm.actuator_trnid[a][0])).name: a for a in range(rm.nu) if rm.actuator_trntype[a] == 0}
    for a in range(om.nu):
        if om.actuator_trntype[a] != 0 or int(om.actuator_trnid[a][0]) not in tree.joint_map:
            continue
        r = rebuilt.get(tree.joint_map[int(om.actuator_trnid[a][0])][0])
        if r is None:
            continue  # not kept: on the ledger
        mine = np.concatenate([om.actuator_gainprm[a][:3], om.actuator_biasprm[a][:3]])
        theirs = np.concatenate([rm.actuator_gainprm[r][:3], rm.actuator_biasprm[r][:3]])
        err = float(np.abs(mine - theirs).max() / max(np.abs(mine).max(), 1e-300))
        _check(verdict, "actuator", err, f"actuator '{om.actuator(a).name or a}' gain and bias")


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


def _mapped(om, rm, tree, q) -> np.ndarray:
    """The rebuilt model's qpos at the original's ``q`` (its chain joints at zero)."""
    out = np.array(rm.qpos0)
    for j, names in tree.joint_map.items():
        adr, t = int(om.jnt_qposadr[j]), int(om.jnt_type[j])
        radr = [int(rm.jnt_qposadr[rm.joint(n).id]) for n in names]
        if t == FREE:
            out[radr[0]:radr[0] + 7] = q[adr:adr + 7]
        elif t == BALL:
            for r, v in zip(radr, ball_angles(q[adr:adr + 4])):
                out[r] = v
        else:
            out[radr[0]] = q[adr]
    return out


def _bodies(verdict, om, od, rm, rd, tree, label: str) -> None:
    for b in range(1, om.nbody):
        name = tree.link_of[b]
        r = rm.body(name).id
        where = f"body '{name}' at {label}"
        mo, mr = float(om.body_mass[b]), float(rm.body_mass[r])
        _check(verdict, "mass", abs(mo - mr) / max(mo, 1e-300) if mo else mr, where)
        frame = od.xpos[b] + od.xmat[b].reshape(3, 3) @ tree.offset[b]
        pose = max(np.abs(frame - rd.xpos[r]).max(), np.abs(od.xmat[b] - rd.xmat[r]).max(),
                   np.abs(od.xipos[b] - rd.xipos[r]).max() if mo else 0.0)
        _check(verdict, "pose", float(pose), where)
        if mo:
            Io, Ir = (_world_inertia(m.body_inertia[i], d.ximat[i]) for m, d, i in ((om, od, b), (rm, rd, r)))
            _check(verdict, "inertia", float(np.abs(Io - Ir).max() / max(np.abs(Io).max(), 1e-300)), where)


def _world_inertia(moments, ximat) -> np.ndarray:
    R = np.asarray(ximat).reshape(3, 3)
    return R @ np.diag(moments) @ R.T


def _velocity_map(om, rm, tree, q) -> np.ndarray:
    """T with v_original = T v_rebuilt (a ball joint's angular velocity from its three angle rates)."""
    T = np.zeros((om.nv, rm.nv))
    for j, names in tree.joint_map.items():
        d, t = int(om.jnt_dofadr[j]), int(om.jnt_type[j])
        rdofs = [int(rm.jnt_dofadr[rm.joint(n).id]) for n in names]
        if t == FREE:
            T[d:d + 6, rdofs[0]:rdofs[0] + 6] = np.eye(6)
        elif t == BALL:
            adr = int(om.jnt_qposadr[j])
            _, b, c = ball_angles(q[adr:adr + 4])
            Rz, Ry = _rot(2, c), _rot(1, b)
            cols = [Rz.T @ Ry.T @ [1, 0, 0], Rz.T @ [0, 1, 0], np.array([0, 0, 1.0])]
            for k, col in enumerate(cols):
                T[d:d + 3, rdofs[k]] = col
        else:
            T[d, rdofs[0]] = 1.0
    return T


def _rot(axis: int, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    i, k = [(1, 2), (0, 2), (0, 1)][axis]
    R = np.eye(3)
    R[i, i], R[k, k] = c, c
    R[i, k], R[k, i] = (-s, s) if axis != 1 else (s, -s)
    return R


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
    scale = max(np.abs(go).max(), 1e-12)
    _check(verdict, "matrix", float(np.abs(go - gr).max() / scale), f"gravity forces at {label}")
    single = [(i, r) for i in range(om.nv) for r in np.flatnonzero(T[i]) if np.count_nonzero(T[:, r]) == 1
              and np.count_nonzero(T[i]) == 1 and om.jnt_type[om.dof_jntid[i]] in (SLIDE, HINGE)]
    for i, r in single:
        scale = max(float(om.dof_armature[i]), 1e-300)
        _check(verdict, "matrix", abs(float(om.dof_armature[i] - rm.dof_armature[r])) / scale if om.dof_armature[i]
               else float(rm.dof_armature[r]), f"armature of joint '{om.joint(int(om.dof_jntid[i])).name}'")
