"""Drives and poses written the same everywhere: MJCF (armature, gains, gravity compensation,
keyframes), URDF ros2_control (initial values), model.sdf (Gazebo Sim joint controllers), the
display launch (joint_state_publisher zeros), report.json (actuators, poses)."""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pytest

from robotkit.emit.env import fmt
from robotkit.pipeline.runner import build
from tests.model.test_gains import ARM, ARMATURE, ROTOR, GEAR
from tests.conftest import write_recipe

POSES = """
poses:
  home: {hinge: 30 deg}
  low: {hinge: -45 deg}
"""


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("arm")
    text = ARM.replace("EFFORT", "20").replace(
        "ACTUATOR", f"{{gains: auto, motor: {{rotor_inertia: {ROTOR}, gear: {GEAR}}}}}") + POSES
    recipe = write_recipe(tmp, text, "arm.yaml")
    result = build([recipe], tmp / "out")
    assert not result.errors, result.errors
    return tmp / "out" / "arm"


def test_the_mjcf_has_the_armature_the_gains_gravity_compensation_and_a_keyframe_per_pose(arm):
    report = json.loads((arm / "report.json").read_text())
    drive = report["actuators"]["drives"]["hinge"]
    model = mujoco.MjModel.from_xml_path(str(arm / "mjcf" / "scene.xml"))
    assert model.dof_armature[0] == pytest.approx(ARMATURE)
    assert model.actuator_gainprm[0, 0] == drive["p"] and -model.actuator_biasprm[0, 2] == drive["d"]
    assert list(model.actuator_forcerange[0]) == [-20, 20]
    assert model.jnt_actgravcomp[0] and model.body_gravcomp[model.body("arm").id] == 1
    assert [model.key(k).name for k in range(model.nkey)] == ["home", "low"]  # home first: the start
    assert model.key("home").qpos[0] == pytest.approx(math.radians(30))
    assert model.key("home").ctrl[0] == pytest.approx(math.radians(30))
    assert report["poses"] == {"home": {"hinge": pytest.approx(math.radians(30))},
                               "low": {"hinge": pytest.approx(math.radians(-45))}}


def test_the_scene_holds_home_against_gravity(arm):
    model = mujoco.MjModel.from_xml_path(str(arm / "mjcf" / "scene.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    for _ in range(int(2 / model.opt.timestep)):
        mujoco.mj_step(model, data)
    assert abs(data.qpos[0] - math.radians(30)) < math.radians(0.01)


def test_ros2_control_starts_at_home_and_gazebo_sim_gets_the_same_gains(arm):
    report = json.loads((arm / "report.json").read_text())
    drive = report["actuators"]["drives"]["hinge"]
    urdf = ET.parse(arm / "urdf" / "arm.urdf").getroot()
    param = urdf.find("ros2_control/joint[@name='hinge']/state_interface[@name='position']/param")
    assert param.get("name") == "initial_value" and float(param.text) == pytest.approx(math.radians(30))
    plugin = ET.parse(arm / "model.sdf").getroot().find("model/plugin")
    assert plugin.get("name") == "gz::sim::systems::JointPositionController"
    assert {k: float(plugin.find(k).text) for k in ("p_gain", "i_gain", "d_gain", "initial_position",
                                                   "cmd_max")} == {
        "p_gain": pytest.approx(drive["p"], rel=1e-14), "i_gain": 0.0, "d_gain": pytest.approx(drive["d"], rel=1e-14),
        "initial_position": pytest.approx(math.radians(30)), "cmd_max": 20.0}
    launch = (arm / "launch" / "display.launch.py").read_text()
    assert f"ZEROS = {{'zeros.hinge': {fmt(math.radians(30))}}}" in launch  # 15 significant digits, as every number


def test_what_a_format_cannot_carry_is_a_loss(arm):
    report = json.loads((arm / "report.json").read_text())
    losses = report["losses"]
    # URDF has no armature by its nature: a limit (report.json, never a warning); the sag is a warning
    assert report["limits"]["urdf"] == [
        "joint 'hinge': armature is not written (URDF has no such joint property; the MJCF carries it)"]
    assert any(line.startswith("joint 'hinge': the MJCF compensates gravity (gravcomp); model.sdf's joint "
                               "controllers (Gazebo Sim) cannot") for line in losses["sdf"])
    assert any("the ros_control controllers (controllers.yaml) cannot" in line for line in losses["package"])


FREE = """
robot: hopper
base: free
links:
  body: {visual: {box: {size: [0.2, 0.2, 0.1]}}, inertial: {mass: 2 kg}}
  leg: {visual: {sphere: {radius: 0.02}, origin: {xyz: [0, 0, -0.2]}}, inertial: {mass: 0.2 kg}}
joints:
  knee: {type: revolute, parent: body, child: leg, axis: [0, 1, 0], origin: {xyz: [0, 0, -0.05]},
         limit: {lower: -1.5, upper: 1.5, effort: 50, velocity: 5}}
poses:
  home: {knee: 60 deg}
"""


def test_a_free_robot_starts_standing_at_its_home_pose(tmp_path):
    recipe = write_recipe(tmp_path, FREE, "hopper.yaml")
    result = build([recipe], tmp_path / "out")
    assert not result.errors, result.errors
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "out" / "hopper" / "mjcf" / "hopper.xml"))
    key = model.key("home")
    # the foot (0.2 m below the knee, radius 2 cm) swings up by 60 degrees: the body comes down
    foot = 0.05 + 0.2 * math.cos(math.radians(60)) + 0.02
    zero_height = 0.05 + 0.2 + 0.02
    assert model.body("body").pos[2] == pytest.approx(zero_height, abs=1e-6)
    assert key.qpos[2] == pytest.approx(max(foot, 0.05), abs=1e-6)  # the box's bottom, 5 cm below the body
    np.testing.assert_allclose(key.qpos[3:7], [1, 0, 0, 0])
    assert key.qpos[7] == pytest.approx(math.radians(60))
