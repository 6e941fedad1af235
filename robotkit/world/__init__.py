"""Worlds from occupancy maps: map_server YAML + image -> closed wall mesh -> Gazebo world and MuJoCo scene.

Public API (numpy, Pillow and trimesh are imported only when these are called):

* :func:`load_map` reads and checks a map_server YAML file and its image
  (:mod:`robotkit.world.mapfile`).
* :func:`wall_mesh` turns its wall cells into one closed mesh in the map frame
  (:mod:`robotkit.world.walls`).
* :func:`build_world` writes ``DIR/<name>/`` with model.config, model.sdf,
  meshes/<name>.stl, <name>.world and scene.xml (:mod:`robotkit.world.emit`).

Bad input raises :class:`robotkit.errors.MapError` holding one line per problem.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    import trimesh

    from robotkit.world.mapfile import OccupancyMap

__all__ = ["OccupancyMap", "build_world", "load_map", "wall_mesh"]
# The modules doing the work are imported when called: `import robotkit.world` stays free of numpy
# and PIL until a map is read.


def load_map(map_yaml: str | os.PathLike) -> "OccupancyMap":
    """Read a map_server YAML file and its PGM/PNG image; MapError lists every problem."""
    from robotkit.world.mapfile import load_map as _load_map

    return _load_map(map_yaml)


def wall_mesh(occupancy_map: "OccupancyMap", height: float = 2.0, *, unknown_as_wall: bool = False) -> "trimesh.Trimesh":
    """The map's walls, ``height`` metres high, as one closed mesh in the map frame (metres)."""
    from robotkit.world.walls import wall_mesh as _wall_mesh

    return _wall_mesh(occupancy_map, height, unknown_as_wall=unknown_as_wall)


def build_world(map_yaml: str | os.PathLike, out_dir: str | os.PathLike, name: str | None = None,
                height: float = 2.0, unknown_as_wall: bool = False, robot: dict | None = None) -> list[Path]:
    """Write ``out_dir/<name>/`` (name: the YAML's stem by default); return the five file paths.

    Nothing is written when the map, the name or the height is unusable (MapError).
    """
    from robotkit.world.emit import build_world as _build_world

    return _build_world(map_yaml, out_dir, name=name, height=height, unknown_as_wall=unknown_as_wall,
                        robot=robot)


def __getattr__(attr):
    if attr == "OccupancyMap":
        from robotkit.world.mapfile import OccupancyMap

        return OccupancyMap
    raise AttributeError(f"module {__name__!r} has no attribute {attr!r}")
