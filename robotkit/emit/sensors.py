"""Sensor and actuator contexts shared by the URDF, SDF and MJCF emitters.

A sensor sits at the origin of its frame link (x forward, z up, as Gazebo's sensors look).
Frame links are <frame>s in SDF and massless bodies in MJCF, so each sensor is written into
its *host*: the nearest ancestor link that is a real SDF link, with the frame's pose in it.
"""

from __future__ import annotations

import math

import numpy as np

from robotkit.geometry import matrix_rpy
from robotkit.emit.formats import Limit
from robotkit.model.robot import Pose, Robot, Sensor

MJCF_MAX_RAYS = 64
SDF_TYPES = {"camera": "camera", "depth": "depth_camera", "lidar": "gpu_lidar", "sonar": "gpu_lidar",
             "imu": "imu", "contact": "contact"}
CLASSIC_TYPES = {"camera": "camera", "depth": "depth", "lidar": "ray", "sonar": "ray", "imu": "imu",
                 "contact": "contact"}


def host_of(robot: Robot, link: str) -> tuple[str, Pose]:
    """The link that carries ``link`` in SDF (itself, or for a massless frame link the nearest
    ancestor with mass, or a massless root's anchor) and the pose of ``link`` in it."""
    frames = robot.frame_links()
    parent_joint = {j.child: j for j in robot.joints}
    T = np.eye(4)
    name = link
    while name in frames:
        j = parent_joint.get(name)
        if j is None:  # a massless root: a frame on the link fixed below it
            anchor = robot.anchor()
            T = np.linalg.inv(robot.anchor_pose().matrix()) @ T
            name = anchor
            break
        T = j.origin.matrix() @ T
        name = j.parent
    return name, Pose(tuple(float(v) for v in T[:3, 3]), matrix_rpy(T[:3, :3]))


def scan(s: Sensor) -> dict:
    """Ray pattern of a lidar, or of a sonar's cone (5 x 5 rays over its opening)."""
    p = s.params
    if s.type == "lidar":
        return dict(p)
    half = p["fov"] / 2
    return {"samples": 5, "min_angle": -half, "max_angle": half, "vertical_samples": 5,
            "vertical_min_angle": -half, "vertical_max_angle": half, "min_range": p["min_range"],
            "max_range": p["max_range"], "resolution": 0.01, "noise": 0.0}


def sensor_context(robot: Robot, s: Sensor) -> dict:
    host, pose = host_of(robot, s.link)
    ctx = {"name": s.name, "type": s.type, "link": s.link, "update_rate": s.update_rate, "topic": s.topic,
           "params": s.params, "optical_frame": s.optical_frame or s.link, "host": host, "host_pose": pose,
           "sdf_type": SDF_TYPES[s.type], "classic_type": CLASSIC_TYPES[s.type], "ros": robot.ros}
    if s.type in ("lidar", "sonar"):
        ctx["scan"] = scan(s)
    if s.type == "contact":
        n = len(robot.link(s.link).collisions_for("sdf"))
        ctx["collisions"] = [f"collision_{i}" for i in range(n)]
        # names libsdformat gives URDF collisions when it converts the URDF for Gazebo classic
        ctx["classic_collisions"] = [f"{s.link}_collision" + (f"_{i}" if i else "") for i in range(n)]
    return ctx


def contexts(robot: Robot) -> list[dict]:
    return [sensor_context(robot, s) for s in robot.sensors]


# ---------------------------------------------------------------- MJCF


def mjcf_rays(s: Sensor) -> list[tuple[str, tuple[float, float, float]]]:
    """(site name, ray direction in the sensor frame) for MuJoCo rangefinders."""
    if s.type == "sonar":
        return [(f"{s.name}_ray", (1.0, 0.0, 0.0))]
    p = s.params
    h = np.linspace(p["min_angle"], p["max_angle"], p["samples"], endpoint=_open_scan(p))
    v = np.linspace(p["vertical_min_angle"], p["vertical_max_angle"], p["vertical_samples"]) \
        if p["vertical_samples"] > 1 else np.array([0.0])
    rays = [(float(a), float(b)) for b in v for a in h]
    if len(rays) > MJCF_MAX_RAYS:
        idx = np.linspace(0, len(rays) - 1, MJCF_MAX_RAYS).round().astype(int)
        rays = [rays[i] for i in sorted(set(idx))]
    return [(f"{s.name}_ray_{k}", (math.cos(b) * math.cos(a), math.cos(b) * math.sin(a), math.sin(b)))
            for k, (a, b) in enumerate(rays)]


def _open_scan(p) -> bool:
    """A full circle's last ray repeats its first: leave it out."""
    return not math.isclose(p["max_angle"] - p["min_angle"], 2 * math.pi, rel_tol=1e-9)


def mjcf_fovy(p: dict) -> float:
    """MuJoCo's vertical field of view in degrees for a horizontal one and an image size."""
    return math.degrees(2 * math.atan(math.tan(p["hfov"] / 2) * p["height"] / p["width"]))


