"""The declaration of an output format: each emitter module lists its own at its bottom
(``FORMATS = [Format(...), ...]``) and :mod:`robotkit.emit` merges them into one registry.

The build's tasks (:mod:`robotkit.pipeline.tasks`) and the tests loop over that registry: a new
output format is one module with its declaration, and nothing else names it."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Mapping

from robotkit.model.robot import Robot

READS = {
    "robot": "the finalized robot: geometry with its recentering offsets, collision pieces, inertials",
    "summary": "the finalized robot and every mesh fact (keyword facts)",
    "rviz": "the resolved robot without inertials, and the facts of its shown meshes (keyword facts)",
    "ros-package": "name, metadata, ros, gazebo, sensors, actuators, worlds, whether there are meshes, whether "
                   "it has a MoveIt configuration",
    "structure": "name, ros, gazebo, actuators",
    "groups": "name, base, joints, link names, poses, and the self-collision matrix",
    "metadata": "name and metadata",
}
"""What part of the robot an output depends on: what its task hashes and which records it waits for."""


class Limit(str):
    """A loss that is the format's nature, not the recipe's doing (MJCF has no velocity limit,
    URDF no armature): ``report.json`` lists it once per build under ``limits``, never as a
    warning, since no recipe could avoid it.  Every other loss is a warning."""

    __slots__ = ()


@dataclass(frozen=True)
class Format:
    """One output file of a robot's build folder."""

    name: str
    """The output's task: ``<robot>:<name>``."""
    render: Callable[..., str]
    """(robot, **options) -> the file's text; reads no file."""
    path: str | Mapping[str, str]
    """Below ``OUT/<robot>/``: a template of :mod:`robotkit.emit.layout` (a mapping: per ROS version)."""
    templates: tuple[str, ...] = ()
    """The templates it renders (an edit rebuilds the output)."""
    reads: str = "robot"
    """A key of :data:`READS`."""
    consumed: bool = False
    """A program loads it as a robot: not written for a robot that a program would refuse."""
    options: Mapping[str, object] = field(default_factory=dict)
    """Keyword arguments of ``render``."""
    needs: tuple[str, ...] = ()
    """The formats whose files it names or describes (a launch file reads the URDF; model.config names
    model.sdf): not written when one of them is not (a consumer would refuse it), so that a build
    folder holds no file naming a missing one."""
    when: Callable[[Robot], bool] | None = None
    """Written only for the robots this accepts (default: every robot)."""
    points: Callable[[Robot], list[str]] | None = None
    """The mesh files below ``meshes/`` whose vertices ``render`` needs (keyword ``points``: file ->
    vertices); the build reads them after writing them."""

    def __post_init__(self):
        if self.reads not in READS:
            raise ValueError(f"format '{self.name}': reads '{self.reads}' is not one of {', '.join(READS)}")

    def wanted(self, robot: Robot) -> bool:
        return self.when is None or self.when(robot)
