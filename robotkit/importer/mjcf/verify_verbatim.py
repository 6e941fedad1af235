"""The verification of what the import kept verbatim (``mjcf_extras``:
:mod:`robotkit.importer.mjcf.verbatim`; ``tree.verbatim``: {kind: {original id: rebuilt name}}),
the rebuilt model against the original, both at the same configuration: each kept tendon's length;
each kept sensor's reading; each kept connect or weld constraint's two anchor points in the world
(the bodies' frames moved to their links' in the rebuild) and its relative orientation, each joint
or tendon coupling's coefficients; each kept actuator's types, gains, bias, dynamics, gear and
ranges; the counts.  ``check(kind, error, where)`` records each comparison."""

from __future__ import annotations

import numpy as np

from robotkit import mj

CONNECT, WELD, JOINT, TENDON = 0, 1, 2, 3
SITE = 6  # mjOBJ_SITE
ACC = 3  # mjSTAGE_ACC


def counts(check, om, rm, tree) -> None:
    kept = tree.verbatim.get("tendon", {})
    check("tendon", float(rm.ntendon != len(kept)),
          f"tendon count: {rm.ntendon} rebuilt, {len(kept)} kept of the original's {om.ntendon}")
    kept = tree.verbatim.get("sensor", {})
    imus = len(tree.kept_sensors)
    check("sensor", float(rm.nsensor != len(kept) + imus),
          f"sensor count: {rm.nsensor} rebuilt, {len(kept) + imus} kept of the original's {om.nsensor}")


def actuators(check, om, rm, tree) -> dict[int, int]:
    """Each verbatim actuator as the original's: {original id: rebuilt id}."""
    out = {}
    for a, name in tree.verbatim.get("actuator", {}).items():
        r = rm.actuator(name).id
        out[a] = r
        where = f"actuator '{om.actuator(a).name or name}'"
        types = [(int(m.actuator_trntype[i]), int(m.actuator_gaintype[i]), int(m.actuator_biastype[i]),
                  int(m.actuator_dyntype[i])) for m, i in ((om, a), (rm, r))]
        check("actuator", float(types[0] != types[1]), f"{where} transmission, gain, bias and dynamics types")
        mine, theirs = (np.concatenate([m.actuator_gainprm[i], m.actuator_biasprm[i], m.actuator_dynprm[i],
                                        m.actuator_gear[i], m.actuator_ctrlrange[i], m.actuator_forcerange[i]])
                        for m, i in ((om, a), (rm, r)))
        check("actuator", float(np.abs(mine - theirs).max() / max(np.abs(mine).max(), 1e-300)),
              f"{where} gains, bias, dynamics, gear and ranges")
    return out


def equalities(check, om, rm, tree) -> set[int]:
    """Each kept constraint's type, softness and state; the original's verbatim equalities."""
    kept = tree.verbatim.get("equality", {})
    for e, name in kept.items():
        r = rm.eq(name).id
        where = f"equality '{om.eq(e).name or name}'"
        same = [int(om.eq_type[e]) == int(rm.eq_type[r]), bool(om.eq_active0[e]) == bool(rm.eq_active0[r])]
        check("equality", float(not all(same)), f"{where} type and state")
        # a weld's torque scale with its softness (eq_data[10]: how its rotation counts)
        mine, theirs = (np.concatenate([m.eq_solref[i], m.eq_solimp[i], m.eq_data[i][10:11] * (m.eq_type[i] == WELD)])
                        for m, i in ((om, e), (rm, r)))
        check("equality", float(np.abs(mine - theirs).max() / max(np.abs(mine).max(), 1e-300)), f"{where} softness")
    return set(kept)


