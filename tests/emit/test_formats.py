"""SDF and MJCF outputs, validated by ign sdf -k and MuJoCo, and proved equivalent to the URDF
with independent parsers (MuJoCo's URDF and MJCF compilers, libsdformat's URDF conversion,
an SDF frame-graph reader)."""

from __future__ import annotations

import re

import json
import math
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from conftest import GOLDEN, assert_golden, example_robots, run_cli, write_recipe
from robotkit.pipeline.runner import build
from robotkit.check.equivalence import equivalence
from robotkit.check.simulation import smoke_test
from validators import check_urdf, ign_sdf_check, mujoco, require


EXAMPLES = example_robots()


def assert_equivalent(robot_dir: Path, configs: int = 100):
    require("ign")
    mujoco()
    result = equivalence(robot_dir, tol=1e-9, configs=configs)
    assert result == {k: [] for k in result}, json.dumps(result, indent=1)


@pytest.mark.slow
@pytest.mark.parametrize("name", EXAMPLES)
def test_example_outputs_pass_every_validator(examples, name):
    root = examples / name
    for rel in (f"urdf/{name}.urdf", "model.sdf", "model.config", f"mjcf/{name}.xml", "mjcf/scene.xml"):
        assert (root / rel).is_file(), rel
    check_urdf(root / "urdf" / f"{name}.urdf")
    ign_sdf_check(root / "model.sdf")
    mj = mujoco()
    model = mj.MjModel.from_xml_path(str(root / "mjcf" / "scene.xml"))
    assert model.nbody == len(ET.parse(root / "urdf" / f"{name}.urdf").getroot().findall("link")) + 1


@pytest.mark.slow
@pytest.mark.parametrize("name", EXAMPLES)
def test_example_formats_agree(examples, name):
    assert_equivalent(examples / name)


@pytest.mark.slow
@pytest.mark.parametrize("name", EXAMPLES)
def test_example_scene_comes_to_rest(examples, name):
    mujoco()
    assert smoke_test(examples / name / "mjcf" / "scene.xml") == []


@pytest.mark.slow
def test_model_config_points_at_model_sdf(examples):
    config = ET.parse(examples / "turret_bot" / "model.config").getroot()
    assert config.find("sdf").text == "model.sdf" and config.find("sdf").get("version") == "1.9"
    assert config.findtext("name") == "turret_bot"
    assert config.find("author/name").text == "Aniruddh K B"


@pytest.mark.slow
@pytest.mark.parametrize("rel", ["model.sdf", "mjcf/turret_bot.xml", "mjcf/scene.xml"])
def test_golden_files(examples, rel):
    assert_golden(examples / "turret_bot" / rel, GOLDEN / "turret_bot" / rel)


# ------------------------------------------------------------ the check can fail


def _copy(examples: Path, tmp_path: Path) -> Path:
    dst = tmp_path / "turret_bot"
    shutil.copytree(examples / "turret_bot", dst)
    return dst


@pytest.mark.slow
def test_equivalence_finds_a_changed_mass_in_the_sdf(examples, tmp_path):
    robot = _copy(examples, tmp_path)
    sdf = robot / "model.sdf"
    text = sdf.read_text()
    mass = ET.fromstring(text).find("model/link[@name='rotor']/inertial/mass").text
    sdf.write_text(text.replace(f"<mass>{mass}</mass>", f"<mass>{float(mass) * (1 + 1e-6)!r}</mass>"))
    result = equivalence(robot)
    assert result["URDF (MuJoCo) vs MJCF (MuJoCo)"] == []
    assert result["URDF (MuJoCo) vs SDF"] and "link 'rotor': mass" in result["URDF (MuJoCo) vs SDF"][0]


@pytest.mark.slow
def test_equivalence_finds_a_rotated_inertia_in_the_mjcf(examples, tmp_path):
    robot = _copy(examples, tmp_path)
    path = robot / "mjcf" / "turret_bot.xml"
    root = ET.parse(path)
    inertial = root.getroot().find(".//body[@name='rotor']/inertial")
    ixx, iyy, izz, *rest = inertial.get("fullinertia").split()
    inertial.set("fullinertia", " ".join([iyy, ixx, izz, *rest]))  # the MuJoCo #3559 symptom
    root.write(path)
    diffs = equivalence(robot)["URDF (MuJoCo) vs MJCF (MuJoCo)"]
    assert diffs and diffs[0].startswith("link 'rotor': inertia tensor")


