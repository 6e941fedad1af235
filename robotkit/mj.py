"""MuJoCo for computing (mass matrices, stepping), never for drawing: the one import of it
outside the picture report.

``MUJOCO_GL`` picks MuJoCo's GL backend when it is imported, and an unusable value (a typo, a
backend this machine lacks) makes ``import mujoco`` itself raise.  Computing needs no GL, so
then MuJoCo is imported with rendering off; the picture report says what to install
(robotkit.picture).  Without a value, OSMesa is the default, as the picture report wants it."""

from __future__ import annotations

import os
import sys

from robotkit.ioutil import environ

GL_FAILURE: list[BaseException] = []
"""Why MuJoCo was imported with rendering off (its import error), if it was: the picture report
gives that reason (robotkit.errors.RendererUnavailable) rather than the disabled backend's."""


def load():
    """The ``mujoco`` module (heavy: imported on first use)."""
    if "mujoco" in sys.modules:
        return sys.modules["mujoco"]
    os.environ.setdefault("MUJOCO_GL", "osmesa")  # software GL, no display: what the pictures use
    try:
        import mujoco
    except Exception as exc:  # noqa: BLE001  (RuntimeError: "invalid value for environment variable
        # MUJOCO_GL"; AttributeError: PyOpenGL found no libOSMesa/libEGL; ImportError, OSError...)
        GL_FAILURE.append(exc)
        for name in [n for n in sys.modules if n == "mujoco" or n.startswith("mujoco.")]:
            del sys.modules[name]
        with environ({"MUJOCO_GL": "disable"}):
            import mujoco
    return mujoco
