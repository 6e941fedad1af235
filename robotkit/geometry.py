"""Rotations in the URDF convention: fixed-axis roll, pitch, yaw, R = Rz(y) Ry(p) Rx(r).

The one home of the rotation helpers the model, the mesh functions, the recipe
language (placing parts), the importer and the emitters share.  Pure arithmetic on
Python floats, so the recipe language uses them without numpy; :func:`rpy_matrix`
wraps the same rows in a numpy array.  (robotkit.check.kinematics keeps its own
copies on purpose: it is an independent reader, the equivalence check's oracle.)
"""

from __future__ import annotations

import math

Vec3 = tuple[float, float, float]


def rpy_rows(rpy) -> list[list[float]]:
    """The rotation matrix of fixed-axis roll, pitch, yaw as three rows of Python floats."""
    r, p, y = (float(a) for a in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]


def rpy_matrix(rpy):
    """Rotation matrix (a 3x3 numpy array) of fixed-axis roll, pitch, yaw: R = Rz(y) Ry(p) Rx(r)."""
    import numpy as np  # late: the recipe language reads rpy_rows and matrix_rpy without numpy

    return np.array(rpy_rows(rpy))


def matrix_rpy(R) -> Vec3:
    """Fixed-axis roll, pitch, yaw of a rotation matrix (a numpy array or rows of numbers;
    inverse of :func:`rpy_matrix`)."""
    sp = -float(R[2][0])
    if abs(sp) >= 1.0 - 1e-12:  # gimbal lock: put everything in yaw
        p = math.copysign(math.pi / 2, sp)
        r = 0.0
        y = math.atan2(-float(R[0][1]), float(R[1][1]))
    else:
        p = math.asin(sp)
        r = math.atan2(float(R[2][1]), float(R[2][2]))
        y = math.atan2(float(R[1][0]), float(R[0][0]))
    return (r, p, y)


def rpy_quat(rpy) -> tuple[float, float, float, float]:
    """The unit quaternion (w, x, y, z) of fixed-axis roll, pitch, yaw, with w >= 0."""
    r, p, y = (0.5 * float(a) for a in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    q = (cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
         cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy)
    return q if q[0] >= 0 else tuple(-v for v in q)
