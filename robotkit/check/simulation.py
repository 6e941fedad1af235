"""The simulation check: the MuJoCo scene the build writes (its integrator, its floor, contacts
on, the robot standing where the scene puts it), stepped with no input: actuators hold their
initial targets.  Its verdict is what a user sees when they open the scene."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from robotkit import mj

START_GAP = 1e-3  # m: a free robot must start on the floor, not above it or inside it
REST_SPEED = 1e-2  # |qvel| of a free base at the end (m/s, rad/s)
MAX_TILT = 2.0  # degrees a free base may tip while it settles


def smoke_test(scene: str | Path, seconds: float = 3.0, notes: list[str] | None = None) -> list[str]:
    """Problems seen while stepping ``scene``: NaN, an explosion, a MuJoCo warning, a robot
    that starts inside the floor, and a free base that tips over or does not come to rest.
    ``notes`` collects what is worth a warning: a free robot that starts above the floor."""
    mujoco = mj.load()  # heavy: imported when the scene is stepped

    model = mujoco.MjModel.from_xml_path(str(scene))
    data = mujoco.MjData(model)
    margins = model.geom_margin.copy()
    model.geom_margin[:] = START_GAP  # contacts within START_GAP count as touching
    mujoco.mj_forward(model, data)
    problems = []
    # the floor's contacts only: links touching each other at the start are the self-collision stage's
    # (Kinova's j2s6s200 folds onto its base at its zero pose: 72.7 mm deep, above the floor)
    floor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "robotkit_floor")
    deepest = min((float(data.contact[i].dist) for i in range(data.ncon)
                   if floor in (data.contact[i].geom1, data.contact[i].geom2)), default=None)
    model.geom_margin[:] = margins
    mujoco.mj_forward(model, data)
    if deepest is not None and deepest < -START_GAP:
        problems.append(f"the robot starts {-deepest * 1000:.3g} mm inside the floor")
    free = [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    if free and deepest is None and notes is not None:  # a drop the recipe may want (a world-rooted robot)
        notes.append(f"the free robot starts more than {START_GAP * 1000:g} mm above the floor and falls")
    free_dofs = [int(model.jnt_dofadr[j]) + k for j in free for k in range(6)]
    upright = [data.qpos[model.jnt_qposadr[j] + 3:model.jnt_qposadr[j] + 7].copy() for j in free]
    steps = int(seconds / model.opt.timestep)
    for i in range(steps):
        mujoco.mj_step(model, data)
        t = (i + 1) * model.opt.timestep
        if not (np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all()):
            return problems + [f"simulation produced NaN or inf after {t:.3f} s"]
        if np.abs(data.qvel).max(initial=0.0) > 1e3:
            return problems + [f"simulation exploded after {t:.3f} s (|qvel| {np.abs(data.qvel).max():.3g})"]
    for w in range(len(data.warning)):
        if data.warning[w].number:
            name = mujoco.mjtWarning(w).name
            problems.append(f"MuJoCo warned {name} ({data.warning[w].number} times) in {seconds:g} s")
    for j, q0 in zip(free, upright):
        q = data.qpos[model.jnt_qposadr[j] + 3:model.jnt_qposadr[j] + 7]
        tilt = math.degrees(2 * math.acos(min(1.0, abs(float(np.dot(q0, q))))))
        if tilt > MAX_TILT:
            problems.append(f"the free robot tipped over by {tilt:.3g} degrees in {seconds:g} s")
    speed = float(np.abs(data.qvel[free_dofs]).max(initial=0.0))
    if speed > REST_SPEED:
        problems.append(f"the free robot is still moving after {seconds:g} s (max |qvel| {speed:.3g}); "
                        "it should stand still with its actuators holding their targets")
    return problems
