"""Where every file of a build folder goes: the one place that spells those paths.

``OUT/<robot>/`` is at once a ROS package and a Gazebo model folder.  The output formats
(:mod:`robotkit.emit`) declare their paths with the templates below; everything that reads a
build folder (check, picture, the viewer, the commands) asks :class:`RobotLayout`."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

# below OUT/<robot>/; {name} is the robot's name
URDF = "urdf/{name}.urdf"
XACRO = "urdf/{name}.urdf.xacro"
SDF = "model.sdf"
MJCF = "mjcf/{name}.xml"
SCENE = "mjcf/scene.xml"
SUMMARY = "report.json"  # computed inertials, mesh facts, what each format lost
MODEL_CONFIG = "model.config"
PACKAGE_XML = "package.xml"
CMAKELISTS = "CMakeLists.txt"
RVIZ = "rviz/{name}.rviz"
CONTROLLERS = "config/controllers.yaml"
PICTURES = "report"  # the picture report's folder
REPORT_HTML = "report/report.html"
MESHES = "meshes"
VISUAL_MESHES = "meshes/visual"
COLLISION_MESHES = "meshes/collision"
WORLDS = "worlds"


@dataclass(frozen=True)
class RobotLayout:
    """The files of one robot's build folder ``root`` (``OUT/<robot>``)."""

    root: Path

    @property
    def name(self) -> str:
        return self.root.name

    def path(self, template: str) -> Path:
        return self.root / template.format(name=self.name)

    @property
    def urdf(self) -> Path:
        return self.path(URDF)

    @property
    def sdf(self) -> Path:
        return self.path(SDF)

    @property
    def mjcf(self) -> Path:
        return self.path(MJCF)

    @property
    def scene(self) -> Path:
        return self.path(SCENE)

    @property
    def report_json(self) -> Path:
        return self.path(SUMMARY)

    @property
    def pictures(self) -> Path:
        return self.path(PICTURES)

    @property
    def report_html(self) -> Path:
        return self.path(REPORT_HTML)

    def is_build(self) -> bool:
        """A robotkit build folder: its model.sdf and its mjcf/ folder are there."""
        return self.sdf.is_file() and self.mjcf.parent.is_dir()


def robot_layout(root: str | os.PathLike) -> RobotLayout:
    return RobotLayout(Path(root))
