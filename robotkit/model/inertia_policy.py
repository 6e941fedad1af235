"""What is wrong with a link's mass properties, and the smallest change that makes them physical.

One rule set, used where an inertial is read: ``robotkit import`` (writes each repair into
the recipe with a comment), the build (a recipe's ``inertia_policy``, whole recipe or per
link) and ``robotkit check``'s lints (which name each defect on the original and the policies
that fix it).

The policies:

- ``keep``: the inertial as given; a defect stops the build.
- ``repair``: the smallest change that makes it physical: the mass raised to a floor when it
  is not positive; the tensor's principal moments raised to a floor (that of a solid sphere of
  radius :data:`MIN_RADIUS` at the link's mass, or :data:`RELATIVE_FLOOR` of the largest
  moment when that is smaller, never below :data:`MIN_MOMENT`), then the triangle inequality
  restored by moving the largest moment down and the other two up by a third of the excess
  each (the least change in the Frobenius norm), plus a third of :data:`TRIANGLE_TOL` of the
  largest, so that the sum of the two ends above it whatever the rounding.  The principal axes
  are kept.
- ``recompute``: from the link's geometry, keeping the given mass (a recipe's
  ``inertial: {mass: M}`` does the same; ``robotkit import --recompute-inertials`` for every link).
- ``estimate``: the link's bounding primitive (robotkit.model.massprops.bounding_primitive) as a
  uniform solid of the given mass.

The build applies them in robotkit.model.resolve (recipe-wide ``inertia_policy``, per link
``inertial.policy``); ``robotkit import --inertia-policy`` chooses one for each link whose given
tensor has :func:`defects` (robotkit.importer.inertials.chosen_inertial).

A link without mass that moves (or a massless root body with moving joints below it) gets one
on import: from its geometry at the recipe's density, or, without geometry, a point mass of a
thousandth of the lightest link with the floor's inertia (robotkit.importer.inertials).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MIN_RADIUS = 1e-3
"""The principal-moment floor is that of a solid sphere of this radius (m) at the link's mass."""

RELATIVE_FLOOR = 1e-3
"""The floor is at most this fraction of the largest principal moment (a thin part stays thin)."""

TRIANGLE_TOL = 1e-9
"""Relative slack of the triangle inequality (what the build accepts)."""


def _moments(values) -> str:
    return ", ".join(f"{v:.6g}" for v in values)


def defects(mass: float, inertia: np.ndarray) -> list[str]:
    """Why ``mass`` and ``inertia`` (about the centre of mass) cannot belong to a real body;
    empty when they can."""
    I = np.asarray(inertia, dtype=float)
    if not np.isfinite(mass):
        return [f"mass is {mass!r}"]
    out = []
    if mass <= 0:
        out.append(f"mass is {mass:.6g} kg" if mass else "mass is 0")
    if not np.all(np.isfinite(I)):
        return out + ["inertia is not finite"]
    if not I.any():
        return out + ["inertia is zero"]
    eig = np.linalg.eigvalsh(0.5 * (I + I.T))
    if eig.min() <= 0:
        out.append(f"inertia is not positive definite (principal moments {_moments(eig)})")
    else:
        a, b, c = eig
        if a + b < c * (1 - TRIANGLE_TOL):
            out.append(f"principal moments {_moments(eig)} violate the triangle inequality")
    return out


@dataclass(frozen=True)
class Repaired:
    mass: float
    inertia: np.ndarray
    changes: tuple[str, ...]
    """What was changed, one phrase each (empty: nothing was wrong)."""


MIN_MOMENT = 1e-13
"""No repair leaves a principal moment below this (kg m^2): MuJoCo refuses a tensor whose least
eigenvalue is under 1e-14 (its mjEPS), and ten times that survives its eigen-decomposition's
rounding.  A tensor a thousandth of whose largest moment is below it is rounding noise (iCub's
1.4e-20 product of inertia) and gets the floor of a zero one, the sphere's."""


def moment_floor(mass: float, largest: float = 0.0) -> float:
    """The smallest principal moment a repair leaves (see the module docstring)."""
    sphere = 0.4 * mass * MIN_RADIUS ** 2
    relative = RELATIVE_FLOOR * largest
    return max(min(sphere, relative) if relative >= MIN_MOMENT else sphere, MIN_MOMENT)


