"""SDF collision surfaces as the recipe link's ``contact`` (mu1, mu2, kp, kd: ODE's friction and
contact stiffness, which the build writes into every format): when a link's collisions agree on
them.  What else a surface sets away from SDF's defaults (slip, soft_cfm, bounce...) has no place
in the recipe, nor do friction values that differ between one link's collisions: stated, one
line per link."""

from __future__ import annotations

from robotkit.importer.sdf.model import children
from robotkit.recipe.schema import MAX_VALUE

MAPPED = {"friction/ode/mu": "mu1", "friction/ode/mu2": "mu2", "contact/ode/kp": "kp", "contact/ode/kd": "kd"}
DEFAULTS = {"slip1": 0.0, "slip2": 0.0, "fdir1": (0.0, 0.0, 0.0), "max_vel": 0.01, "min_depth": 0.0,
            "soft_cfm": 0.0, "soft_erp": 0.2, "restitution_coefficient": 0.0, "threshold": 100000.0,
            "laser_retro": 0.0, "max_contacts": 10.0, "collide_bitmask": 65535.0, "mu": 1.0, "mu2": 1.0,
            "coefficient": 1.0, "use_patch_radius": 1.0, "patch_radius": 0.0, "surface_radius": 0.0,
            "cfm": 0.0, "erp": 0.2, "torsional/ode/slip": 0.0}
"""SDF's defaults of surface elements (libsdformat's collision.sdf, surface.sdf): set to these,
nothing is lost."""


def add_contacts(src, m, tree, ledger) -> dict[str, list[str]]:
    """Each link's ``contact``; link -> what of its surfaces is dropped (for its ledger line).  A
    value above the recipe's largest (youbot's kp of 1e13) is written as that (1e12, SDF's own
    default kp: both a rigid contact), one ledger line per value."""
    dropped: dict[str, list[str]] = {}
    capped: dict[tuple[str, float], list[str]] = {}
    for name, link in m.links.items():
        found, other = [], []
        for c in children(link.el, "collision"):
            surface = c.find("surface")
            other += _unmapped(c, surface, name)
            if surface is not None:
                found.append({key: float(surface.findtext(path)) for path, key in MAPPED.items()
                              if (surface.findtext(path) or "").strip()})
        values = found[0] if found and all(f == found[0] for f in found) else None
        if found and values is None:
            other.append("friction and contact stiffness that differ between its collisions")
        elif values:
            bad = {k: v for k, v in values.items() if v < 0 or (k == "kp" and v == 0)}
            other += [f"{k} {v:g} (negative)" for k, v in bad.items()]
            kept = {k: v for k, v in values.items() if k not in bad}
            for k, v in kept.items():
                if v > MAX_VALUE:
                    capped.setdefault((k, v), []).append(name)
                    kept[k] = MAX_VALUE
            if kept:
                tree.links[name]["contact"] = kept
        if other:
            dropped[name] = [f"its collisions' {', '.join(dict.fromkeys(other))} (the recipe's contact is a link's "
                             "mu1, mu2, kp, kd)"]
    for (key, value), links in capped.items():
        named = ", ".join(f"'{n}'" for n in links)
        ledger.add(src.where("link", links[0]), f"contact {key} {value:g} of link{'s' if len(links) > 1 else ''} "
                   f"{named}", "all", f"approximated: written {MAX_VALUE:g}, the largest the recipe takes")
    return dropped


def _unmapped(collision, surface, link: str) -> list[str]:
    """The surface (and laser_retro) settings away from SDF's defaults that the recipe cannot hold."""
    out = []
    retro = collision.findtext("laser_retro")
    if retro and float(retro) != 0.0:
        out.append("laser_retro")
    if surface is None:
        return out
    for leaf in surface.iter():
        if not isinstance(leaf.tag, str) or len(leaf) or leaf is surface:
            continue
        path = "/".join(a.tag for a in reversed(list(leaf.iterancestors())) if a is not surface
                        and surface in a.iterancestors()) + ("/" if leaf.getparent() is not surface else "") + leaf.tag
        if path in MAPPED:
            continue
        if not _default(leaf.tag, path, leaf.text):
            out.append(f"<{leaf.tag}>")
    return out


def _default(tag: str, path: str, text: str | None) -> bool:
    want = DEFAULTS.get(path, DEFAULTS.get(tag))
    try:
        values = tuple(float(v) for v in (text or "").split())
    except ValueError:
        return False
    if want is None:
        return not values
    return values == (want if isinstance(want, tuple) else (want,))
