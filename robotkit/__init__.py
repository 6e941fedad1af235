"""robotkit: a declarative build system for robot description assets."""

import os as _os

# MuJoCo picks its GL backend when it is first imported: robotkit renders its pictures
# offscreen (software OSMesa, no display) unless the user chose another backend.
_os.environ.setdefault("MUJOCO_GL", "osmesa")

__version__ = "0.1.0"
