"""MuJoCo (PyPI ``mujoco``): the build's MJCF compiled, its bodies' masses and frames."""

from __future__ import annotations

import numpy as np

from robotkit import mj
from robotkit.check.consumers import Missing, Refused, View


def from_mjcf(build) -> View:
    try:  # heavy: imported when MuJoCo is asked (rendering off where MUJOCO_GL cannot work)
        mujoco = mj.load()
    except ImportError:
        raise Missing("MuJoCo is not installed (pip install mujoco)") from None
    if build.mjcf is None:
        raise Missing("no MJCF")
    try:
        model = mujoco.MjModel.from_xml_path(str(build.mjcf))
    except ValueError as exc:
        raise Refused(" ".join(str(exc).split())[:400]) from None
    data = mujoco.MjData(model)
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(model.nbody)]
    masses = {names[b]: float(model.body_mass[b]) for b in range(1, model.nbody)}

    def poses(q: dict[str, float]) -> dict[str, np.ndarray]:
        data.qpos[:] = model.qpos0
        for name, value in q.items():
            j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
            if j >= 0:
                data.qpos[model.jnt_qposadr[j]] = value
        mujoco.mj_kinematics(model, data)
        out = {}
        for b in range(1, model.nbody):
            T = np.eye(4)
            T[:3, :3] = data.xmat[b].reshape(3, 3)
            T[:3, 3] = data.xpos[b]
            out[names[b]] = T
        return out

    return View(masses, poses)
