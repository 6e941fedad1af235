"""Emitters: a finalized Robot -> the text of one output file.

Each emitter module declares its output formats at its bottom (``FORMATS``: name, render
function, path, templates, what it reads, options; :class:`robotkit.emit.formats.Format`);
:data:`FORMATS` merges them, as trimesh's ``exchange`` loaders are merged.  The doit tasks and
the tests loop over this registry.  An emitter reads only the resolved model, never the recipe.
"""

from __future__ import annotations

from robotkit.emit import controllers, gazebo, mjcf, ros, sdf, summary, urdf, xacro_macro
from robotkit.emit.formats import Format

# in the order of their tasks
FORMATS: dict[str, Format] = {
    f.name: f for module in (urdf, xacro_macro, sdf, mjcf, summary, gazebo, ros, controllers)
    for f in module.FORMATS
}