def repair(mass: float, inertia: np.ndarray, min_mass: float) -> Repaired:
    """The smallest change that makes ``mass`` and ``inertia`` physical (see the module
    docstring); ``min_mass`` replaces a mass that is not positive."""
    I = np.asarray(inertia, dtype=float)
    I = 0.5 * (I + I.T)
    changes = []
    if not (np.isfinite(mass) and mass > 0):
        changes.append(f"mass {mass:.6g} kg raised to {min_mass:.6g} kg")
        mass = float(min_mass)
    if not np.all(np.isfinite(I)):
        I = np.zeros((3, 3))
    eig, vecs = np.linalg.eigh(I)
    floor = moment_floor(mass, float(eig.max()))
    new = np.maximum(eig, floor)
    if (new != eig).any():
        changes.append(f"principal moments {_moments(eig)} raised to at least {floor:.6g} kg m^2")
    a, b, c = new
    excess = c - (a + b)
    if excess > c * TRIANGLE_TOL:
        # a + b ends TRIANGLE_TOL * c above c, not on it: equality rounds either way in float
        # (0.00366..7 + 0.00366..7 < 0.00733..4), and MuJoCo refuses a + b < c by any amount
        move = (excess + c * TRIANGLE_TOL) / 3
        new = np.array([a + move, b + move, c - move])
        changes.append(f"principal moments {_moments((a, b, c))} moved to {_moments(new)} "
                       "to meet the triangle inequality")
    if not changes:
        return Repaired(float(mass), I, ())
    if not I.any():
        vecs = np.eye(3)
    out = vecs @ np.diag(new) @ vecs.T
    out = 0.5 * (out + out.T)
    scale = float(np.abs(out).max())
    out[np.abs(out) < 1e-15 * scale] = 0.0  # products of inertia that are rounding only
    return Repaired(float(mass), out + 0.0, tuple(changes))



MUJOCO_MARGIN = 1e-12
"""Relative margin by which principal moments must clear MuJoCo's checks (each above its floor,
a + b >= c, compared exactly after its own eigen-decomposition of the 15-digit fullinertia):
measured on rotated tensors, a + b = c (1 - 1e-14) passes and a + b = c fails 140 times in 300."""


def mujoco_ready(inertia: np.ndarray) -> np.ndarray | None:
    """``inertia`` as MuJoCo accepts it once printed: itself when its principal moments clear
    MuJoCo's checks by :data:`MUJOCO_MARGIN` (and the least is at least :data:`MIN_MOMENT`); else
    the least change that makes them clear, principal axes kept, when that change is rounding:
    at most :data:`TRIANGLE_TOL` of the largest moment (a tensor the build accepts as meeting the
    triangle inequality), or a least moment raised to :data:`MIN_MOMENT` that is noise next to
    the largest (a rod's 1e-20 beside 1e-6: below :data:`RELATIVE_FLOOR` of it).  None when it
    would be more (a tensor whose every moment is under the floor: the recipe's to change)."""
    I = np.asarray(inertia, dtype=float)
    eig, vecs = np.linalg.eigh(0.5 * (I + I.T))
    largest = float(eig.max())
    if not largest > 0:
        return None
    floor = max(MIN_MOMENT, MUJOCO_MARGIN * largest)
    a, b, c = eig
    if a >= floor and a + b >= c * (1 + MUJOCO_MARGIN):
        return I
    raised = np.maximum(eig, floor)
    new = raised.copy()
    new[2] = min(raised[2], (raised[0] + raised[1]) / (1 + MUJOCO_MARGIN))
    noise = RELATIVE_FLOOR * largest >= MIN_MOMENT
    if raised[2] - new[2] > TRIANGLE_TOL * largest or (
            float((raised - eig).max()) > TRIANGLE_TOL * largest and not noise):
        return None
    out = vecs @ np.diag(new) @ vecs.T
    return 0.5 * (out + out.T) + 0.0


# ---------------------------------------------------------------- does the tensor fit the part?

BOX_ERROR, BOX_WARNING = 3.0, 1.5
"""How far the equivalent inertia box may stray from the geometry's (either way) before check
warns and errs (robotkit.check.lints, inertia-box); ``robotkit import`` uses the error one to
recompute a repaired tensor that still does not fit."""

