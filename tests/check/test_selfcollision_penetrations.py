"""robotkit.check.selfcollision.penetrations, the fresh sample's tally in numpy, against the
plain loop it replaced (per pair of link names: the deepest penetration and the samples)."""

from __future__ import annotations

import numpy as np

from robotkit.check.selfcollision import penetrations


def tally(rows, dist, names):
    """The loop as it was: one Python step per contact."""
    deepest, hits = {}, {}
    for (i, a, b), d in zip(rows, dist):
        pair = frozenset((names[a], names[b]))
        if d < 0:
            deepest[pair] = max(deepest.get(pair, 0.0), -float(d))
            hits.setdefault(pair, set()).add(int(i))
    return deepest, {p: len(s) for p, s in hits.items()}


def test_the_same_as_the_loop_on_a_random_sweep():
    rng = np.random.default_rng(3)
    names = ["base", "upper", "fore", "wrist", "hand", "upper"]  # two bodies of one name: one pair of names
    n = 5000
    samples = np.sort(rng.integers(0, 800, n))
    bodies = np.sort(rng.integers(0, len(names), (n, 2)), axis=1)
    bodies = bodies[bodies[:, 0] != bodies[:, 1]]
    rows = np.column_stack([samples[:len(bodies)], bodies])
    dist = rng.normal(0.0, 0.004, len(rows))
    assert penetrations(rows, dist, names) == tally(rows, dist, names)
    assert frozenset(("upper", "fore")) in penetrations(rows, dist, names)[1]


def test_no_contact_and_no_penetration():
    rows = np.array([[0, 1, 2], [3, 1, 2]])
    assert penetrations(rows, np.array([0.001, 0.0]), ["a", "b", "c"]) == ({}, {})
    assert penetrations(np.zeros((0, 3), dtype=int), np.zeros(0), ["a"]) == ({}, {})
