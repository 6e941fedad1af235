"""The MoveIt 2 configuration (robotkit.emit.moveit), checked statically: MoveIt itself is not
packaged for Debian 12.  The YAML files' keys and types, their joints against the URDF's, the
group against the SRDF, the SRDF through Pinocchio (named poses, disabled collision pairs), the
launch file compiled and naming files of the package, a golden joint_limits.yaml."""

from __future__ import annotations

import ast
from dataclasses import replace
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import yaml

from conftest import GOLDEN, RECIPES, assert_golden, run_cli, write_recipe
from robotkit.emit import layout, moveit
from robotkit.emit.ros import folders
from robotkit.model.load import load_robots

MOVING = ("revolute", "continuous", "prismatic")

PAN_TILT = """
robot: pan_tilt
moveit: true
metadata: {authors: [{name: Ada, email: ada@example.org}], license: MIT}
links:
  base: {visual: {box: {size: [0.2, 0.2, 0.1]}}, inertial: {mass: 2 kg}}
  pan: {visual: {cylinder: {radius: 0.05, length: 0.1}}, inertial: {mass: 0.5 kg}}
  tilt: {visual: {box: {size: [0.05, 0.2, 0.05]}}, inertial: {mass: 0.3 kg}}
  slide: {visual: {box: {size: [0.03, 0.03, 0.03]}}, inertial: {mass: 0.1 kg}}
joints:
  pan: {type: continuous, parent: base, child: pan, origin: {xyz: [0, 0, 0.1]}, axis: [0, 0, 1]}
  tilt: {type: revolute, parent: pan, child: tilt, origin: {xyz: [0, 0, 0.1]}, axis: [0, 1, 0],
         limit: {lower: -45 deg, upper: 90 deg, effort: 5, velocity: 1.5}}
  slide: {type: prismatic, parent: tilt, child: slide, axis: [0, 1, 0],
          limit: {lower: 0, upper: 0.05, effort: 10, velocity: 0.5}}
actuators:
  pan: {interface: velocity, p: 1}
  tilt: {interface: effort, p: 20, d: 1}
poses:
  look: {pan: 90 deg, tilt: 30 deg}
"""

FILES = ("kinematics.yaml", "joint_limits.yaml", "moveit_controllers.yaml", "ros2_controllers.yaml")


def _robot(tmp_path, text: str, **kwargs):
    [(_, robot)] = load_robots([write_recipe(tmp_path, text)], **kwargs)
    return robot


# ---------------------------------------------------------------- quick: the resolved robot


def test_recipe_key_and_override(tmp_path):
    plain = PAN_TILT.replace("moveit: true\n", "")
    assert not _robot(tmp_path, plain).moveit
    assert _robot(tmp_path, plain, moveit=True).moveit  # robotkit build --moveit
    assert _robot(tmp_path, PAN_TILT).moveit


def test_controllers_one_per_interface(tmp_path):
    robot = _robot(tmp_path, PAN_TILT)
    assert {n: (i, [a.joint for a in acts]) for n, (i, acts) in moveit.trajectory_controllers(robot).items()} == {
        "pan_tilt_velocity_controller": ("velocity", ["pan"]), "pan_tilt_effort_controller": ("effort", ["tilt"])}
    ros2 = moveit.ros2_controllers(robot)
    assert ros2["pan_tilt_effort_controller"]["ros__parameters"]["gains"] == {"tilt": {"p": 20.0, "i": 0.0, "d": 1.0}}
    assert "gains" not in ros2["pan_tilt_velocity_controller"]["ros__parameters"]
    one = _robot(tmp_path, PAN_TILT.replace("interface: effort", "interface: velocity"))
    assert list(moveit.trajectory_controllers(one)) == ["pan_tilt_controller"]