@pytest.mark.slow
def test_equivalence_finds_a_moved_joint_axis(examples, tmp_path):
    robot = _copy(examples, tmp_path)
    sdf = robot / "model.sdf"
    sdf.write_text(sdf.read_text().replace("<xyz>0 0 1</xyz>", "<xyz>0 1 0</xyz>"))
    diffs = equivalence(robot)["URDF (MuJoCo) vs SDF"]
    assert diffs and "pose differs" in diffs[0]


TIME = r" \(\d+\.\d s\)"  # the check's wall time


@pytest.mark.consumers
@pytest.mark.slow
def test_check_command_on_a_build_folder(examples, tmp_path):
    proc = run_cli("check", examples / "turret_bot")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    lines = proc.stdout.splitlines()
    # each stage with its verdict, as test runners list them
    assert lines[:9] == ["  ok  check_urdf", "  ok  ign sdf -k", "  ok  mujoco (2 files)",
                         "  ok  lints (5 links and joints)",
                         "  ok  equivalence (URDF, model.sdf, MJCF and Gazebo's URDF at 100 configurations)",
                         "  ok  consumers", "  ok  simulation",
                         "  ok  self-collision", "  ok  motion"]
    assert re.fullmatch(re.escape(f"{examples / 'turret_bot'}: 9 stages passed, 0 errors, 0 warnings") + TIME,
                        lines[-1]), lines[-1]
    # the drives' step responses: a line per joint (its slowest simulator)
    assert lines[9].startswith("motion of robot 'turret_bot' (implicitfast, dt 0.002 s; stage ")
    assert lines[10].split() == ["joint", "pose", "sim", "rise", "overshoot", "final", "error"]
    assert [line.split()[:2] for line in lines[11:13]] == [["j1", "zero"], ["j2", "zero"]]
    robot = _copy(examples, tmp_path)
    sdf = robot / "model.sdf"
    sdf.write_text(sdf.read_text().replace("<xyz>0 0 1</xyz>", "<xyz>0 1 0</xyz>"))
    proc = run_cli("check", robot, "--format", "json")
    assert proc.returncode == 1
    report = json.loads(proc.stdout)
    assert report["errors"] >= 1 and report["findings"][0]["check"] == "equivalence"


# ------------------------------------------------------------ features across formats