def at_configuration(check, om, od, rm, rd, tree, label: str) -> None:
    """The tendons' lengths, the sensors' readings and the loops' anchors, both models at rest at
    the same configuration (``mj_forward`` done)."""
    for t, name in tree.verbatim.get("tendon", {}).items():
        r = rm.tendon(name).id
        check("tendon", abs(float(od.ten_length[t]) - float(rd.ten_length[r])), f"tendon '{name}' length at {label}")
    _sensors(check, om, od, rm, rd, tree, label)
    for e, name in tree.verbatim.get("equality", {}).items():
        if int(om.eq_type[e]) in (CONNECT, WELD) and int(om.eq_objtype[e]) != SITE:
            r = rm.eq(name).id
            points = zip(_anchors(om, od, e), _anchors(rm, rd, r))  # a weld's orientation only if both have one
            err = max(np.abs(po - pr).max() for po, pr in points)
            check("pose", float(err), f"equality '{om.eq(e).name or name}' anchors at {label}")
        elif int(om.eq_type[e]) in (JOINT, TENDON):
            r = rm.eq(name).id
            check("equality", abs(_coupling(om, od, e) - _coupling(rm, rd, r)),
                  f"equality '{om.eq(e).name or name}' coupling at {label}")


def _sensors(check, om, od, rm, rd, tree, label: str) -> None:
    """Each kept sensor's reading; those of the acceleration stage (touch, force, accelerometer...)
    with contacts off in both, as the rollout has them (the contact parameters the recipe cannot
    hold are on the ledger)."""
    sensors = tree.verbatim.get("sensor", {})
    if any(int(om.sensor_needstage[s]) == ACC for s in sensors):
        mujoco = mj.load()
        flags = int(om.opt.disableflags), int(rm.opt.disableflags)
        try:
            for m, d in ((om, od), (rm, rd)):
                m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
                mujoco.mj_forward(m, d)
        finally:
            om.opt.disableflags, rm.opt.disableflags = flags
    for s, name in sensors.items():
        r = rm.sensor(name).id
        a, b = int(om.sensor_adr[s]), int(rm.sensor_adr[r])
        dim = int(om.sensor_dim[s])
        mine, theirs = od.sensordata[a:a + dim], rd.sensordata[b:b + dim]
        scale = max(float(np.abs(mine).max()), 1.0)
        check("sensor", float(np.abs(mine - theirs).max()) / scale, f"sensor '{name}' at {label}")


def _coupling(m, d, e: int) -> float:
    """How far a joint or tendon coupling is from holding: ``y - y0 - p(x - x0)`` (MuJoCo's)."""
    a, b, coef = int(m.eq_obj1id[e]), int(m.eq_obj2id[e]), m.eq_data[e][:5]
    if int(m.eq_type[e]) == JOINT:
        value = lambda j: float(d.qpos[m.jnt_qposadr[j]]) - float(m.qpos0[m.jnt_qposadr[j]])  # noqa: E731
    else:
        value = lambda t: float(d.ten_length[t]) - float(m.tendon_length0[t])  # noqa: E731
    x = value(b) if b >= 0 else 0.0
    return value(a) - (float(coef[0]) + (sum(float(c) * x ** k for k, c in enumerate(coef) if k) if b >= 0 else 0.0))


def _anchors(m, d, e: int) -> list[np.ndarray]:
    """A body connect's or weld's two points in the world (a weld's: and body1's frame turned by its
    relative orientation, against body2's)."""
    b1, b2, data = int(m.eq_obj1id[e]), int(m.eq_obj2id[e]), m.eq_data[e]
    if int(m.eq_objtype[e]) == SITE:  # a connect between frame links' sites (robotkit.importer.mjcf.verbatim)
        return [d.site_xpos[b1], d.site_xpos[b2]]
    R1, R2 = d.xmat[b1].reshape(3, 3), d.xmat[b2].reshape(3, 3)
    if int(m.eq_type[e]) == CONNECT:
        return [d.xpos[b1] + R1 @ data[:3], d.xpos[b2] + R2 @ data[3:6]]
    q = np.asarray(data[6:10], float)
    w, x, y, z = q / np.linalg.norm(q)
    Rq = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                   [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                   [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    return [d.xpos[b1] + R1 @ data[3:6], d.xpos[b2] + R2 @ data[:3], (R1 @ Rq).ravel()]