def test_losses(tmp_path):
    robot = _robot(tmp_path, PAN_TILT)
    lines = moveit.losses(robot)
    assert any(line.startswith("joint 'pan': no velocity limit") for line in lines)
    assert any(line.startswith("joint 'slide': in the planning group without an actuator") for line in lines)
    assert not any("serial chain" in line for line in lines)
    ros1 = _robot(tmp_path, PAN_TILT + "ros: ros1\ngazebo: classic\n")
    assert moveit.losses(ros1) == ["the MoveIt configuration is written for ROS 2 (MoveIt 2) only: this ROS 1 "
                                   "package has none (build it with --ros ros2)"]
    assert not any(f.wanted(ros1) for f in moveit.FORMATS)
    idle = _robot(tmp_path, PAN_TILT.split("actuators:")[0])
    assert "config" in folders(idle) and "config" not in folders(replace(idle, moveit=False))
    assert moveit.losses(_robot(tmp_path, PAN_TILT.replace("moveit: true\n", ""))) == []


def test_launch_renders_and_compiles(tmp_path):
    robot = _robot(tmp_path, PAN_TILT)
    text = moveit.render_moveit_launch(robot)
    compile(text, "moveit.launch.py", "exec")
    for name in ("robot_description_semantic", "robot_description_kinematics", "robot_description_planning",
                 "config/moveit/moveit_controllers.yaml", "srdf/pan_tilt.srdf"):
        assert name in text
    idle = _robot(tmp_path, PAN_TILT.split("actuators:")[0])
    text = moveit.render_moveit_launch(idle)
    compile(text, "moveit.launch.py", "exec")
    assert "moveit_controllers.yaml" not in text and not moveit.has_controllers(idle)


# ---------------------------------------------------------------- built: ur5, quadruped, pan_tilt


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> Path:
    from robotkit.pipeline.runner import build

    out = tmp_path_factory.mktemp("moveit")
    result = build([RECIPES / "ur5.yaml", RECIPES / "quadruped.yaml"], out, moveit=True)
    assert not result.errors and not result.failed
    return out


@pytest.fixture(scope="module")
def pan_tilt(tmp_path_factory) -> Path:
    """pan_tilt built by the command line, without the recipe key: ``--moveit`` turns it on."""
    folder = tmp_path_factory.mktemp("pan-tilt")
    recipe = write_recipe(folder, PAN_TILT.replace("moveit: true\n", ""))
    proc = run_cli("build", recipe, "--out", folder / "out", "--no-report", "--moveit")
    assert proc.returncode == 0, proc.stderr
    assert "pan_tilt: MoveIt: joint 'pan': no velocity limit" in proc.stderr
    return folder / "out" / "pan_tilt"


ROBOTS = ["ur5", "quadruped_compact", "quadruped_explorer"]


def _urdf(root: Path):
    return ET.parse(root / layout.output_path(layout.URDF, root.name)).getroot()


def _moving(root: Path) -> set[str]:
    return {j.get("name") for j in _urdf(root).findall("joint") if j.get("type") in MOVING and j.find("mimic") is None}


def _actuated(root: Path) -> set[str]:
    """The joints of the URDF's <ros2_control> tag."""
    return {j.get("name") for rc in _urdf(root).iter("ros2_control") for j in rc.iter("joint")}


def _config(root: Path, name: str):
    return yaml.safe_load((root / layout.MOVEIT / name).read_text(encoding="utf-8"))


def _srdf(root: Path) -> Path:
    return root / layout.output_path(layout.SRDF, root.name)


@pytest.mark.slow
@pytest.mark.parametrize("name", ROBOTS)
def test_files_and_their_schema(built, name):
    root = built / name
    for f in FILES + ("moveit.rviz",):
        assert (root / layout.MOVEIT / f).is_file(), f
    limits = _config(root, "joint_limits.yaml")
    assert set(limits) == {"default_velocity_scaling_factor", "default_acceleration_scaling_factor", "joint_limits"}
    assert set(limits["joint_limits"]) == _moving(root)
    for entry in limits["joint_limits"].values():
        assert {"has_velocity_limits", "max_velocity", "has_acceleration_limits", "max_acceleration",
                "has_position_limits"} <= set(entry)
        assert all(isinstance(entry[k], bool) for k in entry if k.startswith("has_"))
        assert all(isinstance(entry[k], float) for k in entry if k.startswith(("max_", "min_")))
        assert entry["max_acceleration"] == pytest.approx(entry["max_velocity"] / moveit.ACCELERATION_TIME)
    by_name = {j.get("name"): j for j in _urdf(root).findall("joint")}
    for joint, entry in limits["joint_limits"].items():
        assert entry["max_velocity"] == pytest.approx(float(by_name[joint].find("limit").get("velocity")))


