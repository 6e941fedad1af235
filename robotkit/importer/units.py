"""A mesh whose size says it is in other units than its URDF states (a CAD export in
millimetres referenced without ``scale``: 94 m across): which units make it a plausible part,
and, when only one does, the recipe's ``units`` for it, stated in a comment above its link.

The rule is the build's and check's (robotkit.model.plausible): a part is between
PART_SIZE_RANGE across, and its implied density within DENSITY_RANGE when the link's given
mass is on that mesh alone (what tells millimetres from centimetres or inches).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, replace

from robotkit.errors import MeshError
from robotkit.importer.meshes import MeshUse, mesh_is_closed
from robotkit.mesh.inertia import mesh_mass_properties
from robotkit.mesh.io import load_mesh, volume_mesh
from robotkit.model.plausible import DENSITY_RANGE, PART_SIZE_RANGE
from robotkit.recipe.schema import UNITS

UNIT_WORDS = {"m": "metres", "cm": "centimetres", "mm": "millimetres", "in": "inches"}

_EXTENTS: dict[tuple, float] = {}


def _key(source: str) -> tuple:
    st = os.stat(source)
    return (source, st.st_mtime_ns, st.st_size)


def mesh_extent(source: str) -> float:
    """The largest extent of a mesh file at scale 1."""
    key = _key(source)
    if key not in _EXTENTS:
        m = load_mesh(source, (1.0, 1.0, 1.0))
        _EXTENTS[key] = float((m.bounds[1] - m.bounds[0]).max())
    return _EXTENTS[key]


def mesh_volume(source: str) -> float | None:
    """The volume of a mesh file at scale 1, None when it is not closed."""
    if not mesh_is_closed(source, (1.0, 1.0, 1.0)):
        return None
    m = load_mesh(source, (1.0, 1.0, 1.0))
    try:
        vol = volume_mesh(m, "error", os.path.basename(source))[0]
    except MeshError:
        return None
    volume = float(mesh_mass_properties(vol.vertices, vol.faces).volume)
    return volume if volume > 0 else None


def plausible_units(extent: float, volume: float | None, mass: float | None) -> list[str]:
    """The units under which a mesh ``extent`` across at scale 1 (``volume``, and the link's
    ``mass`` on it alone, when known) is a plausible part."""
    out = []
    for unit, f in UNITS.items():
        if not PART_SIZE_RANGE[0] <= extent * f <= PART_SIZE_RANGE[1]:
            continue
        if volume and mass and not DENSITY_RANGE[0] <= mass / (volume * f ** 3) <= DENSITY_RANGE[1]:
            continue
        out.append(unit)
    return out


@dataclass
class UnitFix:
    """What the import makes of one implausibly sized mesh."""

    unit: str | None  # the recipe's units for it, when only one is plausible
    warning: str
    note: str = ""  # the comment above the link, when the recipe changes it


def judge(link: str, kind: str, use: MeshUse, mass_alone: float | None) -> UnitFix | None:
    """None when the mesh is a plausible part as the URDF scales it (or is scaled unevenly)."""
    s = use.scale[0]
    if not use.scale[0] == use.scale[1] == use.scale[2]:
        return None
    extent = mesh_extent(use.source)
    if PART_SIZE_RANGE[0] <= extent * s <= PART_SIZE_RANGE[1] or extent == 0:
        return None
    volume = mesh_volume(use.source) if mass_alone else None
    name = os.path.basename(use.source)
    across = f"{extent * s:.3g} m" if extent * s > PART_SIZE_RANGE[1] else f"{extent * s * 1000:.3g} mm"
    what = f"link '{link}' {kind} mesh {name} is {across} across"
    units = plausible_units(extent, volume, mass_alone)
    if len(units) == 1 and UNITS[units[0]] != s:
        unit = units[0]
        f = UNITS[unit]
        why = (f" (its mass of {mass_alone:g} kg then gives {mass_alone / (volume * f ** 3):.4g} kg/m^3; no other "
               "unit gives a plausible size and density)" if volume and mass_alone else
               " (no other unit gives a plausible size)")
        return UnitFix(unit, f"{what}: {UNIT_WORDS[unit]}{why}; the recipe sets units: {unit}",
                       f"{kind} mesh {name} is {across} across as the original scales it: {UNIT_WORDS[unit]}{why}")
    offer = ("mm" if extent * s > PART_SIZE_RANGE[1] else "m")
    offer = offer if offer in units or not units else units[0]
    f = UNITS[offer]
    return UnitFix(None, f"{what}: {UNIT_WORDS[offer]}? add scale=\"{f:g} {f:g} {f:g}\" "
                         f"(or units: {offer} in the recipe)")


def apply(fix: UnitFix, use: MeshUse, geoms: list[dict], mesh_text: str) -> MeshUse:
    """Set the recipe's ``units`` of every geometry of the link that draws the mesh."""
    for geom in geoms:
        if geom.get("mesh") == mesh_text:
            rest = {k: v for k, v in geom.items() if k not in ("mesh", "scale", "units")}
            geom.clear()
            geom.update({"mesh": mesh_text, **({"units": fix.unit} if fix.unit != "m" else {}), **rest})
    f = UNITS[fix.unit]
    return replace(use, scale=(f, f, f))
