"""The rebuilt model's state at the original's: its positions (a ball joint as the three angles
of its revolute joints, a chain's extra joints at zero) and the map of its velocities to the
original's."""

from __future__ import annotations

import numpy as np

from robotkit.importer.mjcf.extras import ball_angles

FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3


def mapped(om, rm, tree, q) -> np.ndarray:
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


def velocity_map(om, rm, tree, q) -> np.ndarray:
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
