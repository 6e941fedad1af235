"""Contact and simulation settings: a link's sliding friction (the same on all its colliding geoms)
is its ``contact: {mu1}``; every other contact setting that differs from MuJoCo's default (torsional
and rolling friction, condim, solref, solimp, margin, gap, priority, collision bit masks) and every
``<option>`` the rebuilt MJCF does not carry (it writes ``integrator="implicitfast"`` and MuJoCo's
defaults) is one ledger line per body, or per option."""

from __future__ import annotations

from collections import Counter

import numpy as np

from robotkit import mj

REBUILT_OPTION = '<mujoco><option integrator="implicitfast"/><worldbody><geom size="1"/></worldbody></mujoco>'
OPTIONS = ("timestep", "gravity", "wind", "magnetic", "density", "viscosity", "impratio", "o_margin", "integrator",
           "cone", "jacobian", "solver", "iterations", "tolerance", "noslip_iterations", "noslip_tolerance",
           "disableflags", "enableflags", "disableactuator")
GEOM_FIELDS = (("condim", "geom_condim"), ("solref", "geom_solref"), ("solimp", "geom_solimp"),
               ("margin", "geom_margin"), ("gap", "geom_gap"), ("priority", "geom_priority"),
               ("solmix", "geom_solmix"))


NAMED = {"integrator": ("Euler", "RK4", "implicit", "implicitfast"), "cone": ("pyramidal", "elliptic"),
         "jacobian": ("dense", "sparse", "auto"), "solver": ("PGS", "CG", "Newton")}


def _option(name: str, value) -> str:
    names = NAMED.get(name)
    return names[int(value)] if names and 0 <= int(value) < len(names) else _text(value)


def _text(value) -> str:
    arr = np.atleast_1d(np.asarray(value, dtype=float))
    return " ".join(f"{v:g}" for v in arr)


def add_contacts(src, tree, ledger) -> None:
    m, ref = src.model, mj.load().MjModel.from_xml_string(REBUILT_OPTION)
    for name in OPTIONS:
        mine, theirs = getattr(m.opt, name), getattr(ref.opt, name)
        if not np.array_equal(np.asarray(mine), np.asarray(theirs)):
            ledger.add(src.where_tag("option"), f"option {name}", "all",
                       f"{_option(name, mine)} dropped: the rebuilt MJCF has {_option(name, theirs)} (the recipe has "
                       "no simulation options)")
    for b in range(m.nbody):
        geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] == b and (m.geom_contype[g] or m.geom_conaffinity[g])]
        if geoms and b in tree.link_of:
            _body_contacts(src, tree, ledger, b, geoms, ref)


def _body_contacts(src, tree, ledger, b: int, geoms: list[int], ref) -> None:
    m = src.model
    link = tree.links[tree.link_of[b]]
    slide = Counter(float(m.geom_friction[g][0]) for g in geoms)
    mu, _ = slide.most_common(1)[0]
    if mu != float(ref.geom_friction[0][0]):
        link["contact"] = {"mu1": mu}
    lost = []
    if len(slide) > 1:
        lost.append("sliding friction " + ", ".join(f"{v:g}" for v in sorted(slide)) + f" (written {mu:g})")
    for label, attr in (("torsional friction", 1), ("rolling friction", 2)):
        values = {float(m.geom_friction[g][attr]) for g in geoms} - {float(ref.geom_friction[0][attr])}
        if values:
            lost.append(f"{label} " + ", ".join(f"{v:g}" for v in sorted(values)))
    for label, field in GEOM_FIELDS:
        default = np.asarray(getattr(ref, field)[0])
        values = sorted({_text(getattr(m, field)[g]) for g in geoms
                         if not np.allclose(getattr(m, field)[g], default, rtol=1e-6, atol=0)})
        if values:
            lost.append(f"{label} " + "; ".join(values))
    masks = sorted({(int(m.geom_contype[g]), int(m.geom_conaffinity[g])) for g in geoms} - {(1, 1)})
    if masks:
        lost.append("contype/conaffinity " + ", ".join(f"{a}/{c}" for a, c in masks)
                    + " (the rebuild filters by the self-collision matrix)")
    if lost:
        ledger.add(src.where_named("body", m.body(b).name), f"body '{m.body(b).name}' contacts", "all",
                   "dropped: " + "; ".join(lost))
