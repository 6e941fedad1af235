"""robotkit's own outputs agree with each other and with every consumer, on robots of the shapes
where they once did not (issue 32's corpus): each test builds a small robot of that shape."""

from __future__ import annotations

import json
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from conftest import run_cli, write_recipe
from robotkit.check.consumers import Build, consumer_findings
from robotkit.check.equivalence import equivalence
from robotkit.check.kinematics import pose_difference, rpy_matrix
from robotkit.check.simulation import smoke_test
from robotkit.model.inertia_policy import mujoco_ready
from robotkit.pipeline.runner import build
from validators import mujoco, require


def built(tmp_path: Path, text: str) -> Path:
    recipe = write_recipe(tmp_path, text)
    result = build([recipe], tmp_path / "out")
    assert not result.errors, result.errors
    return next(p for p in sorted((tmp_path / "out").iterdir()) if not p.name.startswith("."))


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


# ------------------------------------------------ 5. tensors MuJoCo refuses (Ginger Knee_Link, Valkyrie IMU frames)

INERTIAS = """
    robot: knee_like
    defaults:
      joint: {type: revolute, axis: [0, 1, 0], limit: {lower: -1, upper: 1, effort: 10, velocity: 1}}
    links:
      thigh: {visual: {box: {size: [0.05, 0.05, 0.3]}}}
      knee:
        visual: {box: {size: [0.05, 0.05, 0.3]}}
        inertial:   # principal moments 0.001, 0.002 and 0.003 (1 + 5e-10): a + b < c, by rounding
          mass: 1
          inertia: {ixx: 0.00108733219254516, ixy: -0.000282321236697518, iyy: 0.00191266780745484,
                    izz: 0.0030000000015}
      imu:   # a rod: its least moment 1e-20 kg m^2, below MuJoCo's floor
        inertial: {mass: 0.01, inertia: {ixx: 1e-20, iyy: 1e-6, izz: 1e-6}}
    joints:
      knee_joint: {parent: thigh, child: knee, origin: {xyz: [0, 0, -0.3]}}
      imu_joint: {type: fixed, parent: knee, child: imu, origin: {xyz: [0, 0, -0.1]}}
    """


