"""The rollout of the verification: from each keyframe of the original (its zero configuration
when it has none), :data:`SECONDS` of simulation of the original and of the rebuilt MJCF under
the same control sequence (each kept actuator's control drawn within the original's
``ctrlrange`` and the rebuilt's, which the ledger says may be narrowed to its joint's range,
held for :data:`HOLD` s; a motor whose gear the recipe moved into its control gets the control
times that gear), every original body's frame compared with its link's at the end of every
hold.

What is on the ledger is taken out of both first, so that the rollout compares everything
else: the rebuilt model runs with the original's simulation options (timestep, integrator,
gravity...); the original's dropped equality constraints are off (the mimic
joints have the rebuilt's softness; those kept verbatim in ``mjcf_extras`` act in both as
written), its dropped tendons and its joint springs have no stiffness, damping or friction, its
bodies and joints no gravity compensation, its joints' limits and friction loss have the
rebuilt's softness, and its dropped actuators no force (those kept verbatim get the same
control in both).  A model with a ball joint has no rollout: the three joints through chain
links part from the ball (:func:`robotkit.importer.mjcf.verify.verify` says so).  Contacts are
off in both: the robot alone has no floor, and the contact parameters the recipe cannot hold
are on the ledger; so is the medium (fluid density, viscosity, wind: the rebuild has none, and
its forces act on each body's equivalent inertia box, which a body's joint chain splits)."""

from __future__ import annotations

import copy

import numpy as np

from robotkit.importer.mjcf.state import mapped, velocity_map

SECONDS = 0.5
HOLD = 0.1
SEED = 1
FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3


def rollouts(mujoco, om, rm, tree, kept: dict[int, int], equalities: set[int]):
    """(label, largest frame difference over the rollout, where, a note or '') for each start."""
    om, rm = _neutralised(mujoco, om, rm, tree, kept, equalities)
    starts = [(f"keyframe '{om.key(k).name or k}'", np.array(om.key_qpos[k]), np.array(om.key_qvel[k]))
              for k in range(om.nkey)] or [("the zero configuration", np.array(om.qpos0), np.zeros(om.nv))]
    rng = np.random.default_rng(SEED)
    out = []
    for label, q, v in starts:
        controls = _controls(om, rm, kept, rng)
        out.append((f"rollout from {label}",) + _run(mujoco, om, rm, tree, q, v, controls))
    return out


def _neutralised(mujoco, om, rm, tree, kept: dict[int, int], equalities: set[int]):
    om, rm = copy.deepcopy(om), copy.deepcopy(rm)
    for name in dir(om.opt):  # every simulation option (the ledger lists those the rebuild lacks)
        value = getattr(om.opt, name)
        if not name.startswith("_") and not callable(value):
            setattr(rm.opt, name, copy.copy(value))
    for m in (om, rm):
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        m.opt.density, m.opt.viscosity, m.opt.wind[:] = 0.0, 0.0, 0.0  # no medium: see the module docstring
    rebuilt_eq = {(rm.joint(int(rm.eq_obj1id[e])).name, rm.joint(int(rm.eq_obj2id[e])).name): e
                  for e in range(rm.neq) if int(rm.eq_type[e]) == 2 and int(rm.eq_obj2id[e]) >= 0}
    for e in range(om.neq):
        if e not in equalities:
            om.eq_active0[e] = 0
        elif e in tree.mimics and tree.mimics[e] in rebuilt_eq:  # its softness: the rebuilt's (MuJoCo's defaults)
            r = rebuilt_eq[tree.mimics[e]]
            om.eq_solref[e], om.eq_solimp[e] = rm.eq_solref[r], rm.eq_solimp[r]
    om.jnt_stiffness[:] = 0
    om.body_gravcomp[:], om.jnt_actgravcomp[:] = 0, 0  # the recipe has no gravity compensation (on the ledger)
    for j, names in tree.joint_map.items():  # limit and friction softness: the rebuilt's (MuJoCo's defaults)
        if int(om.jnt_type[j]) in (SLIDE, HINGE):
            r = rm.joint(names[0]).id
            d, e = int(om.jnt_dofadr[j]), int(rm.jnt_dofadr[r])
            om.jnt_solref[j], om.jnt_solimp[j], om.jnt_margin[j] = rm.jnt_solref[r], rm.jnt_solimp[r], rm.jnt_margin[r]
            om.dof_solref[d], om.dof_solimp[d] = rm.dof_solref[e], rm.dof_solimp[e]
    dropped = [t for t in range(om.ntendon) if t not in tree.verbatim.get("tendon", {})]  # the others are verbatim
    for field in ("tendon_stiffness", "tendon_damping", "tendon_frictionloss", "tendon_limited"):
        if hasattr(om, field):
            getattr(om, field)[dropped] = 0
    for a in range(om.nu):
        if a not in kept:
            om.actuator_gainprm[a][:] = 0
            om.actuator_biasprm[a][:] = 0
    return om, rm