@pytest.mark.slow
@pytest.mark.parametrize("name", ROBOTS)
def test_controllers_move_the_actuated_joints(built, name):
    root = built / name
    actuated = _actuated(root)
    assert actuated and actuated <= _moving(root)
    mc = _config(root, "moveit_controllers.yaml")
    assert mc["moveit_controller_manager"] == "moveit_simple_controller_manager/MoveItSimpleControllerManager"
    manager = mc["moveit_simple_controller_manager"]
    names = manager["controller_names"]
    assert isinstance(names, list) and names
    assert {j for n in names for j in manager[n]["joints"]} == actuated
    for n in names:
        assert manager[n]["type"] == "FollowJointTrajectory" and manager[n]["action_ns"] == "follow_joint_trajectory"
    rc = _config(root, "ros2_controllers.yaml")
    params = rc["controller_manager"]["ros__parameters"]
    assert params["joint_state_broadcaster"]["type"] == "joint_state_broadcaster/JointStateBroadcaster"
    for n in names:
        assert params[n]["type"] == "joint_trajectory_controller/JointTrajectoryController"
        p = rc[n]["ros__parameters"]
        assert p["joints"] == manager[n]["joints"] and p["state_interfaces"] == ["position", "velocity"]
        assert p["command_interfaces"] == ["position"]  # ur5's and the legs' drives are position drives
    old = yaml.safe_load((root / layout.CONTROLLERS).read_text())  # the Gazebo controllers name the same joints
    assert {j for k, v in old.items() if k != "controller_manager" for j in v["ros__parameters"]["joints"]} == actuated


@pytest.mark.slow
@pytest.mark.parametrize("name", ROBOTS)
def test_kinematics_group_is_the_srdfs(built, name):
    root = built / name
    groups = {g.get("name"): g for g in ET.parse(_srdf(root)).getroot().iter("group")}
    kin = _config(root, "kinematics.yaml")
    assert set(kin) <= set(groups)
    if name == "ur5":  # one chain: KDL
        assert kin == {"ur5": {"kinematics_solver": "kdl_kinematics_plugin/KDLKinematicsPlugin",
                               "kinematics_solver_search_resolution": 0.005, "kinematics_solver_timeout": 0.005}}
        assert groups["ur5"].find("chain") is not None
    else:  # four legs: no chain, no KDL, said in report.json
        assert kin == {} and groups[name].find("chain") is None
        import json
        losses = json.loads((root / "report.json").read_text())["losses"]["moveit"]
        assert any("is not one serial chain" in line for line in losses)


def _pinocchio_model(root: Path):
    pin = pytest.importorskip("pinocchio")
    urdf = str(root / layout.output_path(layout.URDF, root.name))
    free = ET.parse(_srdf(root)).getroot().find("virtual_joint").get("type") == "floating"
    model = pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer()) if free else pin.buildModelFromUrdf(urdf)
    return pin, model, urdf


