"""Name rules of the importer: which URDF names a recipe keeps as they are (links and joints may
hold '/' between parts, as ROS frame names do), and recipe-safe names for what it renames
(materials, a robot without a valid name)."""

from __future__ import annotations

import re

from robotkit.recipe.schema import FRAME_NAME_HINT, FRAME_NAME_RE, NAME_RE


def valid_name(name: str | None) -> bool:
    return bool(name) and bool(NAME_RE.match(name))


def valid_frame_name(name: str | None) -> bool:
    """Link and joint names may hold '/' between parts, as ROS frame names do."""
    return bool(name) and bool(FRAME_NAME_RE.match(name))


def material_name(name: str, taken: set[str]) -> str:
    base = re.sub(r"[^A-Za-z0-9_.\-]", "_", name or "material")
    if not re.match(r"[A-Za-z_]", base):
        base = "_" + base
    out, i = base, 2
    while out in taken:
        out, i = f"{base}_{i}", i + 1
    return out


def name_hint() -> str:
    return FRAME_NAME_HINT