def _controls(om, rm, kept: dict[int, int], rng) -> list[tuple[np.ndarray, np.ndarray]]:
    """(original ctrl, rebuilt ctrl) for each hold."""
    out = []
    for _ in range(int(round(SECONDS / HOLD))):
        uo, ur = np.zeros(om.nu), np.zeros(rm.nu)
        for a, r in kept.items():
            lo, hi = om.actuator_ctrlrange[a] if om.actuator_ctrllimited[a] else (-1.0, 1.0)
            motor = int(om.actuator_biastype[a]) == 0
            same = om.actuator_gear[a][0] == rm.actuator_gear[r][0]  # a verbatim actuator's (its gear may be 0)
            if rm.actuator_ctrllimited[r] and (same or not motor):  # a ctrlrange narrowed to the joint's range
                lo, hi = max(lo, rm.actuator_ctrlrange[r][0]), min(hi, rm.actuator_ctrlrange[r][1])  # (on the ledger)
                if lo > hi:
                    lo, hi = om.actuator_ctrlrange[a]
            uo[a] = rng.uniform(lo, hi)
            ur[r] = uo[a] * float(om.actuator_gear[a][0]) / float(rm.actuator_gear[r][0]) if motor and not same else uo[a]
        out.append((uo, ur))
    return out


def _run(mujoco, om, rm, tree, q, v, controls) -> tuple[float, str, str]:
    """(largest frame difference, where, a note): compared until the original turns unstable, if
    it does (MuJoCo resets it: what follows compares a restart; the note says when)."""
    od, rd = mujoco.MjData(om), mujoco.MjData(rm)
    od.qpos[:], od.qvel[:] = q, v
    rd.qpos[:] = mapped(om, rm, tree, q)
    rd.qvel[:] = np.linalg.lstsq(velocity_map(om, rm, tree, q), v, rcond=None)[0]
    mujoco.mj_forward(om, od)
    mujoco.mj_forward(rm, rd)
    bodies = [(b, rm.body(tree.link_of[b]).id, tree.offset[b]) for b in range(1, om.nbody)]
    steps = max(1, int(round(HOLD / om.opt.timestep)))
    unstable = int(mujoco.mjtWarning.mjWARN_BADQACC)
    worst, where = 0.0, ""
    for k, (uo, ur) in enumerate(controls):
        od.ctrl[:], rd.ctrl[:] = uo, ur
        for i in range(steps):
            mujoco.mj_step(om, od)
            if od.warning[unstable].number:
                t = (k * steps + i) * om.opt.timestep  # as MuJoCo reports it
                return worst, where, (f"the original turns unstable at {t:.3f} s under this control sequence "
                                      "(MuJoCo resets it): compared until the hold before")
            mujoco.mj_step(rm, rd)
        for b, r, offset in bodies:
            frame = od.xpos[b] + od.xmat[b].reshape(3, 3) @ offset
            err = max(np.abs(frame - rd.xpos[r]).max(), np.abs(od.xmat[b] - rd.xmat[r]).max())
            if err > worst:
                worst, where = float(err), f"body '{tree.link_of[b]}' at {(k + 1) * steps * om.opt.timestep:.2f} s"
    return worst, where, ""
