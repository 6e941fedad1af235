"""Robot -> Gazebo model.config and the ROS package files (package.xml, CMakeLists.txt)."""

from __future__ import annotations

from robotkit.emit.env import render
from robotkit.model.robot import Robot


def render_model_config(robot: Robot, sdf: str) -> str:
    return render("gazebo/model.config.j2", robot=robot, md=robot.metadata, sdf=sdf)


def render_package_xml(robot: Robot) -> str:
    return render("ros/package.xml.j2", robot=robot, md=robot.metadata)


def render_cmakelists(robot: Robot) -> str:
    return render("ros/CMakeLists.txt.j2", robot=robot)
