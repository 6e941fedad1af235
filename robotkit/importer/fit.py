"""Whether an imported link's explicit tensor fits its geometry, by ``robotkit check``'s rule
(robotkit.model.inertia_policy.box_fit_geometry, box_fit_extent: the equivalent inertia box
against the geometry's), read on the recipe as the build resolves it.

A tensor the import repaired (no real body has the original) that still does not fit gets
``recompute`` (``estimate`` without a closed geometry) instead: a repair keeps the wrong size of
a hand-typed tensor.  A physical one that does not fit is kept, with a warning.
"""

from __future__ import annotations

import os

import numpy as np

from robotkit.importer.inertials import geometry_facts
from robotkit.importer.meshes import mesh_is_closed
from robotkit.importer.recipe_writer import fmt
from robotkit.mesh.inertia import density_volume, solid_as_written
from robotkit.mesh.io import load_mesh
from robotkit.model import inertia_policy
from robotkit.model import massprops
from robotkit.model.resolve import geom_mass_props
from robotkit.model.rigidbody import MESHLAB, Implied, Part, RigidBody, implied_density, rigid_bodies


_FACTS: dict[tuple, dict] = {}


def _facts(mesh) -> dict:
    """robotkit.importer.inertials.geometry_facts, once per file version (an import loads the
    recipe twice when it recomputes a tensor)."""
    st = os.stat(mesh.source)
    key = (mesh.key, st.st_mtime_ns, st.st_size)
    if key not in _FACTS:
        _FACTS[key] = geometry_facts(mesh)
    return _FACTS[key]


def _points(geom) -> np.ndarray:
    """The geometry's vertices (a primitive's bounding box corners), in its link frame."""
    s = geom.shape
    if s.kind == "mesh":
        P = np.asarray(load_mesh(s.mesh.source, s.mesh.scale).vertices, dtype=float)
    else:
        half = {"box": lambda: np.asarray(s.size, dtype=float) / 2,
                "cylinder": lambda: np.array([s.radius, s.radius, s.length / 2]),
                "sphere": lambda: np.full(3, s.radius)}[s.kind]()
        P = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half
    T = geom.pose.matrix()
    return P @ T[:3, :3].T + T[:3, 3]


def _closed(geoms) -> tuple[float, np.ndarray] | None:
    """(volume, unit-density inertia) of the geometry when it is all closed, else None."""
    if not all(g.shape.kind != "mesh" or mesh_is_closed(g.shape.mesh.source, g.shape.mesh.scale) for g in geoms):
        return None
    facts = {g.shape.mesh.key: _facts(g.shape.mesh) for g in geoms if g.shape.kind == "mesh"}
    volume, _, I = massprops.combine([geom_mass_props(g, facts) for g in geoms])
    return volume, I


def link_fit(link) -> tuple[inertia_policy.BoxFit, float | None] | None:
    """The fit of a resolved link's explicit inertial to its visual (else collision) geometry,
    as check judges it, with the geometry's volume (None when not closed); None when it has no
    explicit inertial or no geometry."""
    geoms = list(link.visuals or link.collisions)
    if link.inertial_spec.mode != "explicit" or not geoms:
        return None
    given = link.inertial_spec.explicit
    closed = _closed(geoms)
    if closed:
        if max(_size(g) for g in geoms) <= MARKER:
            return None
        volume, I = closed
        return inertia_policy.box_fit_geometry(given.mass, given.tensor(), volume, I), volume
    points = np.vstack([_points(g) for g in geoms])
    if float(np.ptp(points, axis=0).max()) <= MARKER:
        return None
    return inertia_policy.box_fit_extent(given.mass, given.com, given.tensor(), points), None


MARKER = 1e-3
"""m: geometry no larger marks a frame (an IMU's 1 mm box) and says nothing of the part; check
reads it so too (robotkit.check.lints.MARKER)."""


def _size(geom) -> float:
    """The largest side of a geometry's bounding box (a closed mesh's from its cached facts)."""
    if geom.shape.kind == "mesh":
        f = _facts(geom.shape.mesh)
        return float(np.max(np.asarray(f["bbox_max"]) - np.asarray(f["bbox_min"])))
    return float(np.ptp(_points(geom), axis=0).max())


def describe(fit: inertia_policy.BoxFit) -> str:
    sides = [" x ".join(f"{d:.3g}" for d in t) for t in (fit.declared, fit.geometry)]
    than = "the geometry's at uniform density" if fit.slack == 1 else "the geometry"
    return (f"its equivalent inertia box ({sides[0]} m) is {fit.ratio:.3g}x {'larger' if fit.larger else 'smaller'} "
            f"than {than} ({sides[1]} m), along {fit.axes}")


def _said(found: Implied, mass: float, volume: float) -> str:
    """The import's words for check's implied-density verdict on the original's ``mass``."""
    return (f"the original's mass {mass:.4g} kg over its geometry's {volume:.4g} m^3 implies {found.figure} kg/m^3, "
            f"{found.side} {found.bound:g}" + (found.welded() if found.body else f" ({found.cause})"))


_WRITTEN: dict[tuple, tuple[float | None, float]] = {}


def _as_written(geom) -> tuple[float | None, float]:
    """(volume when closed as written, else None; largest side) of a geometry, as check reads the
    built file (robotkit.mesh.inertia.solid_as_written: no repair); a primitive's volume always."""
    s = geom.shape
    if s.kind != "mesh":
        return geom_mass_props(geom, {})[0], float(np.ptp(_points(geom), axis=0).max())
    st = os.stat(s.mesh.source)
    key = (s.mesh.source, tuple(s.mesh.scale), st.st_mtime_ns, st.st_size)
    if key not in _WRITTEN:
        mesh = load_mesh(s.mesh.source, s.mesh.scale)
        V, F = np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)
        props = solid_as_written(V, F)
        _WRITTEN[key] = (props.volume if props else None, float(np.ptp(V, axis=0).max()) if len(V) else 0.0)
    return _WRITTEN[key]


