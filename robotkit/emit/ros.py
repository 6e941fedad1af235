"""Robot -> the files that make the output folder a ROS package for the recipe's ``ros``.

ROS 1: a catkin package (package.xml format 3, CMakeLists.txt with ``catkin_package()``, an
env hook that puts the models on ``GAZEBO_MODEL_PATH``), ``launch/display.launch`` and
``launch/gazebo.launch`` (roslaunch XML). ROS 2: an ament_cmake package (an ament environment
hook for ``GZ_SIM_RESOURCE_PATH`` / ``GAZEBO_MODEL_PATH``), ``launch/display.launch.py`` and
``launch/gazebo.launch.py``. Both: ``rviz/<robot>.rviz``.

Every package a launch file starts, and every plugin package the URDF and the controllers
name, is an ``exec_depend`` (:func:`exec_depends`), so the lists cannot drift apart.
"""

from __future__ import annotations

import math

import numpy as np
import yaml

from robotkit.emit import layout
from robotkit.emit.controllers import controllers
from robotkit.emit.env import fmt, render
from robotkit.emit.formats import Format
from robotkit.emit.sensors import ros_topics
from robotkit.emit.srdf import moving_joints
from robotkit.model.resolve import recenter_offset
from robotkit.model.robot import Robot

# controller type prefix -> the package that provides it
CONTROLLER_PACKAGES = {"position_controllers", "velocity_controllers", "effort_controllers",
                       "joint_trajectory_controller", "joint_state_controller", "joint_state_broadcaster"}


# the templates of the files that differ between ROS 1 and ROS 2
ENV_HOOK = {"ros1": "ros/env-hook.sh.in.j2", "ros2": "ros/env-hook.dsv.in.j2"}
DISPLAY_LAUNCH = {"ros1": "ros/display.launch.j2", "ros2": "ros/display.launch.py.j2"}
GAZEBO_LAUNCH = {"ros1": "ros/gazebo.launch.j2", "ros2": "ros/gazebo.launch.py.j2"}


def is_ros1(robot: Robot) -> bool:
    return robot.ros == "ros1"


def flavour(robot: Robot) -> str:
    return "ros1" if is_ros1(robot) else "ros2"


def has_moveit(robot: Robot) -> bool:
    """The package holds a MoveIt 2 configuration (:mod:`robotkit.emit.moveit`): asked for
    (``moveit``), ROS 2, and a planning group (a joint that moves)."""
    return robot.moveit and not is_ros1(robot) and bool(moving_joints(robot))


# what launch/moveit.launch.py starts and loads (the controller packages come with the actuators)
MOVEIT_PACKAGES = {"moveit_ros_move_group", "moveit_kinematics", "moveit_planners_ompl", "moveit_ros_visualization",
                   "moveit_simple_controller_manager", "python3-yaml"}


def folders(robot: Robot) -> list[str]:
    """The folders of the package, as the build writes them (CMakeLists installs each)."""
    out = [top(layout.URDF)]
    if robot.meshes():
        out.append(layout.MESHES)
    out += [top(layout.MJCF), top(layout.DISPLAY_LAUNCH["ros2"]), top(layout.RVIZ), top(layout.SRDF)]
    if robot.actuators or has_moveit(robot):
        out.append(top(layout.CONTROLLERS))  # config/ (and config/moveit/)
    if robot.worlds:
        out.append(layout.WORLDS)
    return out


def top(template: str) -> str:
    """The top folder of a path template of :mod:`robotkit.emit.layout`."""
    return template.split("/", 1)[0]


def controller_names(robot: Robot) -> list[str]:
    """The controllers of config/controllers.yaml, in the order the launch file spawns them."""
    if not robot.actuators:
        return []
    data = controllers(robot)
    if is_ros1(robot):
        return [k for k in data if k != "gazebo_ros_control"]
    return [k for k in data["controller_manager"]["ros__parameters"] if k != "update_rate"]


def _controller_packages(robot: Robot) -> set[str]:
    if not robot.actuators:
        return set()
    data = controllers(robot)
    if is_ros1(robot):
        types = [v["type"] for k, v in data.items() if k != "gazebo_ros_control"]
    else:
        types = [v["type"] for k, v in data["controller_manager"]["ros__parameters"].items() if k != "update_rate"]
    return {t.split("/")[0] for t in types}


