"""The implied-density rule, judged on the rigid body a link belongs to.

A link welded to others by fixed joints is no body of its own in a simulator that lumps fixed
joints (Gazebo, Drake): only the assembly's mass, centre of mass and inertia act.  A placeholder
mass on a sensor frame or on a dummy link carrying a visual (1e-6 kg on ANYmal B's ``base``, whose
mass sits in the geometry-less ``base_inertia`` welded to it) implies no plausible density of its
own, but the body it belongs to may.  ``robotkit check`` (robotkit.check.lints) and the import's
density warnings (robotkit.importer.fit) both judge a link by :func:`implied_density` on the
bodies of :func:`rigid_bodies`, so the import says what check will.

Standard library only, like robotkit.model.plausible.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable

from robotkit.model.plausible import DENSITY_RANGE

MESHLAB = "the mass is the mesh volume at density 1, MeshLab's default"
NAMED = 3  # names a body's description lists before "and N more"


@dataclass(frozen=True)
class Part:
    """What the rule reads of one link: its mass (None: no inertial), the volume its density is
    judged on (robotkit.mesh.inertia.density_volume; None: not closed, or no part shown) and
    whether it shows a part at all (False: no geometry, or only a marker)."""

    mass: float | None
    volume: float | None
    shows_part: bool


@dataclass(frozen=True)
class RigidBody:
    """The links of a rigid body whose mass and volume are counted, the judged link first and
    the others heaviest first; their total mass (kg) and volume (m^3)."""

    links: tuple[str, ...]
    mass: float
    volume: float

    @property
    def density(self) -> float:
        return self.mass / self.volume

    def describe(self) -> str:
        """``base, base_inertia and 2 more: 16.8 kg, 0.0412 m^3``."""
        names = ", ".join(self.links[:NAMED])
        if len(self.links) > NAMED:
            names += f" and {len(self.links) - NAMED} more"
        return f"{names}: {self.mass:.4g} kg, {self.volume:.4g} m^3"


def _counted(part: Part) -> bool:
    """Whether a link's mass and volume count in its body's: a positive mass on a known volume,
    or on no geometry at all (the mass of a body whose shape is drawn on the links welded to it)."""
    if part.mass is None or not math.isfinite(part.mass) or not part.mass > 0:
        return False
    return part.volume is not None or not part.shows_part


def rigid_bodies(parts: dict[str, Part], fixed: Iterable[tuple[str, str]]) -> dict[str, RigidBody]:
    """The rigid body of each link of ``parts`` (in their order): the links connected to it by
    the ``fixed`` joints (parent, child), both ways.  Its mass is the sum of the masses of its
    links that have a known volume or no geometry at all (:func:`_counted`), its volume the sum
    of the known volumes.  Names in ``fixed`` that ``parts`` lacks (URDF's ``world``) join
    nothing."""
    order = {name: i for i, name in enumerate(parts)}
    near: dict[str, list[str]] = {name: [] for name in parts}
    for parent, child in fixed:
        if parent in near and child in near:
            near[parent].append(child)
            near[child].append(parent)
    group: dict[str, list[str]] = {}
    for name in parts:
        if name in group:
            continue
        members, todo = [], [name]
        while todo:
            n = todo.pop()
            if n in group:
                continue
            group[n] = members
            members.append(n)
            todo += near[n]
    out = {}
    for name in parts:
        counted = [n for n in group[name] if _counted(parts[n])]
        others = sorted((n for n in counted if n != name), key=lambda n: (-parts[n].mass, order[n]))
        links = ([name] if name in counted else []) + others
        out[name] = RigidBody(tuple(links), sum(parts[n].mass for n in links),
                              sum(parts[n].volume or 0.0 for n in links))
    return out


@dataclass(frozen=True)
class Implied:
    """A link's implied density out of DENSITY_RANGE: ``side`` ``below`` or ``above`` its
    ``bound``, the likely ``cause``; ``body`` the rigid body (of 2+ links) it is welded to when that
    body's density is in range (a warning: its mass is a share of the body's), else None (an error)."""

    density: float
    side: str
    bound: float
    cause: str
    body: RigidBody | None

    @property
    def figure(self) -> str:
        """The density as the messages print it (3 significant digits below the range, 4 above)."""
        return f"{self.density:.3g}" if self.side == "below" else f"{self.density:.4g}"

    @property
    def severity(self) -> str:
        return "warning" if self.body is not None else "error"

    def welded(self) -> str:
        """The clause that follows the link's own figures when the body is in range, else ''."""
        if self.body is None:
            return ""
        return (f"; the rigid body it is welded to ({self.body.describe()}) is {self.body.density:.4g} kg/m^3: "
                "its mass is a share of that body's")


WELDED_HINT = ("Gazebo and Drake lump links welded by fixed joints into one body, where only the body's mass acts; "
               "give the link its own share of it for a simulator that keeps it a body of its own")


def implied_density(mass: float, volume: float | None, body: RigidBody | None = None) -> Implied | None:
    """The verdict on ``mass`` over the closed ``volume`` (None when in range or no volume),
    judged on ``body`` (the link's, :func:`rigid_bodies`) when the link's own is out of range."""
    if not volume or not mass > 0:
        return None
    density = mass / volume
    if density < DENSITY_RANGE[0]:
        side, bound = "below", DENSITY_RANGE[0]
        cause = MESHLAB if abs(density - 1.0) < 0.05 else "the density or mass is far too low"
    elif density > DENSITY_RANGE[1]:
        side, bound = "above", DENSITY_RANGE[1]
        cause = ("the mass looks like grams written as kilograms" if density / 1000 < DENSITY_RANGE[1]
                 else "the geometry is far too small for the mass (units?)")
    else:
        return None
    in_range = (body is not None and len(body.links) > 1 and body.volume > 0
                and DENSITY_RANGE[0] <= body.density <= DENSITY_RANGE[1])
    return Implied(density, side, bound, cause, body if in_range else None)
