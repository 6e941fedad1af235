"""Robot -> the MoveIt 2 configuration of its ROS 2 package (recipe ``moveit: true`` or
``robotkit build --moveit``), written statically: MoveIt is not run by the build.

Inside the robot's own package (``config/moveit/``; the SRDF stays ``srdf/<robot>.srdf``,
:mod:`robotkit.emit.srdf`), with MoveIt 2's file names and keys:

- ``kinematics.yaml``: KDL for the planning group (named after the robot) when it is one serial
  chain (KDL solves chains only; otherwise no solver, and a loss line);
- ``joint_limits.yaml``: every joint the planner sets: the URDF's velocity limit, an acceleration
  limit of that velocity reached in :data:`ACCELERATION_TIME`, position limits but for continuous joints;
- ``moveit_controllers.yaml`` and ``ros2_controllers.yaml``: one joint_trajectory_controller per
  command interface of the actuators (:func:`trajectory_controllers`), MoveIt's
  FollowJointTrajectory controllers of the same names;
- ``moveit.rviz``: the package's RViz view with MoveIt's MotionPlanning display;
- ``launch/moveit.launch.py``: robot_state_publisher, move_group and RViz with MoveIt's parameters.

ROS 1 packages get none of it (a loss line in report.json): MoveIt 1's files differ.
"""

from __future__ import annotations

import yaml

from robotkit.emit import layout
from robotkit.emit.controllers import BROADCASTER, TRAJECTORY, UPDATE_RATE, joints_phrase, trajectory_parameters, yaml_file
from robotkit.emit.env import render
from robotkit.emit.formats import Format
from robotkit.emit.ros import has_moveit, is_ros1, rviz_config
from robotkit.emit.srdf import chain, moving_joints
from robotkit.model.robot import Robot

KDL = "kdl_kinematics_plugin/KDLKinematicsPlugin"
SEARCH_RESOLUTION = 0.005  # rad: MoveIt Setup Assistant's default
TIMEOUT = 0.005  # s: MoveIt Setup Assistant's default
ACCELERATION_TIME = 0.1  # s: a joint reaches its velocity limit in this time (max_acceleration = velocity / it)
SCALING = 0.1  # MoveIt Setup Assistant's default velocity and acceleration scaling factors
INTERFACES = ("position", "velocity", "effort")


def group_name(robot: Robot) -> str:
    """The SRDF's one planning group: named after the robot (:func:`robotkit.emit.srdf.render_srdf`)."""
    return robot.name


def kinematics(robot: Robot) -> dict:
    """kinematics.yaml: KDL for the group when it is one serial chain, else nothing."""
    if chain(robot) is None:
        return {}
    return {group_name(robot): {"kinematics_solver": KDL, "kinematics_solver_search_resolution": SEARCH_RESOLUTION,
                                "kinematics_solver_timeout": TIMEOUT}}


def joint_limits(robot: Robot) -> dict:
    """joint_limits.yaml (MoveIt 2's ``robot_description_planning``) for every joint the planner sets."""
    limits = {}
    for j in moving_joints(robot):
        velocity = float(j.limit.velocity) if j.limit is not None and j.limit.velocity else 0.0
        entry = {"has_velocity_limits": velocity > 0, "max_velocity": velocity,
                 "has_acceleration_limits": velocity > 0,
                 "max_acceleration": velocity / ACCELERATION_TIME if velocity > 0 else 0.0}
        bounded = j.type != "continuous" and j.limit is not None and None not in (j.limit.lower, j.limit.upper)
        entry["has_position_limits"] = bounded
        if bounded:
            entry.update(min_position=float(j.limit.lower), max_position=float(j.limit.upper))
        limits[j.name] = entry
    return {"default_velocity_scaling_factor": SCALING, "default_acceleration_scaling_factor": SCALING,
            "joint_limits": limits}


def trajectory_controllers(robot: Robot) -> dict[str, tuple[str, list]]:
    """Controller name -> (command interface, actuators): one joint_trajectory_controller per
    interface (one controller commands one interface); ``<group>_controller`` when the actuators
    share one, else ``<group>_<interface>_controller``."""
    by_interface = {i: [a for a in robot.actuators if a.interface == i] for i in INTERFACES}
    used = {i: acts for i, acts in by_interface.items() if acts}
    group = group_name(robot)
    if len(used) == 1:
        (interface, acts), = used.items()
        return {f"{group}_controller": (interface, acts)}
    return {f"{group}_{i}_controller": (i, acts) for i, acts in used.items()}


def moveit_controllers(robot: Robot) -> dict:
    """moveit_controllers.yaml: moveit_simple_controller_manager with a FollowJointTrajectory
    controller per trajectory controller of ros2_controllers.yaml."""
    manager: dict = {"controller_names": list(trajectory_controllers(robot))}
    for name, (_, acts) in trajectory_controllers(robot).items():
        manager[name] = {"type": "FollowJointTrajectory", "action_ns": "follow_joint_trajectory", "default": True,
                         "joints": [a.joint for a in acts]}
    return {"moveit_controller_manager": "moveit_simple_controller_manager/MoveItSimpleControllerManager",
            "moveit_simple_controller_manager": manager}


