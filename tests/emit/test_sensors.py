"""Sensors and actuators in every format: the rover example, the D435 preset against the
upstream xacro, a MuJoCo rangefinder reading a known distance, ros_control outputs."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import yaml

from conftest import RECIPES, write_recipe
from robotkit.pipeline.runner import build
from robotkit.check import kinematics as k
from validators import check_urdf, ign_sdf_check, mujoco


@pytest.fixture(scope="module")
def rover(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("rover")
    result = build([RECIPES / "rover.yaml"], out)
    assert not result.errors
    return out / "rover"


def test_rover_urdf_has_the_d435_frames_and_gazebo_sensor_blocks(rover):
    urdf = rover / "urdf" / "rover.urdf"
    check_urdf(urdf)
    root = ET.parse(urdf).getroot()
    links = {link.get("name") for link in root.findall("link")}
    assert {"camera_bottom_screw_frame", "camera_link", "camera_depth_optical_frame",
            "camera_color_optical_frame", "camera_infra1_frame", "camera_infra2_optical_frame"} <= links
    sensors = {s.get("name"): s.get("type") for s in root.findall("gazebo/sensor")}
    assert sensors == {"camera_color": "camera", "camera_depth": "depth_camera", "scan": "gpu_lidar",
                       "sonar": "gpu_lidar", "imu": "imu", "bumper": "contact"}
    control = root.find("ros2_control")
    assert [j.get("name") for j in control.findall("joint")] == ["left_wheel_joint", "right_wheel_joint"]
    assert control.find("joint/command_interface").get("name") == "velocity"


def test_rover_sdf_is_valid_and_holds_the_sensors(rover):
    ign_sdf_check(rover / "model.sdf")
    model = ET.parse(rover / "model.sdf").getroot().find("model")
    sensors = {s.get("name"): s.get("type") for s in model.iter("sensor")}
    assert sensors == {"camera_color": "camera", "camera_depth": "depth_camera", "scan": "gpu_lidar",
                       "sonar": "gpu_lidar", "imu": "imu", "bumper": "contact"}
    frames = {f.get("name") for f in model.findall("frame")}
    assert "camera_bottom_screw_frame" in frames and "camera_color_optical_frame" in frames
    # sensor frames are SDF frames, not massless links (which Gazebo would give 1 kg)
    assert all(link.find("inertial") is not None for link in model.findall("link"))
    scan = model.find(".//sensor[@name='scan']")
    assert scan.find("pose").get("relative_to") == "scan_link"
    assert scan.findtext("lidar/scan/horizontal/samples") == "360"


def test_rover_mjcf_sensors_give_finite_data(rover):
    mj = mujoco()
    model = mj.MjModel.from_xml_path(str(rover / "mjcf" / "scene.xml"))
    data = mj.MjData(model)
    assert model.ncam == 2
    kinds = {mj.mjtSensor(t).name for t in model.sensor_type}
    assert {"mjSENS_RANGEFINDER", "mjSENS_ACCELEROMETER", "mjSENS_GYRO", "mjSENS_TOUCH"} <= kinds
    for _ in range(500):
        mj.mj_step(model, data)
    assert np.isfinite(data.sensordata).all()
    accel = data.sensordata[model.sensor_adr[mj.mj_name2id(model, mj.mjtObj.mjOBJ_SENSOR, "imu_accel")]:][:3]
    assert accel[2] == pytest.approx(9.81, rel=1e-2)  # at rest on the floor: gravity
    # the camera's vertical field of view matches the horizontal one and the image size
    cam = mj.mj_name2id(model, mj.mjtObj.mjOBJ_CAMERA, "camera_color")
    hfov = 2 * math.atan(math.tan(math.radians(model.cam_fovy[cam]) / 2) * 640 / 480)
    assert hfov == pytest.approx(1.211, rel=1e-9)


def test_rover_drives_forward_in_mujoco(rover):
    mj = mujoco()
    model = mj.MjModel.from_xml_path(str(rover / "mjcf" / "scene.xml"))
    data = mj.MjData(model)
    data.ctrl[:] = [5.0, 5.0]  # wheel speed, rad/s
    for _ in range(1000):
        mj.mj_step(model, data)
    assert data.qpos[0] > 0.1 and abs(data.qpos[1]) < 0.01  # straight ahead along x


def test_camera_link_inertia_is_plausible_for_72_grams(rover):
    inertial = ET.parse(rover / "urdf" / "rover.urdf").getroot().find("link[@name='camera_link']/inertial")
    assert float(inertial.find("mass").get("value")) == 0.072
    i = inertial.find("inertia").attrib
    # a uniform 72 g box of 25.05 x 90 x 25 mm (the aluminium case)
    x, y, z = 0.02505, 0.090, 0.025
    expected = (0.072 / 12 * (y * y + z * z), 0.072 / 12 * (x * x + z * z), 0.072 / 12 * (x * x + y * y))
    got = (float(i["ixx"]), float(i["iyy"]), float(i["izz"]))
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    assert got[0] < 0.003881 / 50  # upstream's hand-typed ixx is ~75x too large


def test_d435_frames_match_the_upstream_xacro(rover, assets, tmp_path):
    import xacro
    import xacro.substitution_args as sa

    root = assets / "realsense2_description"
    sa._eval_find = lambda pkg: str(root)
    sa._eval_dict["find"] = sa._eval_find
    xacro.all_includes.clear()
    doc = xacro.process_file(str(root / "urdf" / "test_d435_camera.urdf.xacro"),
                             mappings={"use_nominal_extrinsics": "true"})
    upstream = tmp_path / "d435.urdf"
    upstream.write_text(doc.toprettyxml(indent="  "))
    theirs = k.read_urdf(upstream).fk({})
    ours = k.read_urdf(rover / "urdf" / "rover.urdf").fk({})
    names = ["bottom_screw_frame", "link", "depth_frame", "depth_optical_frame", "color_frame",
             "color_optical_frame", "infra1_frame", "infra1_optical_frame", "infra2_frame", "infra2_optical_frame"]
    base_t, base_o = theirs["camera_bottom_screw_frame"], ours["camera_bottom_screw_frame"]
    for n in names:
        a = np.linalg.inv(base_t) @ theirs[f"camera_{n}"]
        b = np.linalg.inv(base_o) @ ours[f"camera_{n}"]
        np.testing.assert_allclose(b, a, atol=1e-12, err_msg=n)


def test_rangefinder_reads_a_known_distance(tmp_path):
    mj = mujoco()
    recipe = write_recipe(tmp_path, """
        robot: ranger
        links:
          base: {visual: {box: {size: [0.1, 0.1, 0.1]}}}
        sensors:
          front: {type: sonar, parent: base, origin: {xyz: [0.05, 0, 0.2]}, sonar: {max_range: 5}}
        """)
    build([recipe], tmp_path / "out")
    robot = tmp_path / "out" / "ranger" / "mjcf"
    (robot / "wall.xml").write_text(
        '<mujoco><include file="ranger.xml"/><worldbody>'
        '<geom name="wall" type="box" size="0.05 2 2" pos="1.55 0 0"/></worldbody></mujoco>')
    model = mj.MjModel.from_xml_path(str(robot / "wall.xml"))
    data = mj.MjData(model)
    mj.mj_forward(model, data)
    # the wall's face is at x = 1.5; the sonar sits at x = 0.05
    assert data.sensordata[0] == pytest.approx(1.45, abs=1e-9)


def test_turret_bot_gets_its_ros1_controllers(tmp_path, assets):
    build([RECIPES / "turret_bot.yaml"], tmp_path)
    robot = tmp_path / "turret_bot"
    ours = yaml.safe_load((robot / "config" / "controllers.yaml").read_text())
    theirs = yaml.safe_load((assets / "turret_bot" / "config" / "config.yaml").read_text())
    assert ours["gazebo_ros_control"]["pid_gains"] == theirs["gazebo_ros_control"]["pid_gains"]
    assert ours["j1_controller"] == theirs["j1_controller"]
    urdf = ET.parse(robot / "urdf" / "turret_bot.urdf").getroot()
    assert [t.findtext("joint/hardwareInterface") for t in urdf.findall("transmission")] == [
        "hardware_interface/PositionJointInterface"] * 2
    assert urdf.find("gazebo/plugin").get("filename") == "libgazebo_ros_control.so"
    mj = mujoco()
    model = mj.MjModel.from_xml_path(str(robot / "mjcf" / "turret_bot.xml"))
    assert model.nu == 2 and model.actuator_gainprm[0][0] == 150.0


def test_classic_flavour_uses_gazebo_ros_plugins(tmp_path):
    recipe = write_recipe(tmp_path, """
        robot: classic
        gazebo: classic
        links:
          base: {visual: {box: {size: [0.2, 0.2, 0.1]}}}
        sensors:
          cam: {type: camera, parent: base, origin: {xyz: [0.1, 0, 0.05]}}
          laser: {type: lidar, parent: base}
          range: {type: sonar, parent: base}
          imu: {type: imu, parent: base}
          bump: {type: contact, parent: base}
        """)
    build([recipe], tmp_path / "out")
    urdf = tmp_path / "out" / "classic" / "urdf" / "classic.urdf"
    check_urdf(urdf)
    ign_sdf_check(urdf)  # libsdformat reads the gazebo blocks as Gazebo classic would
    plugins = {s.get("name"): s.find("plugin").get("filename") for s in ET.parse(urdf).getroot().iter("sensor")}
    assert plugins == {"cam": "libgazebo_ros_camera.so", "laser": "libgazebo_ros_ray_sensor.so",
                       "range": "libgazebo_ros_ray_sensor.so", "imu": "libgazebo_ros_imu_sensor.so",
                       "bump": "libgazebo_ros_bumper.so"}
    cam = ET.parse(urdf).getroot().find(".//sensor[@name='cam']")
    assert cam.findtext("plugin/frame_name") == "cam_optical_frame"


def test_sensor_errors_name_the_key(tmp_path):
    from robotkit.errors import RobotkitError

    recipe = write_recipe(tmp_path, """
        robot: bad
        links: {base: {}}
        sensors:
          cam: {type: camera, parent: bsae}
          imu: {type: imu, parent: base, lidar: {samples: 10}}
        actuators:
          nojoint: {interface: position}
        """)
    with pytest.raises(RobotkitError) as err:
        build([recipe], tmp_path / "out")
    assert [str(p).split(":", 2)[2].strip() for p in err.value.problems] == [
        "sensors.cam.parent: no link named 'bsae' (did you mean 'base'?)",
        "sensors.imu: 'lidar' parameters do not apply to imu sensors",
        "actuators.nojoint: no joint named 'nojoint'",
    ]
