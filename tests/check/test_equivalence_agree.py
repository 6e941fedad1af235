"""robotkit's own outputs agree with each other and with every consumer, on robots of the shapes
where they once did not (issue 32's corpus): each test builds a small robot of that shape."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from conftest import write_recipe
from robotkit.check.consumers import Build, consumer_findings
from robotkit.check.equivalence import equivalence
from robotkit.check.kinematics import pose_difference, rpy_matrix
from robotkit.check.simulation import smoke_test
from robotkit.pipeline.runner import build
from validators import mujoco, require


def built(tmp_path: Path, text: str) -> Path:
    recipe = write_recipe(tmp_path, text)
    result = build([recipe], tmp_path / "out")
    assert not result.errors, result.errors
    return tmp_path / "out" / next(p.name for p in (tmp_path / "out").iterdir())


def assert_agree(robot: Path, consumers=("Gazebo (URDF)", "Gazebo (model.sdf)")):
    require("ign")
    mujoco()
    result = equivalence(robot, tol=1e-9, configs=20)
    assert result == {k: [] for k in result}, json.dumps(result, indent=1)
    name = robot.name
    b = Build(name, robot, robot / "urdf" / f"{name}.urdf", robot / "model.sdf", robot / "mjcf" / f"{name}.xml")
    findings, _ = consumer_findings(b, list(consumers), configs=20)
    assert [str(f) for f in findings if f.severity == "error"] == []


# ------------------------------------------------ 1. tolerances (Lynxmotion AL5D)

AL5D = """
    robot: al5d_like
    defaults:
      joint: {type: revolute, axis: [0, 0, 1], limit: {lower: -1.570796325, upper: 1.570796325, effort: 1, velocity: 1}}
    links:
      base: {visual: {box: {size: [0.08, 0.08, 0.05]}}}
      link1: {visual: {box: {size: [0.05, 0.05, 0.04]}}}
      link2: {visual: {box: {size: [0.14, 0.02, 0.02]}, origin: {xyz: [0.07, 0, 0]}}}
      link3: {visual: {box: {size: [0.18, 0.02, 0.02]}, origin: {xyz: [0.09, 0, 0]}}}
    joints:
      j1: {parent: base, child: link1, origin: {xyz: [0, 0, 0.06858], rpy: [0, 3.141592653, 0]}}
      j2: {parent: link1, child: link2, origin: {xyz: [0.002, 0, 0], rpy: [0, 1.570796325, -1.570796325]}}
      j3: {parent: link2, child: link3, origin: {xyz: [0.14679, 0, 0], rpy: [0, 3.141592653, 1.570796325]}}
    """


@pytest.mark.slow
def test_a_pitch_of_half_pi_agrees_through_libsdformat(tmp_path):
    # libsdformat prints a pitch of 1.570796325 back as 1.570796311893735 (1.5e-8 in the
    # rotation): its arithmetic, not a difference of robotkit's outputs
    assert_agree(built(tmp_path, AL5D))


def test_pose_difference_names_a_turn_and_a_shift():
    A = np.eye(4)
    B = np.eye(4)
    B[:3, :3] = rpy_matrix(0, 0, 1e-6)
    assert pose_difference(A, B, 1e-7) == "at [0.0, 0.0, 0.0], turned by 1e-06 rad"
    assert pose_difference(A, B, 1e-5) is None
    B = np.eye(4)
    B[:3, 3] = [0, 2.4e-19, 0]  # next to a zero reference: absolute, as far as a metre is relative
    assert pose_difference(A, B, 1e-9) is None
    B[:3, 3] = [0, 2e-9, 0]
    assert pose_difference(A, B, 1e-9) == "[0.0, 0.0, 0.0] vs [0.0, 2e-09, 0.0]"


# ------------------------------------------------ 2. massless chains (PhantomX Pincher, TurtleBot arm)

PINCHER = """
    robot: pincher_like
    defaults:
      joint: {type: revolute, axis: [0, 1, 0], limit: {lower: -2.6, upper: 2.6, effort: 30, velocity: 1.5}}
    links:
      base_link: {}
      arm_base_link: {}
      servo: {visual: {box: {size: [0.025, 0.038, 0.047]}}, inertial: {mass: 0.055}}
      pan: {visual: {box: {size: [0.025, 0.038, 0.009]}}, inertial: {mass: 0.008}}
      f10: {visual: {box: {size: [0.025, 0.038, 0.004]}}, inertial: {mass: 0.004}}
    joints:
      arm_base_joint: {type: fixed, parent: base_link, child: arm_base_link, origin: {xyz: [0.1, 0.03, 0.435]}}
      servo_joint: {type: fixed, parent: arm_base_link, child: servo, origin: {rpy: [1.570795, 0, 1.570795]}}
      pan_joint: {parent: servo, child: pan, origin: {xyz: [0, 0.019, 0], rpy: [-1.570795, 1.570795, 3.14159]},
                  axis: [0, 0, -1]}
      f10_joint: {type: fixed, parent: pan, child: f10, origin: {xyz: [0, 0, 0.0545]}}
    """


@pytest.mark.slow
def test_a_massless_root_two_fixed_joints_above_the_first_mass(tmp_path):
    # the massless root is model.sdf's model frame; the link that carries it sits at every
    # fixed joint between them, not at the last one only (0.45 m off on the PhantomX arm)
    robot = built(tmp_path, PINCHER)
    sdf = ET.parse(robot / "model.sdf").getroot()
    assert sdf.find("model/link[@name='servo']/pose").text == "0.1 0.03 0.435 1.570795 0 1.570795"
    assert_agree(robot)


# ------------------------------------------------ 4. a joint to the world (Valkyrie forearm descriptions)

FOREARM = """
    robot: forearm_like
    links:
      world: {}
      forearm: {visual: {box: {size: [0.1, 0.3, 0.13]}, origin: {xyz: [0, -0.13, 0]}}, inertial: {mass: 2.476}}
      wrist: {visual: {box: {size: [0.03, 0.03, 0.03]}}, inertial: {mass: 0.14}}
    joints:
      yaw: {type: revolute, parent: world, child: forearm, origin: {xyz: [-0.0254, 0, 0]}, axis: [0, 1, 0],
            limit: {lower: -2.019, upper: 3.14, effort: 26, velocity: 5}}
      roll: {type: revolute, parent: forearm, child: wrist, origin: {xyz: [0, -0.2871, 0]}, axis: [1, 0, 0],
             limit: {lower: -0.625, upper: 0.62, effort: 14, velocity: 1}}
    """


@pytest.mark.slow
def test_a_joint_that_moves_a_link_against_the_world(tmp_path):
    # model.sdf and libsdformat's URDF keep the joint to the world: the SDF reader keeps it too
    robot = built(tmp_path, FOREARM)
    sdf = ET.parse(robot / "model.sdf").getroot()
    assert sdf.find("model/joint[@name='yaw']/parent").text == "world"
    assert_agree(robot)
    # the forearm hangs from the world at z = 0, 65 mm below it: the floor makes room
    floor = ET.parse(robot / "mjcf" / "scene.xml").getroot().find("worldbody/geom[@name='robotkit_floor']")
    assert floor.get("pos") == "0 0 -0.065"
    assert smoke_test(robot / "mjcf" / "scene.xml", seconds=0.5) == []