EXTENT_SLACK = float(np.sqrt(3.0))
"""Against a geometry's extent (no closed volume) a uniform body's box may be up to sqrt(3) larger
(mass at the ends): the thresholds are that much wider."""


def equivalent_box(mass: float, moments) -> np.ndarray:
    """Full side lengths of the uniform box with ``mass`` and principal ``moments`` (Gazebo's
    View > Inertia): a = sqrt(6 (I2 + I3 - I1) / m), and so on; a side that comes out imaginary
    (moments that break the triangle inequality) is 0."""
    a, b, c = moments
    return np.sqrt(np.maximum(0.0, 6.0 / mass * np.array([b + c - a, a + c - b, a + b - c])))


@dataclass(frozen=True)
class BoxFit:
    """The equivalent inertia box of a declared tensor against the geometry's, along one set of axes."""

    ratio: float
    """The worst side ratio, >= 1 (1: it fits)."""
    larger: bool
    """Whether the declared box is the larger on that side."""
    declared: np.ndarray
    geometry: np.ndarray
    axes: str
    """What the three sides are along: "x, y, z" when the axes are the link's, else principal axes."""
    slack: float = 1.0

    @property
    def severity(self) -> str | None:
        """"error", "warning" or None, as check judges it."""
        r = self.ratio / self.slack
        return "error" if r > BOX_ERROR else "warning" if r > BOX_WARNING else None


def _link_axes(vecs: np.ndarray, *triples):
    """The triples reordered along x, y, z when the columns of ``vecs`` are the link's axes (a
    part modelled square to its frame), with the label of the axes they are along."""
    index = np.argmax(np.abs(vecs), axis=0)
    if sorted(index.tolist()) == [0, 1, 2] and np.all(np.abs(vecs[index, range(3)]) > 1 - 1e-6):
        order = np.argsort(index)
        return [np.asarray(t)[order] for t in triples], "x, y, z"
    return list(triples), None


def box_fit_geometry(mass: float, inertia, volume: float, geometry_inertia) -> BoxFit:
    """The declared ``inertia`` (about the centre of mass, link axes) against the closed
    geometry's at uniform density with the same ``mass`` (``geometry_inertia``: unit density,
    ``volume``), along the geometry's principal axes, so that a rotated or swapped tensor shows."""
    vals, vecs = np.linalg.eigh(np.asarray(geometry_inertia, dtype=float) * (mass / volume))
    declared = np.diag(vecs.T @ np.asarray(inertia, dtype=float) @ vecs)
    want, got = equivalent_box(mass, vals), equivalent_box(mass, declared)
    worst, axis = 1.0, 0
    for k in range(3):
        if want[k] < 1e-9 * max(want.max(), 1e-12):
            continue
        ratio = max(got[k], 1e-12) / want[k]
        ratio = ratio if ratio >= 1 else 1 / ratio
        if ratio > worst:
            worst, axis = ratio, k
    larger = bool(got[axis] > want[axis])
    (got, want), axes = _link_axes(vecs, got, want)
    return BoxFit(worst, larger, got, want, axes or "the geometry's principal axes")


def box_fit_extent(mass: float, com, inertia, points) -> BoxFit:
    """Without a closed geometry: the equivalent inertia box against the extent of ``points``
    (the geometry, link frame) along the tensor's principal axes; only a larger box counts."""
    vals, vecs = np.linalg.eigh(0.5 * (np.asarray(inertia, dtype=float) + np.asarray(inertia, dtype=float).T))
    dims = equivalent_box(mass, vals)
    local = (np.asarray(points, dtype=float) - np.asarray(com, dtype=float)) @ vecs
    extent = local.max(axis=0) - local.min(axis=0)
    worst = max([max(dims[k], 1e-12) / max(extent[k], 1e-12) for k in range(3)
                 if extent[k] > 1e-9 or dims[k] > 1e-9] or [1.0])
    (dims, extent), axes = _link_axes(vecs, dims, extent)
    return BoxFit(max(worst, 1.0), worst > 1, dims, extent, axes or "its principal axes", EXTENT_SLACK)
