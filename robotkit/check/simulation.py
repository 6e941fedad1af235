"""The simulation check: the MuJoCo scene the build writes, stepped with no input."""

from __future__ import annotations

from pathlib import Path


def smoke_test(scene: str | Path, seconds: float = 3.0, notes: list[str] | None = None) -> list[str]:
    """Step a MuJoCo scene; problems if it produces NaN, explodes, gains energy, or if a free
    body does not come to rest (a robot sliding or drifting on the spot: wrong inertials).

    A robot that starts inside the floor (an arm whose zero pose reaches below its base) is
    stepped without contacts, and ``notes`` says so."""
    import mujoco
    import numpy as np

    model = mujoco.MjModel.from_xml_path(str(scene))
    model.opt.enableflags |= mujoco.mjtEnableBit.mjENBL_ENERGY
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4  # conserves energy well: a gain is the model's
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    deepest = min((float(c.dist) for c in data.contact[:data.ncon]), default=0.0)
    if deepest < -1e-3:
        if notes is not None:
            notes.append(f"the robot starts {-deepest * 1000:.3g} mm inside the floor at its zero pose; "
                         "the simulation check ran without contacts")
        model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
        mujoco.mj_forward(model, data)
    e0 = float(data.energy.sum())
    allowed = e0 + max(0.05 * abs(e0), 0.05)
    free_dofs = [int(model.jnt_dofadr[j]) + k for j in range(model.njnt)
                 if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE for k in range(6)]
    steps = int(seconds / model.opt.timestep)
    for i in range(steps):
        mujoco.mj_step(model, data)
        t = (i + 1) * model.opt.timestep
        if not (np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all()):
            return [f"simulation produced NaN or inf after {t:.3f} s"]
        if np.abs(data.qvel).max(initial=0.0) > 1e3:
            return [f"simulation exploded after {t:.3f} s (|qvel| {np.abs(data.qvel).max():.3g})"]
        energy = float(data.energy.sum())
        if energy > allowed:
            return [f"the passive robot gained energy: {e0:.4g} J at the start, {energy:.4g} J after {t:.3f} s"]
    speed = float(np.abs(data.qvel[free_dofs]).max(initial=0.0))
    if speed > 1e-2:
        return [f"a free body is still moving after {seconds:g} s (max |qvel| {speed:.3g}); "
                "a robot that slides or drifts on the spot usually has wrong inertials"]
    return []