def exec_depends(robot: Robot) -> list[str]:
    """Every package the launch files start, the URDF's plugins load and the controllers need."""
    deps = {"robot_state_publisher", "joint_state_publisher", "joint_state_publisher_gui"}
    if is_ros1(robot):
        deps |= {"rviz", "gazebo_ros"}
        if robot.sensors:
            deps.add("gazebo_plugins")
        if robot.actuators:
            deps |= {"controller_manager", "gazebo_ros_control"} | _controller_packages(robot)
        return sorted(deps)
    deps |= {"ament_index_python", "launch", "launch_ros", "rviz2"}
    if robot.gazebo == "sim":
        deps |= {"ros_gz_sim", "ros_gz_bridge"}
        if any(t["type"] == "contact" for t in ros_topics(robot)):
            deps.add("ros_gz_interfaces")
        if robot.actuators:
            deps.add("gz_ros2_control")
    else:
        deps.add("gazebo_ros")
        if robot.sensors:
            deps.add("gazebo_plugins")
        if robot.actuators:
            deps.add("gazebo_ros2_control")
    if robot.actuators:
        deps |= {"controller_manager"} | _controller_packages(robot)
    if has_moveit(robot):
        deps |= MOVEIT_PACKAGES | ({"joint_trajectory_controller"} if robot.actuators else set())
    return sorted(deps)


def _version(v: str) -> str:
    return v + ".0" * (2 - v.count("."))


def render_package_xml(robot: Robot) -> str:
    return render("ros/package.xml.j2", robot=robot, md=robot.metadata, version=_version(robot.metadata.version),
                  ros1=is_ros1(robot), exec_depends=exec_depends(robot))


def render_cmakelists(robot: Robot) -> str:
    return render("ros/CMakeLists.txt.j2", robot=robot, ros1=is_ros1(robot), folders=folders(robot))


def render_env_hook(robot: Robot) -> str:
    return render(ENV_HOOK[flavour(robot)], robot=robot)


def render_display_launch(robot: Robot) -> str:
    """RViz with the joint state publisher starting at the ``home`` pose (its ``zeros``)."""
    home = robot.home()
    return render(DISPLAY_LAUNCH[flavour(robot)], robot=robot, zeros=dict(home.values) if home else {})


def spawn_pose(robot: Robot) -> dict:
    """Where launch/gazebo places the robot by default: its first world's spawn pose, else the origin."""
    pose = next((w.spawn for w in robot.worlds if w.spawn is not None), None)
    xyz, rpy = (pose.xyz, pose.rpy) if pose is not None else ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    return {"x": xyz[0], "y": xyz[1], "z": xyz[2], "roll": rpy[0], "pitch": rpy[1], "yaw": rpy[2]}


def bridge(robot: Robot) -> list[str]:
    """ros_gz_bridge arguments: the clock and every sensor topic (Gazebo Sim -> ROS)."""
    out = ["/clock@rosgraph_msgs/msg/Clock[gz.msgs.Clock"]
    out += [f"{t['topic']}@{t['ros_type']}[{t['gz_type']}" for t in ros_topics(robot) if t["gz_type"]]
    return out


def render_gazebo_launch(robot: Robot) -> str:
    template = GAZEBO_LAUNCH[flavour(robot)]
    pose = {k: fmt(v) for k, v in spawn_pose(robot).items()}
    return render(template, robot=robot, worlds=[w.name for w in robot.worlds], pose=pose,
                  controllers=controller_names(robot), bridge=bridge(robot))


# ---------------------------------------------------------------- RViz


def _motion(joint, q: float) -> np.ndarray:
    """The transform a joint at position ``q`` adds after its origin."""
    from scipy.spatial.transform import Rotation  # scipy: heavy, only for the RViz file

    T = np.eye(4)
    axis = np.asarray(joint.axis, dtype=float) / np.linalg.norm(joint.axis)
    if joint.type in ("revolute", "continuous"):
        T[:3, :3] = Rotation.from_rotvec(axis * q).as_matrix()
    elif joint.type == "prismatic":
        T[:3, 3] = axis * q
    return T