@pytest.mark.slow
@pytest.mark.parametrize("name", ROBOTS)
def test_srdf_poses_in_pinocchio(built, name):
    from robotkit.recipe.load import load_recipes

    root = built / name
    pin, model, _ = _pinocchio_model(root)
    pin.loadReferenceConfigurations(model, str(_srdf(root)), False)
    recipe = next(r.recipe for r in load_recipes(RECIPES / f"{name.split('_')[0]}.yaml") if r.recipe.robot == name)
    poses = {entry.key(): entry.data() for entry in model.referenceConfigurations}
    assert set(poses) == set(recipe.poses) == {"home"}  # the recipe's values: radians once its units are read
    for joint in _moving(root):
        q = poses["home"][model.joints[model.getJointId(joint)].idx_q]
        assert q == pytest.approx(recipe.poses["home"].get(joint, 0.0), abs=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("name", ROBOTS)
def test_srdf_disabled_pairs_in_pinocchio(built, name):
    root = built / name
    pin, model, urdf = _pinocchio_model(root)
    geom = pin.buildGeomFromUrdf(model, urdf, pin.COLLISION, package_dirs=[str(built)])
    geom.addAllCollisionPairs()
    disabled = {frozenset((d.get("link1"), d.get("link2")))
                for d in ET.parse(_srdf(root)).getroot().iter("disable_collisions")}
    assert disabled

    def links(pair):
        objects = geom.geometryObjects
        return frozenset(model.frames[objects[i].parentFrame].name for i in (pair.first, pair.second))

    before = [links(p) for p in geom.collisionPairs]
    expected = sum(1 for p in before if p in disabled)
    assert expected > 0
    pin.removeCollisionPairs(model, geom, str(_srdf(root)), False)
    after = [links(p) for p in geom.collisionPairs]
    assert len(before) - len(after) == expected
    assert not any(p in disabled for p in after)


@pytest.mark.slow
@pytest.mark.parametrize("name", ROBOTS)
def test_launch_file_compiles_and_names_the_package_files(built, name):
    root = built / name
    path = root / layout.MOVEIT_LAUNCH
    text = path.read_text(encoding="utf-8")
    tree = compile(text, str(path), "exec", ast.PyCF_ONLY_AST)
    named = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)
             and n.value.endswith((".urdf", ".srdf", ".yaml", ".rviz"))}
    assert named == {f"urdf/{name}.urdf", f"srdf/{name}.srdf", "config/moveit/kinematics.yaml",
                     "config/moveit/joint_limits.yaml", "config/moveit/moveit_controllers.yaml",
                     "config/moveit/moveit.rviz"}
    assert all((root / rel).is_file() for rel in named)
    compile(text, str(path), "exec")
    for param in ("robot_description", "robot_description_semantic", "robot_description_kinematics",
                  "robot_description_planning"):
        assert f'"{param}"' in text


@pytest.mark.slow
@pytest.mark.parametrize("name", ROBOTS)
def test_package_installs_and_depends(built, name):
    root = built / name
    cmake = (root / "CMakeLists.txt").read_text()
    installed = set(next(line for line in cmake.splitlines() if "install(DIRECTORY" in line).split()[1:])
    assert "config" in installed and "launch" in installed
    assert installed == {p.name for p in root.iterdir() if p.is_dir()} - {"hooks", "report"}
    depends = {d.text for d in ET.parse(root / "package.xml").getroot().iter("exec_depend")}
    started = {kw.value.value for n in ast.walk(ast.parse((root / layout.MOVEIT_LAUNCH).read_text()))
               if isinstance(n, ast.Call) for kw in n.keywords if kw.arg == "package"}
    assert started - {name} <= depends
    assert {"moveit_ros_move_group", "moveit_kinematics", "moveit_simple_controller_manager", "python3-yaml",
            "joint_trajectory_controller"} <= depends


@pytest.mark.slow
def test_golden_joint_limits(pan_tilt):
    assert_golden(pan_tilt / layout.MOVEIT_JOINT_LIMITS, GOLDEN / "pan_tilt" / "joint_limits.yaml")
    mc = _config(pan_tilt, "moveit_controllers.yaml")["moveit_simple_controller_manager"]
    assert mc["controller_names"] == ["pan_tilt_velocity_controller", "pan_tilt_effort_controller"]


@pytest.mark.slow
def test_build_without_the_flag_drops_the_configuration(pan_tilt, tmp_path):
    import shutil

    out = tmp_path / "out"
    shutil.copytree(pan_tilt.parent, out)
    recipe = pan_tilt.parent.parent / "robot.yaml"
    proc = run_cli("build", recipe, "--out", out, "--no-report")
    assert proc.returncode == 0, proc.stderr
    assert not (out / "pan_tilt" / layout.MOVEIT).exists() and not (out / "pan_tilt" / layout.MOVEIT_LAUNCH).exists()
    assert (out / "pan_tilt" / layout.CONTROLLERS).is_file()
