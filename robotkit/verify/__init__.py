"""Checks on built outputs: cross-format equivalence and a simulation smoke test."""

from __future__ import annotations

from pathlib import Path


def equivalence(robot_dir: str | Path, tol: float = 1e-9, configs: int = 100,
                notes: list[str] | None = None) -> dict[str, list[str]]:
    """Compare the URDF, SDF and MJCF of a build folder pairwise; {comparison: differences}.

    A comparison that cannot be made is left out and explained in ``notes``."""
    from robotkit.verify import kinematics as k

    robot_dir = Path(robot_dir)
    name = robot_dir.name
    urdf = robot_dir / "urdf" / f"{name}.urdf"
    u = k.read_urdf(urdf)
    m = k.read_mjcf(robot_dir / "mjcf" / f"{name}.xml")
    s = k.read_sdf(robot_dir / "model.sdf")
    g = k.read_urdf_via_libsdformat(urdf)
    result = {
        "URDF (MuJoCo) vs MJCF (MuJoCo)": k.compare(u, m, tol, configs, ignore=("velocity",)),
        "URDF (MuJoCo) vs SDF": k.compare(u, s, tol, configs, ignore=("mimic",)),
    }
    # libsdformat's URDF conversion drops massless links and lumps what hangs below them
    # into the parent: compare with it only when it kept every link that has mass.
    massful = {n for n, link in u.links.items() if link.mass > 0}
    lumped = sorted(massful - set(g.links))
    if lumped and notes is not None:
        notes.append(f"{name}: URDF (libsdformat) vs SDF not compared: libsdformat's URDF conversion "
                     f"drops massless links and lumps {', '.join(lumped)} into their parents")
    if not lumped:
        g_only = {n for n in u.links if n not in g.links}
        result["URDF (libsdformat) vs SDF"] = k.compare(g, _without(s, g_only), tol, configs, ignore=("mimic",))
    return result


def _without(model, names: set[str]):
    """``model`` without the (massless) links ``names`` and the fixed joints to them."""
    import copy

    model = copy.copy(model)
    model.links = {n: v for n, v in model.links.items() if n not in names}
    model.joints = {n: j for n, j in model.joints.items() if j.child not in names}
    return model


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