def ros2_controllers(robot: Robot) -> dict:
    """ros2_controllers.yaml: a controller manager with the joint state broadcaster and the
    trajectory controllers (parameters as config/controllers.yaml gives its effort controller)."""
    manager: dict = {"update_rate": UPDATE_RATE, "joint_state_broadcaster": dict(BROADCASTER)}
    data: dict = {"controller_manager": {"ros__parameters": manager}}
    for name, (interface, acts) in trajectory_controllers(robot).items():
        manager[name] = {"type": TRAJECTORY}
        data[name] = {"ros__parameters": trajectory_parameters(acts, interface)}
    return data


def render_kinematics(robot: Robot) -> str:
    return yaml_file(robot, kinematics(robot))


def render_joint_limits(robot: Robot) -> str:
    return yaml_file(robot, joint_limits(robot))


def render_moveit_controllers(robot: Robot) -> str:
    return yaml_file(robot, moveit_controllers(robot))


def render_ros2_controllers(robot: Robot) -> str:
    return yaml_file(robot, ros2_controllers(robot))


def render_moveit_rviz(robot: Robot, facts: dict | None = None) -> str:
    """The package's RViz view (:func:`robotkit.emit.ros.rviz_config`) with MoveIt's MotionPlanning display."""
    config = rviz_config(robot, facts or {})
    config["Visualization Manager"]["Displays"].append({
        "Class": "moveit_rviz_plugin/MotionPlanning", "Name": "MotionPlanning", "Enabled": True,
        "Robot Description": "robot_description", "Planning Scene Topic": "/monitored_planning_scene",
        "Move Group Namespace": "", "Planning Request": {"Planning Group": group_name(robot)}})
    header = f"# RViz with MoveIt for {robot.name}, generated by robotkit; edit the recipe, not this file.\n"
    return header + yaml.safe_dump(config, sort_keys=False, default_flow_style=False)


def render_moveit_launch(robot: Robot) -> str:
    return render("ros/moveit.launch.py.j2", robot=robot, srdf=layout.output_path(layout.SRDF, robot.name),
                  urdf=layout.output_path(layout.URDF, robot.name), kinematics=layout.MOVEIT_KINEMATICS,
                  joint_limits=layout.MOVEIT_JOINT_LIMITS, rviz=layout.MOVEIT_RVIZ,
                  controllers=layout.MOVEIT_CONTROLLERS if robot.actuators else None)


def losses(robot: Robot) -> list[str]:
    """What the MoveIt configuration lacks (report.json ``losses.moveit``; build warnings)."""
    if not robot.moveit:
        return []
    if is_ros1(robot):
        return ["the MoveIt configuration is written for ROS 2 (MoveIt 2) only: this ROS 1 package has none "
                "(build it with --ros ros2)"]
    joints = moving_joints(robot)
    if not joints:
        return ["no joint moves: no planning group, so no MoveIt configuration is written"]
    out = []
    if chain(robot) is None:
        out.append(f"group '{group_name(robot)}' is not one serial chain: kinematics.yaml names no IK solver "
                   "(KDL solves chains only); MoveIt plans to joint goals, not to pose goals")
    fixed_speed = [j.name for j in joints if j.limit is None or not j.limit.velocity]
    if fixed_speed:
        out.append(f"{joints_phrase(fixed_speed)}: no velocity limit, so joint_limits.yaml gives MoveIt none and "
                   "no acceleration limit (time parameterization needs both): give the joint limit.velocity")
    actuated = {a.joint for a in robot.actuators}
    idle = [j.name for j in joints if j.name not in actuated]
    if idle:
        out.append(f"{joints_phrase(idle)}: in the planning group without an actuator: no controller moves it, "
                   "so MoveIt cannot execute a plan that moves it")
    return out


def has_controllers(robot: Robot) -> bool:
    return has_moveit(robot) and bool(robot.actuators)


MOVEIT_NEEDS = ("urdf", "srdf")  # MoveIt reads the robot from both
FORMATS = [
    Format("moveit-kinematics", render_kinematics, layout.MOVEIT_KINEMATICS, reads="groups", needs=MOVEIT_NEEDS,
           when=has_moveit),
    Format("moveit-joint-limits", render_joint_limits, layout.MOVEIT_JOINT_LIMITS, reads="groups",
           needs=MOVEIT_NEEDS, when=has_moveit),
    Format("moveit-controllers", render_moveit_controllers, layout.MOVEIT_CONTROLLERS, reads="structure",
           needs=MOVEIT_NEEDS, when=has_controllers),
    Format("ros2-controllers", render_ros2_controllers, layout.ROS2_CONTROLLERS, reads="structure",
           needs=MOVEIT_NEEDS, when=has_controllers),
    Format("moveit-rviz", render_moveit_rviz, layout.MOVEIT_RVIZ, reads="rviz", needs=MOVEIT_NEEDS, when=has_moveit),
    Format("moveit-launch", render_moveit_launch, layout.MOVEIT_LAUNCH, ("ros/moveit.launch.py.j2",),
           reads="ros-package", needs=MOVEIT_NEEDS, when=has_moveit),
]
