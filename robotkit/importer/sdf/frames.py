"""SDF poses and frames: ``<pose relative_to=...>`` resolved to the model frame, as libsdformat's
frame semantics do (a link's pose is relative to its model, a joint's to its child link, a
frame's to the frame it is attached to; a nested model's names are ``model::name``)."""

from __future__ import annotations

import math

import numpy as np

from robotkit.errors import Problem, RobotkitError
from robotkit.geometry import rpy_matrix
from robotkit.importer.mjcf.frames import quat_matrix

MODEL = "__model__"


def transform(R=None, p=None) -> np.ndarray:
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    if p is not None:
        T[:3, 3] = p
    return T


def pose_of(el) -> tuple[str | None, np.ndarray]:
    """(relative_to, 4x4) of an element's ``<pose>`` (identity when it has none)."""
    p = el.find("pose") if el is not None else None
    if p is None:
        return None, np.eye(4)
    values = [float(v) for v in (p.text or "").split()] or [0.0] * 6
    if len(values) == 7 or p.get("rotation_format") == "quat_xyzw":
        x, y, z, qx, qy, qz, qw = (values + [0.0] * 7)[:7]
        return p.get("relative_to") or None, transform(quat_matrix([qw, qx, qy, qz]), [x, y, z])
    values = (values + [0.0] * 6)[:6]
    rpy = values[3:]
    if (p.get("degrees") or "").strip().lower() in ("true", "1"):
        rpy = [math.radians(v) for v in rpy]
    return p.get("relative_to") or None, transform(np.array(rpy_matrix(rpy), float), values[:3])


class Frames:
    """Every named frame of a model (links, joints, frames, nested models) and its pose in the
    model frame, resolved on demand."""

    def __init__(self, file: str, own: str = ""):
        self.file = file
        self.own = f"{own}::" if own else ""  # the model's own name, which Gazebo classic lets names begin with
        self.spec: dict[str, tuple[str, np.ndarray]] = {MODEL: ("", np.eye(4))}
        self.done: dict[str, np.ndarray] = {MODEL: np.eye(4)}

    def add(self, name: str, relative_to: str, T: np.ndarray) -> None:
        self.spec[name] = (relative_to, T)

    def get(self, name: str, seen: tuple = ()) -> np.ndarray:
        if name in self.done:
            return self.done[name]
        if name not in self.spec and self.own and name.startswith(self.own) and name[len(self.own):] in self.spec:
            return self.get(name[len(self.own):], seen)
        if name not in self.spec:
            raise RobotkitError(Problem(f"a pose relative to '{name}', which is no frame of the model", file=self.file))
        if name in seen:
            raise RobotkitError(Problem(f"the poses relative to '{name}' make a cycle", file=self.file))
        base, T = self.spec[name]
        self.done[name] = self.get(base, seen + (name,)) @ T
        return self.done[name]


def scoped(scope: str, name: str | None, default: str) -> str:
    """A name as written inside nested model ``scope`` (``""`` at the top), qualified."""
    if not name:
        return default
    if name == MODEL:
        return scope[:-2] if scope else MODEL
    if name == "world":
        return "world"
    return scope + name
