"""Each body's mass properties exactly as MuJoCo computed them (``body_mass``, ``body_ipos``,
``body_iquat``, ``body_inertia``: from the file's inertial, or from its geoms when the file
says so), written as the link's explicit inertial: the full tensor in the link's axes; a body
moved by several joints gives a point mass to each link of its chain
(robotkit.importer.mjcf.chainmass)."""

from __future__ import annotations

import numpy as np

from robotkit.importer.mjcf.chainmass import place_chain_masses, recipe_tensor
from robotkit.importer.mjcf.frames import clean, quat_matrix


def add_inertials(src, tree, ledger) -> None:
    m = src.model
    for b in range(1, m.nbody):
        link = tree.links[tree.link_of[b]]
        mass = float(m.body_mass[b])
        if mass <= 0:
            if link.get("visual") is not None or link.get("collision") not in (None, "none"):
                link["inertial"] = "none"  # MuJoCo gave it no mass: not computed from its shapes
            continue
        R = quat_matrix(m.body_iquat[b])
        full = R @ np.diag(m.body_inertia[b]) @ R.T
        com = clean(np.array(m.body_ipos[b], float) - tree.offset[b])
        link["inertial"] = {"mass": mass, "com": com, "inertia": recipe_tensor(full)}
    place_chain_masses(src, tree, ledger)
