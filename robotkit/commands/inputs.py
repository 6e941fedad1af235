"""What a PATH given to a command is, and which robot build folders are under it: the one
answer every verb uses (check, report, view, the job summary).

    recipe   a .yaml/.yml recipe
    build    a robot's build folder (OUT/<robot>: model.sdf and mjcf/) or an output folder
             holding several (OUT)
    urdf, xacro, sdf, mjcf   a description file written anywhere
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from pathlib import Path

from robotkit.emit.layout import RobotLayout, robot_layout
from robotkit.errors import Problem, RobotkitError

SUFFIXES = {".yaml": "recipe", ".yml": "recipe", ".urdf": "urdf", ".xacro": "xacro", ".sdf": "sdf",
            ".world": "sdf", ".xml": "mjcf"}
NOT_A_BUILD = "not a build folder (no <robot>/model.sdf below it)"


@dataclass(frozen=True)
class Input:
    kind: str  # recipe | build | urdf | xacro | sdf | mjcf
    path: Path
    robots: tuple[RobotLayout, ...] = ()  # a build folder's robots

    def one_robot(self) -> RobotLayout:
        """The build folder of the one robot under a build PATH (a command that shows one robot)."""
        if len(self.robots) == 1:
            return self.robots[0]
        names = ", ".join(r.name for r in self.robots)
        raise RobotkitError(Problem(f"holds {len(self.robots)} robots ({names}); name one folder", file=str(self.path)))


def robot_dirs(folder: Path) -> list[RobotLayout]:
    """The robot build folders a folder is or holds (sorted); none for any other folder."""
    own = robot_layout(folder)
    if own.sdf.is_file():
        return [own]
    if not folder.is_dir():
        return []
    return [layout for d in sorted(folder.iterdir()) if (layout := robot_layout(d)).is_build()]


def enclosing_build(path: Path) -> RobotLayout | None:
    """The robot build folder a description file sits at the top of (a build's model.sdf), when
    that folder holds its MJCF; None for a file written anywhere else."""
    layout = robot_layout(path.parent)
    return layout if layout.mjcf.is_file() else None


def classify(path: str | os.PathLike, kinds: tuple[str, ...] = ("recipe", "build", "urdf", "xacro", "sdf", "mjcf"),
             expected: str = "a recipe .yaml, .urdf, .xacro, .sdf or MJCF .xml") -> Input:
    """What PATH is, among the ``kinds`` the command takes; bad input raises with the file named."""
    p = Path(path)
    if p.is_dir() and "build" in kinds:
        robots = robot_dirs(p)
        if not robots:
            raise RobotkitError(Problem(NOT_A_BUILD, file=str(path)))
        return Input("build", p, tuple(robots))
    if not p.is_file():
        raise RobotkitError(Problem("no such file or folder", file=str(path)))
    kind = SUFFIXES.get(p.suffix.lower())
    if kind not in kinds:
        raise RobotkitError(Problem(f"unknown kind of file (expected {expected})", file=str(path)))
    return Input(kind, p)


def package_paths(items: list[str]) -> dict[str, str] | None:
    """``--package-path PKG=DIR`` items as a dict; None (after one line on stderr) when one is malformed."""
    packages = {}
    for item in items:
        pkg, sep, folder = item.partition("=")
        if not sep or not pkg or not folder:
            print(f"robotkit: error: --package-path takes PKG=DIR (got '{item}')", file=sys.stderr)
            return None
        packages[pkg] = folder
    return packages
