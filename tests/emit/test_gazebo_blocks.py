"""Verbatim <gazebo> blocks (urdf_extras) carried into model.sdf as libsdformat's URDF
conversion carries them: sensors into the link the block names (or the link that carries a
frame link), surface tags into its collisions, plugins into the model; turtlebot3's imu and
lidar against `ign sdf -p` of its URDF."""

from __future__ import annotations

import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from conftest import RECIPES, write_recipe
from robotkit.geometry import rpy_matrix
from validators import ign_sdf_check, require

BLOCKS = """
robot: blocks
links:
  base:
    visual: {box: {size: [0.2, 0.2, 0.1]}}
    collision: {box: {size: [0.2, 0.2, 0.1]}}
    inertial: {mass: 1}
  imu_link: {}
  wheel:
    visual: {cylinder: {radius: 0.05, length: 0.02}}
    collision: {cylinder: {radius: 0.05, length: 0.02}}
    inertial: {mass: 0.1}
joints:
  imu_joint: {type: fixed, parent: base, child: imu_link, origin: {xyz: [0.1, 0, 0.05]}}
  wheel_joint:
    type: continuous
    parent: base
    child: wheel
    origin: {xyz: [0, 0.1, 0]}
    axis: [0, 1, 0]
urdf_extras:
  - >-
    <gazebo reference="imu_link"><sensor name="imu" type="imu"><always_on>true</always_on>
    <imu><noise><type>gaussian</type></noise></imu></sensor>
    <gravity>false</gravity></gazebo>
  - >-
    <gazebo reference="wheel"><mu1>0.8</mu1><mu2>0.7</mu2><fdir1>1 0 0</fdir1><maxVel>0.1</maxVel>
    <maxContacts>4</maxContacts><material>Gazebo/Black</material><turnGravityOff>true</turnGravityOff>
    <dampingFactor>0.01</dampingFactor><kp value="1000000.0"/><kd>1</kd>
    <visual><plugin filename="draw.so" name="draw"/></visual>
    <sensor name="wheel_imu" type="imu"><pose>0 0 0.01 0 0 0</pose></sensor></gazebo>
  - >-
    <gazebo reference="wheel_joint"><provideFeedback>true</provideFeedback><stopErp>0.2</stopErp>
    <springStiffness>5</springStiffness></gazebo>
  - >-
    <gazebo><plugin filename="p.so" name="imu_plugin"><bodyName>imu_link</bodyName></plugin>
    <static>false</static></gazebo>
  - <gazebo reference="nowhere"><sensor name="lost" type="imu"/></gazebo>
  - <transmission name="t"><type>transmission_interface/SimpleTransmission</type></transmission>
"""


@pytest.fixture
def blocks(tmp_path):
    from robotkit.model.load import load_robots
    from robotkit.model.resolve import finalize

    [(_, robot)] = load_robots([write_recipe(tmp_path, BLOCKS, "blocks.yaml")])
    return finalize(robot, {}, {})


def test_gazebo_blocks_go_where_libsdformat_puts_them(blocks, tmp_path):
    from robotkit.emit.sdf import render_sdf

    text = render_sdf(blocks)
    (tmp_path / "model.sdf").write_text(text)
    ign_sdf_check(tmp_path / "model.sdf")
    model = ET.fromstring(text).find("model")
    link = {x.get("name"): x for x in model.findall("link")}
    assert set(link) == {"base", "wheel"} and model.find("frame[@name='imu_link']") is not None
    # a frame link's sensor: in the link that carries it, posed relative to the frame
    imu = link["base"].find("sensor[@name='imu']")
    assert imu.find("pose").get("relative_to") == "imu_link" and imu.findtext("pose") == "0 0 0 0 0 0"
    assert imu.findtext("always_on") == "true"
    wheel_imu = link["wheel"].find("sensor[@name='wheel_imu']")
    assert wheel_imu.find("pose").get("relative_to") is None and wheel_imu.findtext("pose") == "0 0 0.01 0 0 0"
    # surface tags into the link's collisions, the material into its visuals
    collision = link["wheel"].find("collision")
    assert [(e.tag, e.text) for e in collision.find("surface/friction/ode")] == [
        ("mu", "0.8"), ("mu2", "0.7"), ("fdir1", "1 0 0")]
    assert collision.findtext("surface/contact/ode/max_vel") == "0.1"
    # a tag's value attribute is its value (<kp value="1e6"/>, as libsdformat reads it)
    assert (collision.findtext("surface/contact/ode/kp"), collision.findtext("surface/contact/ode/kd")) == (
        "1000000.0", "1")
    assert "draw.so" not in text  # a <visual> block: listed (test_only_what_cannot_be_carried_is_a_loss)
    assert collision.findtext("max_contacts") == "4"
    assert link["wheel"].findtext("visual/material/script/name") == "Gazebo/Black"
    assert link["base"].find("visual/material") is None
    assert link["wheel"].findtext("gravity") == "false" and link["base"].find("gravity") is None
    assert [(e.tag, e.text) for e in link["wheel"].find("velocity_decay")] == [("linear", "0.01"), ("angular", "0.01")]
    # a joint's tags into the joint; the model's into the model, a plugin's body moved to the carrier
    physics = model.find("joint[@name='wheel_joint']/physics")
    assert (physics.findtext("provide_feedback"), physics.findtext("ode/limit/erp")) == ("true", "0.2")
    assert model.findtext("static") == "false"
    plugin = model.find("plugin[@name='imu_plugin']")
    assert [(e.tag, e.text) for e in plugin] == [("bodyName", "base"), ("xyzOffset", "0.1 0 0.05"),
                                                  ("rpyOffset", "0 0 0")]
    assert "lost" not in text and "transmission" not in text


