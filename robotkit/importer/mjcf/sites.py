"""MuJoCo sites as the recipe's frames: each site a link of its own without mass or shape, fixed
to its body's link at the site's pose (a ``<frame>`` in model.sdf, a link in the URDF, a body
without mass holding a site of the link's name in the rebuilt MJCF: :func:`robotkit.emit.mjcf.frame_site`).  ROS reads them as tf frames (a gripper's pinch point, an IMU's
mounting).  What a site draws (its type, size, colour) is on the ledger."""

from __future__ import annotations

import numpy as np

from robotkit.importer.mjcf.frames import origin, quat_matrix
from robotkit.importer.names import valid_frame_name

SHAPES = {2: "sphere", 3: "capsule", 4: "ellipsoid", 5: "cylinder", 6: "box"}
"""MuJoCo's site types by number (mjtGeom)."""


def add_sites(src, tree, ledger) -> None:
    """One frame link per site of a body that is a link (``tree.sites``: site id -> link name), but
    an IMU's, whose sensor makes its frame."""
    m, specs = src.model, list(src.spec.sites)
    for s in range(m.nsite):
        b = int(m.site_bodyid[s])
        site = m.site(s).name
        where = src.where(specs[s]) if s < len(specs) and specs[s].name == site else src.where_named("site", site)
        label = f"site '{site}'" if site else f"site #{s}"
        if s in tree.sites:  # an IMU's (robotkit.importer.mjcf.sensors): its sensor's frame
            continue
        if b not in tree.link_of:  # the world's, when the robot is its own root (base: free)
            ledger.add(where, label, "all", "dropped: a site of the world, and the robot has no world link")
            continue
        name = free_name(tree, site if valid_frame_name(site) else f"site{s}")
        parent = tree.link_of[b]
        joint = {"type": "fixed", "parent": parent, "child": name}
        o = site_origin(m, tree, s)
        if o:
            joint["origin"] = o
        tree.links[name] = {}
        tree.joints[free_name(tree, f"{name}_fixed", tree.joints)] = joint
        tree.sites[s] = name
        renamed = f" '{name}'" if name != site else ""
        ledger.add(where, label, "mjcf", f"a frame link{renamed} (in the rebuilt MJCF a body without mass holding a "
                   f"site of its name): its {_shape(m, s)} is not drawn")


def site_origin(m, tree, s: int) -> dict | None:
    """The recipe ``origin`` of site ``s`` in its body's link frame (None for the identity)."""
    b = int(m.site_bodyid[s])
    return origin(np.asarray(m.site_pos[s], float) - tree.offset[b], quat_matrix(m.site_quat[s]))


def _shape(m, s: int) -> str:
    kind = SHAPES.get(int(m.site_type[s]), "shape")
    used = {"sphere": 1, "capsule": 2, "cylinder": 2}.get(kind, 3)
    return f"{kind} of size " + " ".join(f"{float(v):g}" for v in m.site_size[s][:used])


def free_name(tree, base: str, taken: dict | None = None) -> str:
    """``base``, or ``base_2``, ``base_3``... the first not taken (by a link, or in ``taken``)."""
    taken = tree.links if taken is None else taken
    name, n = base, 2
    while name in taken or (taken is tree.links and name in tree.joints):
        name, n = f"{base}_{n}", n + 1
    return name
