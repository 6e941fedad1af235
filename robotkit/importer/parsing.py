"""Reading values out of URDF elements for the importer: numbers, vectors, origins, and the
list of problems (one line each, naming the file) that an import collects before it fails."""

from __future__ import annotations

import math
import os

from robotkit.errors import Problem, RobotkitError
from robotkit.importer.recipe_writer import fmt


def shown(path: str | os.PathLike) -> str:
    """A path as a message names it: relative to the cwd (``../ws/pkg/robot.urdf`` too), so that
    a line of the URDF can be opened from where the command ran."""
    try:
        return os.path.relpath(os.path.normpath(os.path.abspath(path)))
    except ValueError:  # another drive (Windows)
        return os.fspath(path)


class Problems:
    def __init__(self, file: str):
        self.file = file
        self.items: list[Problem] = []

    def add(self, message: str, line: int | None = None):
        """A problem of the input file; with its ``line``, the file is named relative to the cwd."""
        self.items.append(Problem(message, file=self.file if line is None else shown(self.file), line=line))

    def raise_if_any(self):
        if self.items:
            raise RobotkitError(self.items)


def read_floats(text: str | None, n: int, what: str, problems: Problems, default=None):
    if text is None:
        return list(default) if default is not None else None
    parts = text.split()
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != n or not all(math.isfinite(v) for v in values):
        problems.add(f"{what}: '{text}' is not {n} finite number{'s' if n > 1 else ''}")
        return list(default) if default is not None else None
    return [v + 0.0 for v in values]  # no -0.0


def read_float(text, what, problems, default=None):
    values = read_floats(text, 1, what, problems, None if default is None else [default])
    return None if values is None else values[0]


def read_origin(el, what: str, problems: Problems):
    """(xyz, rpy) of an <origin> child, zeros when absent."""
    if el is None:
        return [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    xyz = read_floats(el.get("xyz"), 3, f"{what} origin xyz", problems, [0.0, 0.0, 0.0])
    rpy = read_floats(el.get("rpy"), 3, f"{what} origin rpy", problems, [0.0, 0.0, 0.0])
    return xyz, rpy


def origin_dict(xyz, rpy) -> dict | None:
    out = {}
    if any(xyz):
        out["xyz"] = list(xyz)
    if any(rpy):
        out["rpy"] = list(rpy)
    return out or None


def local_name(tag) -> str:
    if not isinstance(tag, str):
        return "#comment"
    return tag.rsplit("}", 1)[-1]


def fmt_list(values) -> str:
    return "[" + ", ".join(fmt(v) for v in values) + "]"
