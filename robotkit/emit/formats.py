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
    limit: Callable[[Robot], str | None] | None = None
    """The format's own limit: why it cannot hold this robot (None: it can).  Not the recipe's
    fault: the build leaves the format out, with every format that needs it, and says so in one
    warning, unless the recipe lists it under ``outputs`` (then its task refuses the robot)."""
    points: Callable[[Robot], list[str]] | None = None
    """The mesh files below ``meshes/`` whose vertices ``render`` needs (keyword ``points``: file ->
    vertices); the build reads them after writing them."""

    def __post_init__(self):
        if self.reads not in READS:
            raise ValueError(f"format '{self.name}': reads '{self.reads}' is not one of {', '.join(READS)}")

    def wanted(self, robot: Robot) -> bool:
        return self.when is None or self.when(robot)


def unknown_outputs(outputs: list[str], formats: Mapping[str, Format]) -> list[str]:
    """The names of ``outputs`` (a recipe's ``outputs:``) that are not formats of ``formats``."""
    return [n for n in outputs if n not in formats]


@dataclass(frozen=True)
class Outputs:
    """The formats a robot's build writes (:func:`outputs_of`)."""

    written: tuple[str, ...]
    """In the registry's order."""
    lost: Mapping[str, str] = field(default_factory=dict)
    """Format -> why it cannot hold the robot (its own limit), left out."""
    with_lost: tuple[str, ...] = ()
    """The formats left out because they need a lost one."""

    def __contains__(self, name: str) -> bool:
        return name in self.written


def outputs_of(robot: Robot, formats: Mapping[str, Format], outputs: list[str] | None = None) -> Outputs:
    """The formats of ``formats`` the build writes for ``robot``: the ones it wants, or the
    recipe's ``outputs`` with every format they need; without ``outputs``, a format at its own
    limit (:attr:`Format.limit`) is lost, with every format that needs it."""
    wanted = [n for n, f in formats.items() if f.wanted(robot)]
    if outputs is not None:
        chosen, todo = set(), list(outputs)
        while todo:
            name = todo.pop()
            if name in formats and name not in chosen:
                chosen.add(name)
                todo += list(formats[name].needs)
        return Outputs(tuple(n for n in wanted if n in chosen))
    lost = {n: why for n in wanted if formats[n].limit is not None and (why := formats[n].limit(robot))}
    gone, changed = set(lost), True
    while changed:
        more = {n for n in wanted if n not in gone and any(m in gone for m in formats[n].needs)}
        gone |= more
        changed = bool(more)
    return Outputs(tuple(n for n in wanted if n not in gone), lost, tuple(n for n in wanted if n in gone - set(lost)))
