"""Occupancy map -> the five files of a world folder, rendered in memory, then written.

``DIR/<name>/``: ``model.config``, ``model.sdf`` (a static model whose mesh is
``model://<name>/meshes/<name>.stl``), ``meshes/<name>.stl`` (binary, map frame, metres),
``<name>.world`` (SDF 1.9: sun, ground plane and the walls inline, so it needs no model
path) and ``scene.xml`` (MuJoCo: floor, light, the wall mesh for looks and one collision
box per merged rectangle of wall cells).

Everything is checked and rendered before the first byte is written; each file is then
written atomically and only when its bytes change, so a rebuild rewrites nothing.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

from robotkit.errors import MapError, Problem
from robotkit.emit.env import fmt, render
from robotkit.ioutil import write_if_changed
from robotkit.mesh.export import stl_bytes
from robotkit.paths import name_problem
from robotkit.world.mapfile import load_map
from robotkit.world.walls import check_height, extrude, padded_wall_cells, rectangles, to_map

WALL_RGBA = (0.7, 0.7, 0.7, 1.0)
GROUND_MARGIN = 5.0  # metres of floor around the map
_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$")


class Box(NamedTuple):
    """One collision box as the MJCF attributes read: three numbers each, as text."""

    pos: str
    size: str  # half sizes, as MuJoCo wants them


@dataclass(frozen=True)
class WorldContext:
    """Everything the world templates need, as plain numbers and strings."""

    name: str
    description: str
    mesh_file: str  # relative to meshes/
    model_mesh_uri: str
    world_mesh_uri: str
    wall_rgba: tuple[float, ...]
    ground_centre: tuple[float, float]
    ground_size: tuple[float, float]
    ground_half: tuple[float, float]
    grid_pos: tuple[float, float, float]
    grid_quat: tuple[float, float, float, float]
    boxes: tuple[Box, ...]


def check_name(name: str) -> str:
    if not isinstance(name, str) or not _NAME.match(name):
        raise MapError(Problem(f"{name!r} cannot name a Gazebo model and its files "
                               "(use letters, digits, '_', '-' and '.')", key="name"))
    if (why := name_problem(name)) is not None:
        raise MapError(Problem(f"name {why}", key="name"))
    return name


def world_context(name: str, occupancy_map, height: float, rects) -> WorldContext:
    """The template context: ``rects`` are the wall rectangles in grid cells ([x0, y0, x1, y1])."""
    import numpy as np

    om = occupancy_map
    res = om.resolution
    x, y, yaw = om.origin
    # floor: the map's bounding box in the map frame, with a margin
    m = om.grid_to_map()
    corners = np.array([[0, 0], [om.cols, 0], [0, om.rows], [om.cols, om.rows]], dtype=np.float64)
    cx = m[0, 0] * corners[:, 0] + m[0, 1] * corners[:, 1] + m[0, 2]
    cy = m[1, 0] * corners[:, 0] + m[1, 1] * corners[:, 1] + m[1, 2]
    half = (math.ceil((cx.max() - cx.min()) / 2 + GROUND_MARGIN), math.ceil((cy.max() - cy.min()) / 2 + GROUND_MARGIN))
    centre = (float(round((cx.max() + cx.min()) / 2, 3)), float(round((cy.max() + cy.min()) / 2, 3)))
    # in the grid frame (the map origin and yaw go on the enclosing frame); rounded to the
    # nanometre so that 0.03 * 513 / 2 reads 7.695, not 7.694999999999999
    # Each number is res * k / 2 for a whole k, so it is formatted once per k (a big map has
    # 10^5 boxes and a few thousand distinct k).
    x0, y0, x1, y1 = np.asarray(rects, dtype=np.int64).reshape(-1, 4).T
    k = np.stack([x0 + x1, y0 + y1, x1 - x0, y1 - y0])
    distinct, which = np.unique(k, return_inverse=True)
    text = np.array([fmt(round(res * v / 2, 9) + 0.0) for v in distinct.tolist()], dtype=object)  # + 0.0: no -0
    px, py, sx, sy = text[which.reshape(k.shape)].tolist()
    z = fmt(round(height / 2, 9) + 0.0)
    boxes = tuple(map(Box._make, zip([f"{a} {b} {z}" for a, b in zip(px, py)],
                                     [f"{a} {b} {z}" for a, b in zip(sx, sy)])))
    stem = Path(om.yaml_path).name
    description = (f"Walls {_num(height)} m high from the occupancy map {stem} "
                   f"({om.cols} x {om.rows} cells of {_num(res)} m), built by robotkit.")
    return WorldContext(
        name=name,
        description=description,
        mesh_file=f"{name}.stl",
        model_mesh_uri=f"model://{name}/meshes/{name}.stl",
        world_mesh_uri=f"meshes/{name}.stl",
        wall_rgba=WALL_RGBA,
        ground_centre=centre,
        ground_size=(2 * half[0], 2 * half[1]),
        ground_half=half,
        grid_pos=(x, y, 0.0),
        grid_quat=(math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)),
        boxes=boxes,
    )


def _num(x: float) -> str:
    return fmt(x)


def render_world(name: str, occupancy_map, height: float = 2.0, unknown_as_wall: bool = False,
                 robot: dict | None = None) -> dict[str, bytes]:
    """Every output file of the world, by path relative to ``DIR/<name>/``, as bytes.

    ``robot`` (name, root, xyz, rpy, quat) places a robot built into the same output folder
    in the world and the scene."""
    from types import SimpleNamespace

    padded = padded_wall_cells(occupancy_map, unknown_as_wall)
    mask = padded[1:-1, 1:-1]
    rects = rectangles(mask, padded=padded)
    vertices, faces = extrude(mask, height, padded=padded)  # as walls.mask_mesh, without trimesh (0.8 s)
    del mask, padded  # the whole grid: not kept while the files are made
    vertices[:, :2] = to_map(vertices[:, :2], occupancy_map.grid_to_map())
    mesh = SimpleNamespace(vertices=vertices, faces=faces)
    w = world_context(name, occupancy_map, height, rects)
    return {
        "model.config": render("world/model.config.j2", w=w).encode("utf-8"),
        "model.sdf": render("world/model.sdf.j2", w=w).encode("utf-8"),
        f"meshes/{name}.stl": stl_bytes(mesh),
        f"{name}.world": render("world/world.sdf.j2", w=w, robot=robot).encode("utf-8"),
        "scene.xml": render("world/scene.xml.j2", w=w, robot=robot).encode("utf-8"),
    }


def build_world(map_yaml: str | os.PathLike, out_dir: str | os.PathLike, name: str | None = None,
                height: float = 2.0, unknown_as_wall: bool = False, robot: dict | None = None) -> list[Path]:
    """Read ``map_yaml`` and write the world folder ``out_dir/<name>/``; return the five paths.

    ``name`` defaults to the YAML file's stem.  Raises MapError (nothing written) when the
    map, the name or the height is unusable.
    """
    map_yaml = Path(map_yaml)
    name = map_yaml.stem if name is None else name
    problems: list[Problem] = []
    for check, value in ((check_name, name), (check_height, height)):
        try:
            check(value)
        except MapError as exc:
            problems.extend(exc.problems)
    try:
        occupancy_map = load_map(map_yaml)
    except MapError as exc:
        problems.extend(exc.problems)
    if problems:
        raise MapError(problems)
    files = render_world(name, occupancy_map, float(height), unknown_as_wall, robot)
    folder = Path(out_dir) / name
    paths = []
    for rel, data in files.items():
        path = folder / rel
        write_if_changed(path, data)
        paths.append(path)
    return paths