@pytest.mark.slow
def test_tensors_that_round_outside_mujocos_inequality_are_written_inside_it(tmp_path):
    robot = built(tmp_path, INERTIAS)
    mj = mujoco()
    model = mj.MjModel.from_xml_path(str(robot / "mjcf" / "scene.xml"))  # it loads
    knee = model.body_inertia[mj.mj_name2id(model, mj.mjtObj.mjOBJ_BODY, "knee")]
    np.testing.assert_allclose(sorted(knee), [0.001, 0.002, 0.003], rtol=1e-9)
    assert_agree(robot, consumers=("MuJoCo (MJCF)", "Gazebo (URDF)", "Gazebo (model.sdf)"))
    urdf = ET.parse(robot / "urdf" / "knee_like.urdf").getroot()  # every format states the same numbers
    mjcf = ET.parse(robot / "mjcf" / "knee_like.xml").getroot()
    i = urdf.find("link[@name='knee']/inertial/inertia").attrib
    assert mjcf.find(".//body[@name='knee']/inertial").get("fullinertia") == " ".join(
        i[k] for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz"))


def test_a_tensor_mujoco_refuses_beyond_rounding_stops_the_build(tmp_path):
    recipe = write_recipe(tmp_path, """
        robot: imu_like
        links:
          base: {visual: {box: {size: [0.1, 0.1, 0.1]}}}
          imu: {inertial: {mass: 1e-6, inertia: {ixx: 1e-17, iyy: 1e-17, izz: 1e-17}}}
        joints:
          imu_joint: {type: fixed, parent: base, child: imu}
        """)
    proc = run_cli("build", recipe, "--out", tmp_path / "out")
    assert proc.returncode == 1
    assert (f"{recipe}:4: links.imu: link 'imu': MuJoCo refuses its inertia (principal moments 1e-17, 1e-17, "
            "1e-17 kg m^2; it needs each at least 1e-13 and the two smaller summing to the largest); give links.imu "
            "an inertia it accepts (inertial.policy: repair raises the moments)") in proc.stderr.splitlines()
    assert not (tmp_path / "out" / "imu_like" / "mjcf" / "imu_like.xml").exists()


def test_mujoco_ready_changes_a_tensor_by_rounding_only():
    normal = np.diag([1.0, 2.0, 2.5])
    assert mujoco_ready(normal) is normal
    ready = mujoco_ready(np.diag([0.001, 0.002, 0.003 * (1 + 5e-10)]))
    assert ready[2, 2] == pytest.approx(0.003 / (1 + 1e-12), rel=1e-15) and ready[0, 0] == 0.001
    assert np.diag(mujoco_ready(np.diag([1e-20, 1e-6, 1e-6]))).tolist() == [1e-13, 1e-6, 1e-6]
    assert mujoco_ready(np.diag([1e-17, 1e-17, 1e-17])) is None  # all below the floor: not rounding
    assert mujoco_ready(np.diag([0.001, 0.002, 0.0031])) is None  # a + b < c by 3 %


# ------------------------------------------------ 3. a <gazebo> block's joint names a lumped link (PR2 grippers)

PALM = """
    robot: palm_like
    links:
      wrist: {visual: {box: {size: [0.05, 0.05, 0.05]}}, inertial: {mass: 0.1}}
      palm: {visual: {box: {size: [0.08, 0.05, 0.03]}}, inertial: {mass: 0.58}}
      parallel: {visual: {box: {size: [0.05, 0.02, 0.02]}}, inertial: {mass: 0.017}}
    joints:
      palm_joint: {type: fixed, parent: wrist, child: palm}
      finger: {type: revolute, parent: palm, child: parallel, origin: {xyz: [0.07, 0.01, 0]}, axis: [0, 0, 1],
               limit: {lower: 0, upper: 0.5, effort: 10, velocity: 1}}
    urdf_extras:
      - >-
        <gazebo><link name="parallel_link"><inertial><mass>0.17</mass></inertial></link>
        <joint name="parallel_root_joint" type="revolute"><parent>parallel</parent><child>palm</child>
        <axis><xyz>0 0 1</xyz></axis><pose>0.05 0.03 0 0 0 0</pose></joint></gazebo>
    """


@pytest.mark.slow
def test_a_gazebo_block_joint_keeps_the_link_it_names(tmp_path):
    # libsdformat would lump 'palm' into 'wrist', then refuse the block's joint ("a pose is
    # relative to 'palm', which the model does not define"): the URDF asks it to keep the link
    robot = built(tmp_path, PALM)
    urdf = ET.parse(robot / "urdf" / "palm_like.urdf").getroot()
    assert urdf.find("gazebo[@reference='palm_joint']/preserveFixedJoint").text == "true"
    proc = subprocess.run(["ign", "sdf", "-k", str(robot / "urdf" / "palm_like.urdf")], capture_output=True, text=True)
    assert "Valid." in proc.stdout, proc.stdout + proc.stderr
    assert_agree(robot)  # the block's link and joint are Gazebo's additions, not compared


def test_a_gazebo_classic_joint_tag_stays_out_of_model_sdf():
    # the PR2's <stopKd>/<stopKp>: libsdformat copies them with a warning, Drake refuses model.sdf
    from robotkit.emit.gazebo import carry
    from robotkit.model.robot import Joint, Link, Robot

    robot = Robot(name="r", links=(Link("a"), Link("b")), joints=(Joint("j", "revolute", "a", "b"),),
                  urdf_extras=('<gazebo reference="j"><stopKd value="1.0"/><provideFeedback>true</provideFeedback>'
                               '</gazebo>',))
    out = carry(robot)
    assert out.losses == ['<gazebo reference="j">: <stopKd> not in model.sdf: an SDF joint has no <stopKd>']
    assert out.joints == {"j": ["<physics>\n  <provide_feedback>true</provide_feedback>\n</physics>"]}


FOLDED = """
    robot: folded
    self_collide: true
    links:
      world: {}
      base: {collision: {box: {size: [0.2, 0.2, 0.1]}}, visual: {box: {size: [0.2, 0.2, 0.1]}}}
      arm: {collision: {box: {size: [0.05, 0.05, 0.05]}}, visual: {box: {size: [0.05, 0.05, 0.05]}}}
      hand: {collision: {box: {size: [0.05, 0.05, 0.05]}}, visual: {box: {size: [0.05, 0.05, 0.05]}}}
    joints:
      mount: {type: fixed, parent: world, child: base, origin: {xyz: [0, 0, 0.05]}}
      fold: {type: revolute, parent: base, child: arm, origin: {xyz: [0, 0, 0.35]}, axis: [1, 0, 0],
             limit: {lower: -1.5, upper: 1.5, effort: 10, velocity: 1}}
      wrist: {type: fixed, parent: arm, child: hand, origin: {xyz: [0, 0, -0.33]}}
    """


@pytest.mark.slow
def test_links_that_touch_each_other_at_the_start_are_not_inside_the_floor(tmp_path):
    # Kinova's j2s6s200 folds onto its base at its zero pose, 72.7 mm deep but above the floor
    robot = built(tmp_path, FOLDED)
    mjcf = robot / "mjcf" / "folded.xml"  # the hand inside the base, 50 mm deep: their contact kept
    mjcf.write_text(mjcf.read_text().replace('<exclude body1="base" body2="hand"/>', ""))
    mj = mujoco()
    model = mj.MjModel.from_xml_path(str(robot / "mjcf" / "scene.xml"))
    data = mj.MjData(model)
    mj.mj_forward(model, data)
    assert min(data.contact[i].dist for i in range(data.ncon)) < -0.04
    assert not any("inside the floor" in p for p in smoke_test(robot / "mjcf" / "scene.xml", seconds=0.2))
