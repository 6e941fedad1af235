"""The rebuilt URDF in Pinocchio against the original MJCF in MuJoCo: the joint-space mass
matrix and the gravity forces at the verification's configurations.

The joints are matched by name: the URDF's joints are the recipe's, and so are the rebuilt
MJCF's, whose state the verification maps to the original's (:mod:`robotkit.importer.mjcf.state`);
Pinocchio's velocities become the rebuilt MJCF's (a free flyer's linear velocity is in its body
frame, MuJoCo's free joint's in the world's), then the original's.  Pinocchio merges links
joined by fixed joints: the matrix is the same.  Armature apart (URDF has none)."""

from __future__ import annotations

import numpy as np

from robotkit.importer.mjcf.frames import quat_matrix


class PinocchioModel:
    """The URDF loaded once; :meth:`matrices` at a rebuilt MJCF state."""

    def __init__(self, urdf, free: bool):
        import pinocchio as pin  # heavy, and only here

        self.pin = pin
        self.model = (pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer()) if free
                      else pin.buildModelFromUrdf(str(urdf)))
        self.data = self.model.createData()

    def matrices(self, rm, rqpos) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(mass matrix, gravity forces, P) with v_rebuilt = P v_pinocchio, at the rebuilt state ``rqpos``."""
        pin, model = self.pin, self.model
        q, P = pin.neutral(model), np.zeros((rm.nv, model.nv))
        for jid in range(1, model.njoints):
            joint, name = model.joints[jid], model.names[jid]
            j = rm.joint(name).id if name != "root_joint" else _free_joint(rm)
            adr, dof = int(rm.jnt_qposadr[j]), int(rm.jnt_dofadr[j])
            if joint.nq == 7:  # a free flyer: x y z, then the quaternion x y z w
                w, x, y, z = rm_q = rqpos[adr + 3:adr + 7]
                q[joint.idx_q:joint.idx_q + 7] = [*rqpos[adr:adr + 3], x, y, z, w]
                P[dof:dof + 3, joint.idx_v:joint.idx_v + 3] = quat_matrix(rm_q)
                P[dof + 3:dof + 6, joint.idx_v + 3:joint.idx_v + 6] = np.eye(3)
            elif joint.nq == 2:  # a continuous joint: (cos, sin)
                q[joint.idx_q:joint.idx_q + 2] = np.cos(rqpos[adr]), np.sin(rqpos[adr])
                P[dof, joint.idx_v] = 1.0
            else:
                q[joint.idx_q] = rqpos[adr]
                P[dof, joint.idx_v] = 1.0
        M = pin.crba(model, self.data, q)
        M = np.triu(M) + np.triu(M, 1).T
        return M, np.array(pin.computeGeneralizedGravity(model, self.data, q)), P


def _free_joint(rm) -> int:
    return next(j for j in range(rm.njnt) if int(rm.jnt_type[j]) == 0)