def link_poses(robot: Robot, q: dict[str, float] | None = None) -> dict[str, np.ndarray]:
    """Every link's pose in the root frame, the joints at ``q`` (by name; default 0; mimic joints follow)."""
    q = dict(q or {})
    for j in robot.joints:
        if j.mimic is not None:
            q[j.name] = j.mimic.multiplier * q.get(j.mimic.joint, 0.0) + j.mimic.offset
    children: dict[str, list] = {}
    for j in robot.joints:
        children.setdefault(j.parent, []).append(j)
    poses = {robot.root: np.eye(4)}
    stack = [robot.root]
    while stack:
        name = stack.pop()
        for j in children.get(name, []):
            poses[j.child] = poses[name] @ j.origin.matrix() @ _motion(j, q.get(j.name, 0.0))
            stack.append(j.child)
    return poses


def _corners(geom, facts: dict) -> np.ndarray | None:
    s = geom.shape
    if s.kind == "box":
        half = np.asarray(s.size) / 2
    elif s.kind in ("cylinder", "capsule"):
        half = np.array([s.radius, s.radius, s.length / 2 + (s.radius if s.kind == "capsule" else 0.0)])
    elif s.kind == "sphere":
        half = np.full(3, s.radius)
    elif s.kind == "mesh" and s.mesh is not None and s.mesh.key in facts:
        f = facts[s.mesh.key]
        lo, hi = np.asarray(f["bbox_min"]), np.asarray(f["bbox_max"])
        return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    else:
        return None
    return np.array([[x, y, z] for x in (-half[0], half[0]) for y in (-half[1], half[1])
                     for z in (-half[2], half[2])])


