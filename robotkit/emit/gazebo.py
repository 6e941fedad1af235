"""Robot -> Gazebo model.config (the ROS package files are robotkit.emit.ros)."""

from __future__ import annotations

from robotkit.emit import layout
from robotkit.emit.env import render
from robotkit.emit.formats import Format
from robotkit.model.robot import Robot


def render_model_config(robot: Robot, sdf: str) -> str:
    return render("gazebo/model.config.j2", robot=robot, md=robot.metadata, sdf=sdf)


FORMATS = [Format("model.config", render_model_config, layout.MODEL_CONFIG, ("gazebo/model.config.j2",),
                  reads="metadata", options={"sdf": layout.SDF}, needs=("sdf",))]