def _shown(link) -> tuple[list, list]:
    """The volumes (None: open as written) of the parts the link's visual and collision geometry
    show, as check reads them; a role whose geometry is no larger than a marker shows no part."""
    shown = []
    for geoms in (link.visuals, link.collisions):
        parts = [_as_written(g) for g in geoms]
        shown.append([v for v, _ in parts] if parts and max(size for _, size in parts) > MARKER else [])
    return shown[0], shown[1]


def _check_volume(link) -> float | None:
    """The volume check judges a link's density on (robotkit.mesh.inertia.density_volume, check's
    rule): its visual geometry's when closed as written, else its collision geometry's when so
    (ANYmal B's base: a placeholder 1e-6 kg on an open mesh and closed boxes; G1's ankle roll links:
    a visual mesh that robotkit's repair would close, open as written), else None."""
    return density_volume(*_shown(link))


def _recipe_mass(link) -> float | None:
    """The mass the build gives a link of the imported recipe (None: no inertial)."""
    spec = link.inertial_spec
    if spec.mode == "explicit":
        return spec.explicit.mass
    if spec.mode in ("mass", "estimate"):
        return spec.mass
    if spec.mode == "density" and link.source_geoms():
        facts = {g.shape.mesh.key: _facts(g.shape.mesh) for g in link.source_geoms() if g.shape.kind == "mesh"}
        return spec.density * sum(geom_mass_props(g, facts)[0] for g in link.source_geoms())
    return None


def rigid_bodies_of(robot) -> dict[str, RigidBody]:
    """The rigid body each link of the recipe belongs to, as check will read the build
    (robotkit.model.rigidbody.rigid_bodies; check's robotkit.check.lints.rigid_bodies_of)."""
    parts = {}
    for link in robot.links:
        visual, collision = _shown(link)
        parts[link.name] = Part(_recipe_mass(link), density_volume(visual, collision), bool(visual or collision))
    return rigid_bodies(parts, [(j.parent, j.child) for j in robot.joints if j.type == "fixed"])


def _density(link, mass: float, bodies) -> tuple[Implied, float] | None:
    """Check's implied-density verdict on the original's ``mass`` with the volume check reads
    (judged on the link's rigid body, ``bodies()``, when its own is out of range), else None."""
    judged = _check_volume(link)  # check's volume, which may differ from the repaired geometry's
    if implied_density(mass, judged) is None:
        return None
    return implied_density(mass, judged, bodies()[link.name]), judged


def misfits(robot, explicit: dict[str, dict], recompute: bool) -> tuple[dict[str, tuple[str, str]], dict[str, str]]:
    """(link -> (policy, why) for the tensors, given or repaired, that do not fit and the masses no
    solid part of that volume has, when ``recompute``; link -> why for those kept otherwise), judged
    as check's errors.  A tensor that does not fit gets ``recompute`` (``estimate`` without a
    closed geometry), a mass that is the volume at density 1 (MeshLab's) ``density`` (mass and
    tensor from the geometry at the recipe's density); another too light or too heavy for its
    volume is kept (the geometry may be what is wrong)."""
    overrides, kept = {}, {}
    cache: list = []

    def bodies() -> dict[str, RigidBody]:  # read only when a link's own density is out of range
        if not cache:
            cache.append(rigid_bodies_of(robot))
        return cache[0]

    for link in robot.links:
        given = explicit.get(link.name)
        spec = link.inertial_spec
        if given is None or not (spec.mode == "explicit" or (spec.mode in ("mass", "estimate") and spec.mass == given["mass"])):
            continue  # no given mass, or one the recipe no longer keeps (computed at its density)
        found = link_fit(link)  # None when the link's inertial is no longer explicit (repaired, estimated)
        volume = found[1] if found else None
        density = _density(link, given["mass"], bodies)
        if density is not None:
            verdict, judged = density
            said = _said(verdict, given["mass"], judged)
            if recompute and volume and verdict.cause == MESHLAB:  # the one obvious reading: MeshLab's volume as the mass
                overrides[link.name] = ("density", said)
                continue
            # too heavy: a placeholder mass on a marker, or a part drawn smaller than it is; too light:
            # the geometry may be what is wrong (simple_humanoid's 4 m^3 body of 27 kg); no one reading
            kept[link.name] = (f"{said}; compute it from the geometry at the recipe's density (no inertial on the "
                               "link in the recipe)" if verdict.cause == MESHLAB
                               else f"{said}: kept (check {'warns of' if verdict.body else 'reports'} it)")
        if found is None or found[0].severity != "error":
            continue
        fit = found[0]
        t = given["inertia"]
        tensor = np.array([[t["ixx"], t["ixy"], t["ixz"]], [t["ixy"], t["iyy"], t["iyz"]],
                           [t["ixz"], t["iyz"], t["izz"]]])
        repaired = bool(inertia_policy.defects(given["mass"], tensor))
        if recompute:
            overrides[link.name] = ("recompute" if fit.slack == 1 else "estimate",
                                    f"repaired, {describe(fit)}" if repaired
                                    else f"the given inertial does not fit its geometry: {describe(fit)}")
        elif not repaired:
            kept[link.name] = (f"the given inertial does not fit its geometry: {describe(fit)}; recompute it from the "
                               f"geometry (inertial: {{mass: {fmt(given['mass'])}}} on the link in the recipe, or "
                               "import with --recompute-inertials)")
    return overrides, kept