def test_only_what_cannot_be_carried_is_a_loss(blocks):
    from robotkit.emit.sdf import losses

    assert [x for x in losses(blocks) if "gazebo" in x or "urdf_extras" in x] == [
        "<gazebo reference=\"imu_link\">: <sensor name=\"imu\">: <imu><noise> not in model.sdf: SDF 1.5 moved an "
        "IMU's noise into <angular_velocity> and <linear_acceleration>",
        "<gazebo reference=\"imu_link\">: <gravity> not in model.sdf: 'imu_link' is a frame there (massless, "
        "fixed), carried by 'base'",
        "<gazebo reference=\"wheel\">: <visual> not in model.sdf: the SDF visuals are the recipe's, named by "
        "robotkit",
        "<gazebo reference=\"wheel_joint\">: <springStiffness> not in model.sdf: model.sdf writes the recipe's "
        "joint dynamics",
        "<gazebo reference=\"nowhere\">: <sensor> not in model.sdf: 'nowhere' names no link or joint of the robot",
        "1 urdf_extras element that is not a <gazebo> block is in the URDF only, not in model.sdf: "
        "<transmission name=\"t\">",
    ]


def test_a_second_sensor_of_one_name_in_one_link_is_a_loss(tmp_path):
    """TALOS' URDF names two sensors of its head camera 'rgbd_frame_sensor': libsdformat refuses
    a link holding both (`ign sdf -k`: "sensor with name[rgbd_frame_sensor] already exists")."""
    from robotkit.emit.sdf import losses, render_sdf
    from robotkit.model.load import load_robots
    from robotkit.model.resolve import finalize

    text = BLOCKS.split("urdf_extras:")[0] + """urdf_extras:
  - >-
    <gazebo reference="wheel"><sensor name="cam" type="depth"><update_rate>6</update_rate></sensor>
    <sensor name="cam" type="depth"><update_rate>30</update_rate></sensor></gazebo>
"""
    [(_, robot)] = load_robots([write_recipe(tmp_path, text, "twice.yaml")])
    robot = finalize(robot, {}, {})
    assert [x for x in losses(robot) if "gazebo" in x] == [
        '<gazebo reference="wheel">: <sensor name="cam"> not in model.sdf: link \'wheel\' has a <sensor> of '
        "that name already (SDF needs them apart)"]
    sdf = tmp_path / "model.sdf"
    sdf.write_text(render_sdf(robot))
    wheel = ET.parse(sdf).getroot().find("model/link[@name='wheel']")
    assert [s.findtext("update_rate") for s in wheel.findall("sensor")] == ["6"]
    require("ign")
    ign_sdf_check(sdf)


# --- turtlebot3: its recipe's blocks against libsdformat's conversion of its URDF ------------


@pytest.fixture(scope="module")
def turtlebot3(tmp_path_factory) -> Path:
    from robotkit.pipeline.runner import build

    out = tmp_path_factory.mktemp("turtlebot3")
    result = build([RECIPES / "turtlebot3_burger.yaml"], out)
    assert not result.errors
    return out / "turtlebot3_burger"


def _matrix(pose: str) -> np.ndarray:
    v = [float(x) for x in pose.split()]
    T = np.eye(4)
    T[:3, :3] = rpy_matrix(v[3:])
    T[:3, 3] = v[:3]
    return T


