"""Pinocchio (PyPI ``pin``): the URDF as a kinematic model (free-flyer root for a free base).
Pinocchio merges links joined by fixed joints into the body of their moving joint."""

from __future__ import annotations

import os

import numpy as np

from robotkit.check.consumers import Limit, Missing, Refused, View

# pin.Data holds per-joint matrices as wide as the model: measured with pin 4.1 on serial chains,
# 66 MB at 99 DoF, 505 MB at 199, 1683 MB at 299, 3965 MB at 399 (~65 bytes x DoF^3)
DATA_BYTES_PER_DOF3 = 65


def _available_memory() -> float:
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError):
        return float("inf")


def from_urdf(build) -> View:
    try:  # optional and heavy: imported when Pinocchio is asked
        import pinocchio as pin
    except ImportError:
        raise Missing("Pinocchio is not installed (pip install pin)") from None
    try:
        if build.base == "free":
            model = pin.buildModelFromUrdf(str(build.urdf), pin.JointModelFreeFlyer())
        else:
            model = pin.buildModelFromUrdf(str(build.urdf))
    except Exception as exc:  # ValueError / RuntimeError with the parser's message
        raise Refused(" ".join(str(exc).split())[:400]) from None
    need = DATA_BYTES_PER_DOF3 * model.nv ** 3
    if need > _available_memory() / 2:
        raise Limit(f"Pinocchio's model data for {model.nv} degrees of freedom needs about {need / 1e9:.3g} GB "
                      "(it grows with the cube of the count), more than half of this machine's free memory")
    data = model.createData()
    bodies = [(i, f) for i, f in enumerate(model.frames) if f.type == pin.FrameType.BODY]
    masses = {}
    for jid in range(model.njoints):  # each joint's body is named after its first link
        link = next((f.name for _, f in bodies if f.parentJoint == jid and f.name != "world"), None)
        if link is not None:
            masses[link] = float(model.inertias[jid].mass)

    def poses(q: dict[str, float]) -> dict[str, np.ndarray]:
        qv = pin.neutral(model)
        for name, value in q.items():
            if not model.existJointName(name):
                continue
            joint = model.joints[model.getJointId(name)]
            if joint.nq == 2:  # a continuous joint: (cos, sin)
                qv[joint.idx_q:joint.idx_q + 2] = (np.cos(value), np.sin(value))
            else:
                qv[joint.idx_q] = value
        pin.framesForwardKinematics(model, data, qv)
        return {f.name: data.oMf[i].homogeneous.copy() for i, f in bodies}

    return View(masses, poses, lumped=True, lumps_world=True)
