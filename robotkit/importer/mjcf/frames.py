"""Poses as MuJoCo gives them (position, quaternion w x y z) and as a recipe writes them
(``origin: {xyz, rpy}``)."""

from __future__ import annotations

import numpy as np

from robotkit.geometry import matrix_rpy
from robotkit.importer.parsing import origin_dict

TINY = 1e-15
"""Below this, a coordinate is float noise of the file's own rotations (0.5 written as 0.499...):
written as 0."""


def quat_matrix(q) -> np.ndarray:
    w, x, y, z = (float(v) for v in q)
    n = w * w + x * x + y * y + z * z
    s = 2.0 / n if n > 0 else 0.0
    return np.array([
        [1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)],
        [s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)],
        [s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)],
    ])


def clean(values) -> list[float]:
    return [0.0 if abs(float(v)) < TINY else float(v) for v in values]


def origin(pos, R) -> dict | None:
    """The recipe ``origin`` of a pose (None for the identity)."""
    return origin_dict(clean(pos), clean(matrix_rpy(R)))


def compose(pa, Ra, pb, Rb) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(pa) + Ra @ np.asarray(pb), Ra @ Rb


def inverse(p, R) -> tuple[np.ndarray, np.ndarray]:
    return -R.T @ np.asarray(p), R.T
