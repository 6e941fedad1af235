"""Link, joint and frame names the recipe refuses (libsdformat takes 'base link', '1st_arm'),
renamed as a ROS frame name holds them, each change on the ledger: the model read (links,
joints, frames, the ends of joints) and the Source's lookups of the original's lines."""

from __future__ import annotations

import re

from robotkit.importer.names import valid_frame_name


def recipe_names(src, m, ledger) -> None:
    """Rename, in ``m``, each link, joint and frame whose name the recipe refuses."""
    taken = set(m.links) | set(m.joints) | set(m.frames)
    new: dict[str, dict[str, str]] = {"link": {}, "joint": {}, "frame": {}}
    for kind, names in (("link", m.links), ("joint", m.joints), ("frame", m.frames)):
        for name in names:
            if not valid_frame_name(name):
                new[kind][name] = _free(_sane(name), taken)
                taken.add(new[kind][name])
    if not any(new.values()):
        return
    links, joints, frames = new["link"], new["joint"], new["frame"]
    for old, name in links.items():
        m.links[old].name = name
    m.links = {links.get(k, k): v for k, v in m.links.items()}
    for j in m.joints.values():
        j.name, j.parent, j.child = joints.get(j.name, j.name), links.get(j.parent, j.parent), links.get(j.child, j.child)
    m.joints = {joints.get(k, k): v for k, v in m.joints.items()}
    m.frames = {frames.get(k, k): (links.get(a, a), T) for k, (a, T) in m.frames.items()}
    for kind, changed in new.items():
        for old, name in changed.items():
            src.renamed_as[kind][name] = old
            ledger.add(src.where(kind, name), f"{kind} '{old}'", "all", f"renamed '{name}' (a recipe name holds "
                       "letters, digits, '_', '-' and '.', a letter or '_' first, with '/' between parts)")


def _sane(name: str) -> str:
    parts = [re.sub(r"[^A-Za-z0-9_.\-]", "_", part) or "_" for part in name.split("/")]
    if not re.match(r"[A-Za-z_]", parts[0]):
        parts[0] = "_" + parts[0]
    return "/".join(parts)


def _free(name: str, taken: set) -> str:
    out, n = name, 2
    while out in taken:
        out, n = f"{name}_{n}", n + 1
    return out
