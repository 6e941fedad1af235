"""Pinocchio (PyPI ``pin``): the URDF as a kinematic model (free-flyer root for a free base).
Pinocchio merges links joined by fixed joints into the body of their moving joint."""

from __future__ import annotations

import numpy as np

from robotkit.check.consumers import Missing, Refused, View


def from_urdf(build) -> View:
    try:
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
    data = model.createData()
    bodies = [(i, f) for i, f in enumerate(model.frames) if f.type == pin.FrameType.BODY]
    masses = {}
    for jid in range(model.njoints):  # each joint's body is named after its first link
        link = next((f.name for _, f in bodies if f.parentJoint == jid), None)
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

    return View(masses, poses, lumped=True)
