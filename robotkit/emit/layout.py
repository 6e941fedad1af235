"""Where every file of a build folder goes: the one place that spells those paths.

``OUT/<robot>/`` is at once a ROS package and a Gazebo model folder.  The output formats
(:mod:`robotkit.emit`) declare their paths with the templates below; everything that reads a
build folder (check, picture, the viewer, the commands) asks :class:`RobotLayout`.  The
build's own records (mesh facts, collision pieces, inertials) live in ``OUT/.robotkit/<robot>/``
(:data:`RECORDS`), the worlds in ``OUT/<world>/`` (:data:`WORLD_FILES`)."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

# below OUT/<robot>/; {name} is the robot's name; a mapping gives the path per ROS version (``ros``)
URDF = "urdf/{name}.urdf"
XACRO = "urdf/{name}.urdf.xacro"
SDF = "model.sdf"
MJCF = "mjcf/{name}.xml"
SCENE = "mjcf/scene.xml"
SUMMARY = "report.json"  # computed inertials, mesh facts, what each format lost
MODEL_CONFIG = "model.config"
PACKAGE_XML = "package.xml"
CMAKELISTS = "CMakeLists.txt"
ENV_HOOK = {"ros1": "env-hooks/50.{name}.sh.in", "ros2": "hooks/{name}.dsv.in"}
DISPLAY_LAUNCH = {"ros1": "launch/display.launch", "ros2": "launch/display.launch.py"}
GAZEBO_LAUNCH = {"ros1": "launch/gazebo.launch", "ros2": "launch/gazebo.launch.py"}
RVIZ = "rviz/{name}.rviz"
SRDF = "srdf/{name}.srdf"
CONTROLLERS = "config/controllers.yaml"
# the MoveIt 2 configuration (robotkit.emit.moveit): inside the robot's own package (docs/ros.md, MoveIt)
MOVEIT = "config/moveit"
MOVEIT_KINEMATICS = "config/moveit/kinematics.yaml"
MOVEIT_JOINT_LIMITS = "config/moveit/joint_limits.yaml"
MOVEIT_CONTROLLERS = "config/moveit/moveit_controllers.yaml"
ROS2_CONTROLLERS = "config/moveit/ros2_controllers.yaml"
MOVEIT_RVIZ = "config/moveit/moveit.rviz"
MOVEIT_LAUNCH = "launch/moveit.launch.py"
PICTURES = "report"  # the picture report's folder
REPORT_HTML = "report/report.html"
MESHES = "meshes"
VISUAL_MESHES = "meshes/visual"
COLLISION_MESHES = "meshes/collision"
WORLDS = "worlds"  # the package's copies of the worlds, without the robot

# below OUT/<world>/ (and OUT/<robot>/worlds/<world>/); {name} is the world's name
WORLD_FILES = ("model.config", "model.sdf", "meshes/{name}.stl", "{name}.world", "scene.xml")

# the build's records, below OUT/.robotkit/<robot>/; {key} is a mesh key, a proxy key or a link's file stem
RECORDS = {"mesh": "mesh/{key}.json", "collision": "collision/{key}.json", "visual": "visual/{key}.json",
           "inertial": "inertial/{key}.json", "pictures": "pictures.json",
           "drives": "drives.json", "self-collision": "self_collision.json"}


def output_path(template: str | Mapping[str, str], name: str, ros: str = "ros2") -> str:
    """The path below ``OUT/<robot>/`` of one of the templates above, for robot ``name`` (and ``ros``)."""
    if not isinstance(template, str):
        template = template[ros]
    return template.format(name=name)


@dataclass(frozen=True)
class RobotLayout:
    """The files of one robot's build folder ``root`` (``OUT/<robot>``)."""

    root: Path

    @property
    def name(self) -> str:
        return self.root.name

    def path(self, template: str | Mapping[str, str], ros: str = "ros2") -> Path:
        return self.root / output_path(template, self.name, ros)

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

    @property
    def meshes(self) -> Path:
        return self.path(MESHES)

    def is_build(self) -> bool:
        """A robotkit build folder: its model.sdf and its mjcf/ folder are there, or its MJCF was
        left out at the format's own limit (:meth:`left_out`)."""
        return self.sdf.is_file() and (self.mjcf.parent.is_dir() or "mjcf" in self.left_out())

    def left_out(self) -> dict[str, str]:
        """The formats the build left out at their own limits, and why (report.json's ``left_out``:
        MJCF for a chain deeper than MuJoCo reads); none without a readable report.json."""
        try:
            lost = json.loads(self.report_json.read_text(encoding="utf-8")).get("left_out", {})
        except (OSError, ValueError, AttributeError):
            return {}
        return lost if isinstance(lost, dict) else {}


def robot_layout(root: str | os.PathLike) -> RobotLayout:
    return RobotLayout(Path(root))
