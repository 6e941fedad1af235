"""Robot -> Gazebo model.config (the ROS package files are robotkit.emit.ros)."""

from __future__ import annotations

from robotkit.emit.env import render
from robotkit.model.robot import Robot


def render_model_config(robot: Robot, sdf: str) -> str:
    return render("gazebo/model.config.j2", robot=robot, md=robot.metadata, sdf=sdf)

