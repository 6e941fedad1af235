"""robotkit.check.kinematics.first_pose_difference, every link at once, against the per-link
pose_difference loop it replaced in compare: the same first link, or none."""

from __future__ import annotations

import numpy as np

from robotkit.check.kinematics import first_pose_difference, pose_difference, rpy_matrix


def frame(rng, scale):
    T = np.eye(4)
    T[:3, :3] = rpy_matrix(*rng.uniform(-np.pi, np.pi, 3))
    T[:3, 3] = rng.uniform(-scale, scale, 3)
    return T


def loop(ra, Ta, rb, Tb, names, tol):
    return next((n for n in names if pose_difference(ra @ Ta[n], rb @ Tb[n], tol)), None)


def test_the_same_link_as_the_loop():
    rng = np.random.default_rng(7)
    names = [f"link{i}" for i in range(12)]
    found = set()
    for trial in range(300):
        Ta = {n: frame(rng, 3.0 if trial % 2 else 0.5) for n in names}
        Tb = {n: T.copy() for n, T in Ta.items()}
        ra, rb = np.linalg.inv(Ta["link0"]), np.linalg.inv(Tb["link0"])
        for n in rng.choice(names, int(rng.integers(0, 3)), replace=False):  # nudged by about the tolerance
            i, j = (int(rng.integers(0, 3)), int(rng.integers(0, 4)))
            Tb[n][i, j] += rng.choice([0.5, 2.0, 50.0]) * 1e-9 * (1 if j < 3 else 3.0)
        first = first_pose_difference(ra, Ta, rb, Tb, names, 1e-9)
        assert first == loop(ra, Ta, rb, Tb, names, 1e-9)
        found.add(first is None)
    assert found == {True, False}  # agreeing and differing cases both met
    Tb["link5"][0, 3] = np.nan
    assert first_pose_difference(ra, Ta, rb, Tb, names, 1e-9) == loop(ra, Ta, rb, Tb, names, 1e-9)
    assert first_pose_difference(ra, Ta, rb, Tb, [], 1e-9) is None