def _in_model(model: ET.Element, element: ET.Element, owner: str) -> np.ndarray:
    """The pose of ``element`` (of link ``owner``) in the model frame, following ``relative_to``
    through links, joints and frames (SDF 1.9: a pose without it is relative to the owner)."""
    named = {e.get("name"): e for tag in ("link", "joint", "frame") for e in model.findall(tag)}

    def frame(name: str) -> np.ndarray:
        if name == "__model__":
            return np.eye(4)
        e = named[name]
        pose = e.find("pose")
        default = "__model__" if e.tag == "link" else e.findtext("child") if e.tag == "joint" \
            else e.get("attached_to")
        rel = pose.get("relative_to", default) if pose is not None else default
        return frame(rel) @ _matrix(pose.text if pose is not None else "0 0 0 0 0 0")

    pose = element.find("pose")
    rel = pose.get("relative_to", owner) if pose is not None else owner
    return frame(rel) @ _matrix(pose.text if pose is not None else "0 0 0 0 0 0")


def _sensors(model: ET.Element) -> dict[str, tuple[str, str, np.ndarray, ET.Element]]:
    """Each sensor: (its link, its type, its pose in the model frame, the element)."""
    return {s.get("name"): (link.get("name"), s.get("type"), _in_model(model, s, link.get("name")), s)
            for link in model.findall("link") for s in link.findall("sensor")}


def _lumped(urdf: Path) -> dict[str, str]:
    """libsdformat's lumping: each URDF link -> the link its fixed joints merge it into."""
    root = ET.parse(urdf).getroot()
    parent = {j.find("child").get("link"): j for j in root.findall("joint")}

    def up(name: str) -> str:
        j = parent.get(name)
        return up(j.find("parent").get("link")) if j is not None and j.get("type") == "fixed" else name
    return {link.get("name"): up(link.get("name")) for link in root.findall("link")}


@pytest.mark.slow
def test_turtlebot3_model_sdf_has_its_imu_and_lidar(turtlebot3):
    ign_sdf_check(turtlebot3 / "model.sdf")
    model = ET.parse(turtlebot3 / "model.sdf").getroot().find("model")
    sensors = _sensors(model)
    assert {n: s[:2] for n, s in sensors.items()} == {"imu": ("base_link", "imu"),
                                                      "lds_lfcd_sensor": ("base_scan", "ray")}
    # the same parameters as the recipe's blocks, element for element
    extras = ET.fromstring("<x>" + "".join(__import__("yaml").safe_load(
        (RECIPES / "include" / "turtlebot3_burger.gazebo.yaml").read_text())["urdf_extras"]) + "</x>")
    for name, (_, _, _, got) in sensors.items():
        want = extras.find(f".//sensor[@name='{name}']")
        if name == "imu":  # imu_link is a frame in model.sdf: the sensor is posed relative to it
            assert got.find("pose").get("relative_to") == "imu_link"
            got.remove(got.find("pose"))
        assert ET.canonicalize(ET.tostring(got), strip_text=True) == ET.canonicalize(ET.tostring(want),
                                                                                     strip_text=True)
    # imu_joint at (-0.032, 0, 0.068) on base_link, 0.01 above the footprint; the lidar 0.172
    assert np.allclose(sensors["imu"][2][:3, 3], [-0.032, 0, 0.078], atol=1e-12)
    assert np.allclose(sensors["lds_lfcd_sensor"][2][:3, 3], [-0.032, 0, 0.182], atol=1e-12)
    plugins = [p.get("name") for p in model.findall("plugin")]
    assert plugins == ["turtlebot3_burger_controller", "imu_plugin"]


@pytest.mark.slow
@pytest.mark.consumers
def test_turtlebot3_sensors_are_those_gazebo_sees_in_its_urdf(turtlebot3):
    """libsdformat's conversion of the URDF (`ign sdf -p`) and model.sdf: the same sensors, of
    the same types, in the same links (up to libsdformat's lumping of fixed joints) at the same
    poses in the model frame; the same model plugins."""
    exe = require("ign")
    urdf = turtlebot3 / "urdf" / "turtlebot3_burger.urdf"
    proc = subprocess.run([exe, "sdf", "-p", str(urdf)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    # libsdformat marks its offsets <ignition::corrected_offsets>: not a well-formed XML name
    theirs = ET.fromstring(proc.stdout.replace("ignition::", "ignition_")).find("model")
    ours = ET.parse(turtlebot3 / "model.sdf").getroot().find("model")
    lumped = _lumped(urdf)
    a, b = _sensors(theirs), _sensors(ours)
    assert sorted(a) == sorted(b) == ["imu", "lds_lfcd_sensor"]
    for name in a:
        assert a[name][1] == b[name][1], name
        assert a[name][0] == lumped[b[name][0]], name
        assert np.allclose(a[name][2], b[name][2], atol=1e-9), name
    assert sorted(p.get("name") for p in theirs.findall("plugin")) == sorted(p.get("name") for p in
                                                                              ours.findall("plugin"))