def test_mimic_floating_base_contact_and_losses(tmp_path):
    recipe = write_recipe(tmp_path, """
        robot: gripper
        links:
          world: {}
          palm:
            visual: {box: {size: [0.1, 0.1, 0.04]}}
            contact: {mu1: 0.9, mu2: 0.7, kp: 100000, kd: 300}
          left: {visual: {box: {size: [0.01, 0.02, 0.06]}, origin: {xyz: [0, 0, 0.03]}}}
          right: {visual: {box: {size: [0.01, 0.02, 0.06]}, origin: {xyz: [0, 0, 0.03]}}}
        joints:
          base: {type: floating, parent: world, child: palm, origin: {xyz: [0, 0, 0.3]}}
          left_finger:
            type: prismatic
            parent: palm
            child: left
            origin: {xyz: [-0.03, 0, 0.02]}
            axis: [1, 0, 0]
            limit: {lower: 0, upper: 0.02, effort: 20, velocity: 0.1}
            dynamics: {damping: 2, friction: 0.1, armature: 0.01}
          right_finger:
            type: prismatic
            parent: palm
            child: right
            origin: {xyz: [0.03, 0, 0.02], rpy: [0, 0, 3.141592653589793]}
            axis: [1, 0, 0]
            limit: {lower: 0, upper: 0.02, effort: 20, velocity: 0.1}
            mimic: {joint: left_finger, multiplier: 1, offset: 0}
        """)
    result = build([recipe], tmp_path / "out")
    robot = tmp_path / "out" / "gripper"
    assert "gripper: SDF: joint 'right_finger': SDF 1.9 cannot express mimic joints (SDF 1.11 can); " \
           "it moves independently of 'left_finger' in Gazebo" in result.warnings
    report = json.loads((robot / "report.json").read_text())
    # what a format cannot hold by its nature: report.json's limits, never a warning
    limits = report["limits"]
    assert "joint 'base': SDF has no floating joint; link 'palm' is a free body placed at the joint's pose" \
        in limits["sdf"]
    assert limits["urdf"] == ["joint 'left_finger': armature is not written (URDF has no such joint property; the "
                              "MJCF carries it)"]
    assert "link 'palm': MuJoCo friction is isotropic; mu2 0.7 dropped, mu1 0.9 used" in limits["mjcf"]
    assert not any(x in w for w in result.warnings for x in ("floating", "armature", "isotropic", "kp/kd"))
    assert len(report["losses"]["sdf"]) == 1 and len(limits["sdf"]) == 2  # mimic; floating, armature
    check_urdf(robot / "urdf" / "gripper.urdf")
    ign_sdf_check(robot / "model.sdf")
    mj = mujoco()
    model = mj.MjModel.from_xml_path(str(robot / "mjcf" / "scene.xml"))
    assert model.jnt_type[0] == mj.mjtJoint.mjJNT_FREE
    assert model.neq == 1 and model.eq_type[0] == mj.mjtEq.mjEQ_JOINT
    j = mj.mj_name2id(model, mj.mjtObj.mjOBJ_JOINT, "left_finger")
    assert model.dof_armature[model.jnt_dofadr[j]] == 0.01
    palm_geom = mj.mj_name2id(model, mj.mjtObj.mjOBJ_GEOM, "palm_collision_0")
    assert model.geom_friction[palm_geom][0] == 0.9
    # Gazebo's kp/kd are not MuJoCo's solref (per unit mass there): MuJoCo keeps its default softness
    np.testing.assert_allclose(model.geom_solref[palm_geom], [0.02, 1.0])
    assert ("link 'palm': contact kp/kd are Gazebo (ODE) stiffness and damping; MuJoCo keeps its own contact "
            "softness (solref is per unit mass there: copied, they bounce the robot)") in limits["mjcf"]
    sdf = ET.parse(robot / "model.sdf").getroot()
    assert sdf.find("model/link[@name='palm']/collision/surface/friction/ode/mu2").text == "0.7"
    urdf = ET.parse(robot / "urdf" / "gripper.urdf").getroot()
    assert urdf.find("gazebo[@reference='palm']/kp").text == "100000"
    # the floating palm, placed 0.3 m up by the recipe, falls onto the floor and comes to rest
    notes = []
    assert smoke_test(robot / "mjcf" / "scene.xml", seconds=3, notes=notes) == []
    assert notes == ["the free robot starts more than 1 mm above the floor and falls"]


def test_dae_visuals_are_converted_for_mujoco(tmp_path, assets):
    shutil.copyfile(assets / "ur_description" / "meshes" / "ur5" / "visual" / "wrist3.dae", tmp_path / "wrist3.dae")
    recipe = write_recipe(tmp_path, """
        robot: dae
        links:
          a: {visual: {mesh: wrist3.dae}}
        """)
    result = build([recipe], tmp_path / "out")
    robot = tmp_path / "out" / "dae"
    assert (robot / "meshes" / "visual" / "wrist3.dae").read_bytes() == (tmp_path / "wrist3.dae").read_bytes()
    assert (robot / "meshes" / "mjcf" / "wrist3.obj").is_file()
    limits = json.loads((robot / "report.json").read_text())["limits"]
    assert ("mesh 'wrist3.dae': MuJoCo reads no DAE; converted to meshes/mjcf/wrist3.obj (the file's own colours "
            "and textures are dropped, the recipe's material is used)") in limits["mjcf"]
    assert not any("DAE" in w for w in result.warnings)
    mujoco().MjModel.from_xml_path(str(robot / "mjcf" / "scene.xml"))
    assert_equivalent(robot, configs=5)


@pytest.mark.slow
def test_continuous_joint_has_no_infinite_limits_in_sdf(examples):
    ign_sdf_check(examples / "lidar_mast" / "model.sdf")
    joint = ET.parse(examples / "lidar_mast" / "model.sdf").getroot().find("model/joint[@name='scan_joint']")
    assert joint.get("type") == "continuous"
    assert joint.find("axis/limit/lower") is None and joint.findtext("axis/limit/effort") == "0.5"


# ------------------------------------------------------------ random robots (property test)