def mjcf_context(robot: Robot) -> dict[str, dict]:
    """Per body (link): cameras, sites and the sensor elements that read them."""
    out: dict[str, dict] = {}
    sensors: list[dict] = []
    for s in robot.sensors:
        body = out.setdefault(s.link, {"cameras": [], "sites": []})
        if s.type in ("camera", "depth"):
            # MuJoCo cameras look along -z with y up: x right = -y of the link, y up = z of the link
            body["cameras"].append({"name": s.name, "fovy": mjcf_fovy(s.params),
                                    "resolution": (s.params["width"], s.params["height"])})
        elif s.type in ("lidar", "sonar"):
            for site, direction in mjcf_rays(s):
                body["sites"].append({"name": site, "zaxis": direction, "size": 0.005})
                sensors.append({"kind": "rangefinder", "name": site, "site": site,
                                "cutoff": s.params["max_range"]})
        elif s.type == "imu":
            body["sites"].append({"name": f"{s.name}_site", "zaxis": (0.0, 0.0, 1.0), "size": 0.005})
            sensors.append({"kind": "accelerometer", "name": f"{s.name}_accel", "site": f"{s.name}_site"})
            sensors.append({"kind": "gyro", "name": f"{s.name}_gyro", "site": f"{s.name}_site"})
        elif s.type == "contact":
            body["sites"].append({"name": f"{s.name}_site", "zaxis": (0.0, 0.0, 1.0), "size": None,
                                  "touch": True, "link": s.link})
            sensors.append({"kind": "touch", "name": s.name, "site": f"{s.name}_site"})
    return {"bodies": out, "sensors": sensors}


def losses(robot: Robot) -> dict[str, list[str]]:
    sdf, mjcf = [], []
    for s in robot.sensors:
        if s.type == "sonar":
            sdf.append(Limit(f"sensor '{s.name}': Gazebo Sim has no sonar; written as a 5 x 5 gpu_lidar cone"))
            mjcf.append(Limit(f"sensor '{s.name}': MuJoCo has no cone sensor; written as one rangefinder on the axis"))
        if s.type == "lidar":
            n = s.params["samples"] * s.params["vertical_samples"]
            rays = len(mjcf_rays(s))
            if rays < n:
                mjcf.append(Limit(f"sensor '{s.name}': {n} lidar rays written as {rays} MuJoCo rangefinders"))
            if s.params["noise"]:
                mjcf.append(Limit(f"sensor '{s.name}': range noise is not written (MuJoCo sensors have none)"))
        if s.type == "imu" and (s.params["gyro_noise"] or s.params["accel_noise"]):
            mjcf.append(Limit(f"sensor '{s.name}': IMU noise is not written (MuJoCo sensors have none)"))
        if s.type in ("camera", "depth"):
            mjcf.append(Limit(f"sensor '{s.name}': a MuJoCo camera has no clip distances or image format; "
                              "fovy and resolution are written"))
    for compensated in (False, True):  # with gravity compensated in the MJCF, i has no sag to remove there
        drives = [a for a in robot.actuators if a.i and a.gravcomp == compensated]
        if drives:
            names = [a.joint for a in drives]
            more = f" and {len(names) - 1} more ({', '.join(repr(n) for n in names[1:])})" if names[1:] else ""
            gains = ", ".join(sorted({f"{a.i:g}" for a in drives}, key=float))
            text = f"actuator '{names[0]}'{more}: MuJoCo servos have no integral term (i = {gains} dropped)"
            mjcf.append(Limit(text + "; the MJCF compensates gravity instead") if compensated else text)
    return {"sdf": sdf, "mjcf": mjcf}


# ---------------------------------------------------------------- ROS topics


# sensor type -> (RViz display, ROS message, Gazebo Sim message) of the topic it publishes
ROS_MESSAGES = {
    "camera": ("Image", "sensor_msgs/msg/Image", "gz.msgs.Image"),
    "depth": ("Image", "sensor_msgs/msg/Image", "gz.msgs.Image"),
    "lidar": ("LaserScan", "sensor_msgs/msg/LaserScan", "gz.msgs.LaserScan"),
    "sonar": ("Range", "sensor_msgs/msg/Range", None),
    "imu": (None, "sensor_msgs/msg/Imu", "gz.msgs.IMU"),
    "contact": (None, "ros_gz_interfaces/msg/Contacts", "gz.msgs.Contacts"),
}


def ros_topics(robot: Robot) -> list[dict]:
    """The ROS topic each sensor publishes on, as the URDF's Gazebo plugins (or, for Gazebo Sim,
    the ros_gz bridge of launch/gazebo.launch.py) name it: sensor, topic, RViz display (or None),
    ROS message type, Gazebo Sim message type (bridged topics only)."""
    out = []
    for s in robot.sensors:
        display, ros_type, gz_type = ROS_MESSAGES[s.type]
        topic = "/" + s.topic.strip("/")
        if robot.gazebo == "classic" and s.type in ("camera", "depth"):
            topic += "/image_raw"  # gazebo_ros_camera / openni_kinect: <camera name>/image_raw
        if robot.gazebo == "sim" and s.type == "sonar":
            display, ros_type, gz_type = "LaserScan", "sensor_msgs/msg/LaserScan", "gz.msgs.LaserScan"  # a gpu_lidar cone
        if robot.gazebo == "classic" and s.type == "contact":
            ros_type = "gazebo_msgs/msg/ContactsState"  # gazebo_ros_bumper
        if robot.ros == "ros1":
            ros_type = ros_type.replace("/msg/", "/")
        out.append({"sensor": s.name, "type": s.type, "topic": topic, "display": display, "ros_type": ros_type,
                    "gz_type": gz_type if robot.gazebo == "sim" else None, "frame": s.optical_frame or s.link})
    return out
