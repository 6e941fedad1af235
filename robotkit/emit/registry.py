"""The registry of output formats: every emitter module's ``FORMATS`` merged, as trimesh's
``exchange`` loaders are merged.  The doit tasks and the tests loop over it."""

from __future__ import annotations

from robotkit.emit import controllers, gazebo, mjcf, moveit, ros, sdf, srdf, summary, urdf, xacro_macro
from robotkit.emit.formats import Format

# in the order of their tasks
FORMATS: dict[str, Format] = {
    f.name: f for module in (urdf, xacro_macro, sdf, mjcf, srdf, summary, gazebo, ros, controllers, moveit)
    for f in module.FORMATS
}

for _f in FORMATS.values():  # a format waits for the ones it names: a typo would silently not
    if unknown := [n for n in _f.needs if n not in FORMATS]:
        raise ValueError(f"format '{_f.name}' needs unknown formats: {', '.join(unknown)}")