def random_recipe(rng: np.random.Generator, index: int) -> str:
    n = int(rng.integers(2, 7))
    lines = [f"robot: random{index}", "links:"]
    for i in range(n):
        kind = rng.choice(["box", "cylinder", "sphere", "explicit"])
        xyz = [float(v) for v in rng.uniform(-0.2, 0.2, 3)]
        rpy = [float(v) for v in rng.uniform(-math.pi, math.pi, 3)]
        origin = f"origin: {{xyz: {xyz}, rpy: {rpy}}}"
        if kind == "box":
            geom = f"box: {{size: {[float(v) for v in rng.uniform(0.02, 0.3, 3)]}}}"
        elif kind == "cylinder":
            geom = f"cylinder: {{radius: {float(rng.uniform(0.01, 0.1))}, length: {float(rng.uniform(0.05, 0.4))}}}"
        else:
            geom = f"sphere: {{radius: {float(rng.uniform(0.01, 0.1))}}}"
        lines.append(f"  l{i}:")
        lines.append(f"    visual: {{{geom}, {origin}}}")
        if kind == "explicit":
            # a rotated, full (off-diagonal) tensor about an off-centre centre of mass
            from robotkit.geometry import rpy_matrix

            R = rpy_matrix(rng.uniform(-math.pi, math.pi, 3))
            principal = np.sort(rng.uniform(0.01, 0.1, 3))
            principal[2] = min(principal[2], 0.95 * (principal[0] + principal[1]))
            I = (R @ np.diag(principal) @ R.T).tolist()
            lines.append(f"    inertial: {{mass: {float(rng.uniform(0.1, 5))}, com: {xyz}, inertia: "
                         f"{{ixx: {I[0][0]!r}, iyy: {I[1][1]!r}, izz: {I[2][2]!r}, ixy: {I[0][1]!r}, "
                         f"ixz: {I[0][2]!r}, iyz: {I[1][2]!r}}}}}")
        else:
            lines.append(f"    inertial: {{density: {float(rng.uniform(100, 8000))}}}")
    lines.append("joints:")
    movable = []
    for i in range(1, n):
        parent = int(rng.integers(0, i))
        jtype = str(rng.choice(["revolute", "continuous", "prismatic", "fixed"]))
        xyz = [float(v) for v in rng.uniform(-0.5, 0.5, 3)]
        rpy = [float(v) for v in rng.uniform(-math.pi, math.pi, 3)]
        axis = rng.normal(size=3)
        axis = [float(v) for v in axis / np.linalg.norm(axis)]
        j = [f"  j{i}:", f"    type: {jtype}", f"    parent: l{parent}", f"    child: l{i}",
             f"    origin: {{xyz: {xyz}, rpy: {rpy}}}"]
        if jtype != "fixed":
            j.append(f"    axis: {axis}")
            j.append(f"    dynamics: {{damping: {float(rng.uniform(0, 1))}, friction: {float(rng.uniform(0, 1))}}}")
        if jtype in ("revolute", "prismatic"):
            lo = float(rng.uniform(-1.5, 0))
            j.append(f"    limit: {{lower: {lo}, upper: {lo + float(rng.uniform(0.1, 2))}, "
                     f"effort: {float(rng.uniform(1, 100))}, velocity: {float(rng.uniform(0.5, 5))}}}")
        elif jtype == "continuous":
            j.append(f"    limit: {{effort: {float(rng.uniform(1, 100))}, velocity: {float(rng.uniform(0.5, 5))}}}")
        if jtype in ("revolute", "continuous") and movable and rng.random() < 0.3:
            leader = movable[int(rng.integers(0, len(movable)))]
            j.append(f"    mimic: {{joint: {leader}, multiplier: {float(rng.uniform(-2, 2))}, "
                     f"offset: {float(rng.uniform(-0.1, 0.1))}}}")
        elif jtype in ("revolute", "continuous", "prismatic"):
            movable.append(f"j{i}")
        lines += j
    if n == 1:
        lines.pop()
    return "\n".join(lines) + "\n"


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(8))
def test_random_robots_agree_across_formats(tmp_path, seed):
    rng = np.random.default_rng(1000 + seed)
    recipe = tmp_path / "robot.yaml"
    recipe.write_text(random_recipe(rng, seed))
    result = build([recipe], tmp_path / "out")
    robot = tmp_path / "out" / f"random{seed}"
    check_urdf(robot / "urdf" / f"random{seed}.urdf")
    ign_sdf_check(robot / "model.sdf")
    assert_equivalent(robot, configs=100)
    del result