def bounds(robot: Robot, facts: dict) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned box around the visual geometry and every link origin, in the root frame
    (``robot`` as resolved: recentering offsets are taken from the mesh ``facts``)."""
    poses = link_poses(robot)
    points = [T[:3, 3] for T in poses.values()]
    for link in robot.links:
        for g in link.visuals:
            c = _corners(g, facts)
            if c is not None:
                T = poses[link.name] @ g.origin.then(recenter_offset(g, facts)).matrix()
                points.extend(c @ T[:3, :3].T + T[:3, 3])
    pts = np.array(points)
    return pts.min(axis=0), pts.max(axis=0)


def _round(x: float, digits: int = 3) -> float:
    """``x`` to ``digits`` significant figures (keeps the .rviz file readable and stable)."""
    if x == 0:
        return 0.0
    return float(round(x, digits - 1 - int(math.floor(math.log10(abs(x)))))) + 0.0


def camera(robot: Robot, facts: dict) -> dict:
    """An orbit view that shows the whole robot: focal point at its centre, distance from its size
    (RViz's vertical field of view is 45 degrees; the robot's bounding sphere fills 80 % of it)."""
    lo, hi = bounds(robot, facts)
    radius = max(float(np.linalg.norm(hi - lo)) / 2, 0.05)
    centre = (lo + hi) / 2
    distance = radius / math.sin(math.radians(22.5)) / 0.8
    return {"distance": _round(distance), "focal": [_round(float(v)) for v in centre], "radius": radius}


def rviz_config(robot: Robot, facts: dict) -> dict:
    ros1 = is_ros1(robot)
    cls = (lambda name: f"rviz/{name}") if ros1 else (lambda name: f"rviz_default_plugins/{name}")
    view = camera(robot, facts)
    cell = _round(max(0.1, 10 ** math.floor(math.log10(view["radius"]))), 1)

    def topic(name: str) -> object:
        return name if ros1 else {"Value": name, "Depth": 5, "History Policy": "Keep Last",
                                  "Reliability Policy": "Best Effort", "Durability Policy": "Volatile"}

    robot_model = {"Class": cls("RobotModel"), "Name": "RobotModel", "Enabled": True, "Visual Enabled": True,
                   "Collision Enabled": False, "Alpha": 1}
    if ros1:
        robot_model["Robot Description"] = "robot_description"
    else:
        robot_model["Description Source"] = "Topic"
        robot_model["Description Topic"] = {"Value": "/robot_description", "Depth": 5, "History Policy": "Keep Last",
                                            "Reliability Policy": "Reliable", "Durability Policy": "Transient Local"}
    displays = [
        {"Class": cls("Grid"), "Name": "Grid", "Enabled": True, "Cell Size": cell, "Plane Cell Count": 20,
         "Reference Frame": "<Fixed Frame>"},
        robot_model,
        {"Class": cls("TF"), "Name": "TF", "Enabled": True, "Show Names": False, "Show Axes": True,
         "Show Arrows": False, "Marker Scale": _round(max(view["radius"], 0.1), 2)},
    ]
    for t in ros_topics(robot):
        if t["display"] is None:
            continue
        d = {"Class": cls(t["display"]), "Name": t["sensor"], "Enabled": True}
        if t["display"] == "Image":
            d["Image Topic" if ros1 else "Topic"] = topic(t["topic"])
        else:
            d["Topic"] = topic(t["topic"])
        if t["display"] == "LaserScan":
            d.update({"Style": "Points", "Size (Pixels)": 3, "Color Transformer": "FlatColor",
                      "Color": "255; 0; 0"})
        displays.append(d)
    views = {"Current": {"Class": cls("Orbit"), "Name": "Current View", "Distance": view["distance"],
                         "Focal Point": dict(zip("XYZ", view["focal"])), "Pitch": 0.5, "Yaw": 0.8,
                         "Target Frame": "<Fixed Frame>"}, "Saved": None}
    panel = "rviz/Displays" if ros1 else "rviz_common/Displays"
    return {
        "Panels": [{"Class": panel, "Name": "Displays"}],
        "Visualization Manager": {
            "Class": "",
            "Displays": displays,
            "Enabled": True,
            "Global Options": {"Background Color": "48; 48; 48", "Fixed Frame": robot.root, "Frame Rate": 30},
            "Name": "root",
            "Tools": [{"Class": cls("Interact")}, {"Class": cls("MoveCamera")}, {"Class": cls("Select")},
                      {"Class": cls("FocusCamera")}, {"Class": cls("Measure")}],
            "Value": True,
            "Views": views,
        },
        "Window Geometry": {"Height": 800, "Width": 1200, "X": 0, "Y": 0},
    }


def render_rviz(robot: Robot, facts: dict | None = None) -> str:
    header = f"# RViz configuration for {robot.name}, generated by robotkit; edit the recipe, not this file.\n"
    return header + yaml.safe_dump(rviz_config(robot, facts or {}), sort_keys=False, default_flow_style=False)


def losses(robot: Robot) -> list[str]:
    """What the package lacks that the recipe must give (printed as build warnings)."""
    out = []
    if not robot.metadata.maintainers:
        out.append("no maintainer: package.xml names none, and catkin and colcon refuse a package without one "
                   "(give metadata.maintainers, or an author with an email)")
    return out


FORMATS = [
    # a ROS package is its URDF's: without it, none of it (a package naming a missing file)
    Format("package.xml", render_package_xml, layout.PACKAGE_XML, ("ros/package.xml.j2",), reads="ros-package",
           needs=("urdf",)),
    Format("CMakeLists.txt", render_cmakelists, layout.CMAKELISTS, ("ros/CMakeLists.txt.j2",), reads="ros-package",
           needs=("package.xml", "urdf", "sdf", "model.config", "env-hook")),  # it installs them
    Format("env-hook", render_env_hook, layout.ENV_HOOK, tuple(ENV_HOOK.values()), reads="ros-package",
           needs=("package.xml",)),
    Format("display-launch", render_display_launch, layout.DISPLAY_LAUNCH, tuple(DISPLAY_LAUNCH.values()),
           reads="ros-package", needs=("urdf", "rviz")),
    Format("gazebo-launch", render_gazebo_launch, layout.GAZEBO_LAUNCH, tuple(GAZEBO_LAUNCH.values()),
           reads="ros-package", needs=("urdf", "controllers")),
    Format("rviz", render_rviz, layout.RVIZ, reads="rviz", needs=("urdf",)),
]
