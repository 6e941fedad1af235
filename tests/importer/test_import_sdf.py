"""robotkit import model.sdf / MODEL_FOLDER: SDF read through libsdformat into a recipe, each
conversion stated on the ledger and proved against the rebuilt model.sdf (through libsdformat)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import yaml

from robotkit.commands.import_ import build_sdf
from robotkit.importer import import_sdf
from tests.conftest import ASSETS, run_cli

pytestmark = pytest.mark.skipif(shutil.which("ign") is None, reason="needs libsdformat's ign sdf")
MODELS = Path(__file__).resolve().parents[1] / "data" / "gazebo_models"


SHARED = ASSETS / "gazebo_models"
_DONE: dict[str, tuple] = {}


def _imported(tmp_path: Path, name: str):
    """The import (and verification) of a test model, once per session."""
    if name not in _DONE:
        result = import_sdf(MODELS / name, tmp_path / f"{name}.yaml", build=build_sdf)
        _DONE[name] = result, yaml.safe_load(result.recipe_path.read_text())
    return _DONE[name]


def _joints(recipe: dict) -> dict:
    """The recipe's joints with its ``defaults: joint:`` applied."""
    base = recipe.get("defaults", {}).get("joint", {})
    return {name: {**base, **j} for name, j in recipe["joints"].items()}


def test_folder_takes_newest_sdf_metadata_and_invalid_inertia_recomputed(tmp_path):
    result, recipe = _imported(tmp_path, "simple_arm")
    assert result.verdict.ok, result.verdict.lines()
    assert recipe["metadata"]["authors"] == [{"name": "John Hsu", "email": "hsu@osrfoundation.org"}]
    assert recipe["metadata"]["description"] == "A simple SCARA arm."
    assert recipe["links"]["arm_base"]["inertial"]["policy"] == "recompute"
    assert any("link 'arm_base' inertial: all: the original's" in line and "recomputed from its collision geometry"
               in line for line in result.ledger)
    assert recipe["base"] == "free"


def test_joint_named_like_a_link_is_renamed(tmp_path):
    result, recipe = _imported(tmp_path, "simple_gripper")
    assert result.verdict.ok, result.verdict.lines()
    assert any(line.endswith("model.sdf:203: joint 'left_finger_tip': all: renamed 'left_finger_tip_joint' (a link "
               "has its name: libsdformat refuses the pair)") for line in result.ledger)
    assert "left_finger_tip_joint" in recipe["joints"] and "left_finger_tip" in recipe["links"]


def test_joint_types_urdf_lacks_are_approximated_or_dropped(tmp_path):
    result, recipe = _imported(tmp_path, "demo_joint_types")
    assert result.verdict.ok, result.verdict.lines()
    joints = _joints(recipe)
    assert [joints[f"ball_demo_{a}"]["axis"] for a in "xyz"] == [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    assert joints["ball_demo_x"]["child"] in recipe["links"] and joints["ball_demo_z"]["child"] == "ball_ball"
    assert joints["revolute_demo"]["type"] == "continuous"  # SDF's +-1e16 limits
    assert joints["prismatic_demo"]["type"] == "prismatic"
    assert "gearbox_demo" not in joints
    text = "\n".join(result.ledger)
    assert "joint 'gearbox_demo' (gearbox): all: dropped" in text
    assert "joint 'ball_demo' (ball): all: approximated: three revolute joints" in text
    assert "joint 'universal_demo' (universal): all: approximated: two revolute joints" in text
    assert "(screw): all: approximated: a revolute joint" in text
    scripts = [line for line in result.ledger if "material script <uri>" in line]  # one line, not one per visual
    assert len(scripts) == 1 and scripts[0].split(": ", 1)[1].startswith(
        "material script <uri> model://demo_joint_types/materials/scripts, model://demo_joint_types/materials/"
        "textures: all: dropped from 18 visuals (heavy_base_visual, revolute_base_visual, ")
    assert len(result.ledger) <= 20


def test_file_libsdformat_refuses_is_read_from_its_xml(tmp_path):
    result, recipe = _imported(tmp_path, "ragdoll")
    assert result.verdict.ok, result.verdict.lines()
    assert "libsdformat refuses it" in result.ledger[0] and "read from its own XML" in result.ledger[0]
    assert len(recipe["joints"]) == 23 and {j["type"] for j in _joints(recipe).values()} == {"revolute"}
    assert recipe["base"] == "free"


def test_verification_compares_poses_at_random_configurations(tmp_path):
    result, _ = _imported(tmp_path, "simple_arm")
    assert result.verdict.configurations == 11
    assert "verified through libsdformat against the original at 11 configurations: every quantity agrees" \
        == result.verdict.lines()[0]


def test_sdf_file_through_the_cli(tmp_path):
    proc = run_cli("import", MODELS / "simple_gripper" / "model.sdf", "-o", tmp_path / "g.yaml", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "every quantity agrees" in proc.stdout
    assert (tmp_path / "g.yaml").is_file()


def test_bad_sdf_one_line_exit_2_nothing_written(tmp_path):
    bad = tmp_path / "bad.sdf"
    bad.write_text("<sdf version='1.9'><model name='m'><link name='a'></model></sdf>\n")
    proc = run_cli("import", bad, "-o", tmp_path / "out" / "bad.yaml", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr == "bad.sdf:1: not well-formed XML: mismatched tag: line 1, column 52\n"
    assert not (tmp_path / "out").exists()


def test_sdf_libsdformat_refuses_and_its_xml_cannot_be_read_exit_2(tmp_path):
    bad = tmp_path / "pose.sdf"
    bad.write_text('<sdf version="1.9"><model name="m"><link name="a"><pose>a b c 0 0 0</pose></link></model></sdf>\n')
    proc = run_cli("import", bad, "-o", tmp_path / "out" / "x.yaml", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.startswith("pose.sdf: libsdformat refuses it (") and proc.stderr.count("\n") == 1
    assert proc.stderr.endswith("), and its XML holds a value that is not a number: could not convert string to "
                                "float: 'a'\n")
    assert not (tmp_path / "out").exists()


def test_folder_without_model_config_exit_2(tmp_path):
    (tmp_path / "empty").mkdir()
    proc = run_cli("import", "empty", "-o", tmp_path / "out" / "x.yaml", cwd=tmp_path)
    assert (proc.returncode, proc.stderr) == (2, "empty: a model folder without model.config\n")
    assert not (tmp_path / "out").exists()


SYNTHETIC = """<?xml version="1.0"?>
<sdf version="1.9">
  <model name="bench">
    <static>true</static>
    <link name="base">
      <pose>0 0 0.5 0 0 0</pose>
      <inertial><mass>2</mass><inertia><ixx>0.1</ixx><iyy>0.1</iyy><izz>0.1</izz></inertia></inertial>
      <collision name="c"><geometry><capsule><radius>0.1</radius><length>0.4</length></capsule></geometry></collision>
      <visual name="v"><geometry><capsule><radius>0.1</radius><length>0.4</length></capsule></geometry>
        <material><diffuse>0.2 0.4 0.6 1</diffuse></material><transparency>0.5</transparency></visual>
      <sensor name="imu" type="imu"><update_rate>50</update_rate></sensor>
    </link>
    <link name="arm">
      <pose>0.3 0 0.5 0 0 0</pose>
      <inertial><mass>1</mass><inertia><ixx>0.01</ixx><iyy>0.01</iyy><izz>0.01</izz></inertia></inertial>
      <visual name="grey"><geometry><box><size>0.1 0.1 0.1</size></box></geometry>
        <material><script><name>Gazebo/Grey</name></script></material></visual>
    </link>
    <joint name="hinge" type="revolute">
      <pose>0 0.1 0 0 0 0</pose>
      <parent>base</parent><child>arm</child>
      <axis><xyz>0 1 0</xyz><limit><lower>-1</lower><upper>1</upper><effort>5</effort><velocity>2</velocity></limit>
        <dynamics><damping>0.3</damping><friction>0.1</friction><spring_stiffness>3</spring_stiffness></dynamics></axis>
    </joint>
    <frame name="tool" attached_to="arm"><pose>0.1 0 0 0 0 0</pose></frame>
    <plugin name="p" filename="libp.so"><x>1</x></plugin>
  </model>
</sdf>
"""


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("synthetic")
    (tmp / "bench.sdf").write_text(SYNTHETIC)
    built = {}

    def build(recipe, folder):
        path = build_sdf(recipe, folder)
        built["sdf"] = path.read_text()
        built["report"] = json.loads((path.parent / "report.json").read_text())
        return path

    result = import_sdf(tmp / "bench.sdf", tmp / "bench.yaml", build=build)
    return result, yaml.safe_load(result.recipe_path.read_text()), built["sdf"], built["report"]


def test_static_model_is_fixed_to_world(synthetic):
    result, recipe, _ = synthetic[:3]
    assert result.verdict.ok, result.verdict.lines()
    assert "base" not in recipe or recipe.get("base") != "free"
    assert _joints(recipe)["base_fixed"]["parent"] == "world"


def test_joint_off_its_child_moves_the_link_frame_limits_dynamics(synthetic):
    _, recipe, _ = synthetic[:3]
    hinge = _joints(recipe)["hinge"]
    assert hinge["origin"]["xyz"] == [0.3, 0.1, 0]
    assert hinge["axis"] == [0, 1, 0]
    assert hinge["limit"] == {"lower": -1, "upper": 1, "effort": 5, "velocity": 2}
    assert hinge["dynamics"] == {"damping": 0.3, "friction": 0.1}
    assert recipe["links"]["arm"]["inertial"]["com"] == [0, -0.1, 0]  # in the joint's frame


def test_capsule_is_a_cylinder_and_two_spheres_with_its_colour(synthetic):
    _, recipe, _ = synthetic[:3]
    visual = recipe["links"]["base"]["visual"]
    assert [next(k for k in ("cylinder", "sphere") if k in s) for s in visual] == ["cylinder", "sphere", "sphere"]
    assert [s.get("origin", {}).get("xyz") for s in visual[1:]] == [[0, 0, -0.2], [0, 0, 0.2]]
    assert recipe["materials"][visual[0]["material"]]["rgba"] == [0.2, 0.4, 0.6, 1]
    grey = recipe["links"]["arm"]["visual"]["material"]  # Gazebo's standard material, named without a colour
    assert recipe["materials"][grey] == {"rgba": [0.7, 0.7, 0.7, 1], "gazebo": "Gazebo/Grey"}


def test_frame_is_a_massless_link_fixed_where_it_is(synthetic):
    _, recipe, _ = synthetic[:3]
    assert recipe["links"]["tool"] == {} or "inertial" not in recipe["links"]["tool"]
    joint = _joints(recipe)["tool_frame"]
    assert (joint["type"], joint["parent"], joint["child"]) == ("fixed", "arm", "tool")
    assert joint["origin"]["xyz"] == pytest.approx([0.1, -0.1, 0], abs=1e-15)


def test_the_ledger_is_in_the_recipe_and_the_builds_report_json(synthetic):
    result, recipe, _, report = synthetic
    assert result.ledger and recipe["metadata"]["ledger"] == result.ledger
    assert report["ledger"] == result.ledger


def test_sensor_and_plugin_carried_verbatim_into_model_sdf(synthetic):
    result, recipe, rebuilt = synthetic[:3]
    assert any(e.startswith('<gazebo reference="base">\n  <sensor name="imu" type="imu">') for e in recipe["urdf_extras"])
    assert '<sensor name="imu" type="imu">' in rebuilt.replace("'", '"') and 'filename="libp.so"' in rebuilt
    assert any("sensor 'imu' (imu) of link 'base': MJCF: dropped (kept verbatim" in line for line in result.ledger)
    assert any("plugin 'p' (libp.so): MJCF: dropped (kept verbatim" in line for line in result.ledger)


def test_included_model_found_on_the_model_path_with_scoped_names(tmp_path):
    result = import_sdf(MODELS / "nested_hokuyo" / "model.sdf", tmp_path / "n.yaml", build=build_sdf)
    recipe = yaml.safe_load(result.recipe_path.read_text())
    assert result.verdict.ok, result.verdict.lines()
    assert "hokuyo/link" in recipe["links"]  # model://hokuyo's link 'link', hokuyo::link in SDF
    joint = _joints(recipe)["hokuyo_joint"]
    assert (joint["parent"], joint["child"]) == ("chassis", "hokuyo/link")
    assert joint["origin"]["xyz"] == [0.2, 0, 0.13]
    assert result.inputs[-1].endswith("gazebo_models/hokuyo/meshes/hokuyo.dae")


def test_what_the_recipe_cannot_hold_is_named_on_the_ledger(synthetic):
    result, _, _ = synthetic[:3]
    where = str(Path(result.inputs[0]))
    assert f"{where}:5: link 'base': all: dropped (no place in the recipe): visual 'v' <transparency>" in result.ledger
    assert (f"{where}:19: joint 'hinge': all: dropped (no place in the recipe): <axis><dynamics><spring_stiffness> 3"
            in result.ledger)


@pytest.mark.slow
@pytest.mark.parametrize("model", sorted(p.name for p in SHARED.iterdir() if (p / "model.config").is_file())
                         if SHARED.is_dir() else [])
def test_every_shared_gazebo_model_imports_and_verifies(model, tmp_path):
    result = import_sdf(SHARED / model, tmp_path / f"{model}.yaml", build=build_sdf)
    assert result.verdict.ok, result.verdict.lines()
    assert len(result.ledger) <= 30


def test_joint_to_world_roots_the_recipe_in_world(tmp_path):
    (tmp_path / "w.sdf").write_text("""<sdf version="1.9"><model name="w">
<link name="base"><pose>0 0 1 0 0 0</pose><inertial><mass>1</mass></inertial></link>
<link name="arm"><pose>0 0 1.5 0 0 0</pose><inertial><mass>2</mass></inertial></link>
<joint name="fix" type="fixed"><parent>world</parent><child>base</child></joint>
<joint name="j" type="prismatic"><parent>base</parent><child>arm</child>
  <axis><xyz>0 0 1</xyz><limit><lower>0</lower><upper>0.5</upper></limit></axis></joint>
</model></sdf>
""")
    result = import_sdf(tmp_path / "w.sdf", tmp_path / "w.yaml", build=build_sdf)
    recipe = yaml.safe_load(result.recipe_path.read_text())
    assert result.verdict.ok and result.verdict.configurations == 11, result.verdict.lines()
    assert "base" not in recipe or recipe.get("base") != "free"
    assert recipe["joints"]["fix"] == {"type": "fixed", "parent": "world", "child": "base", "origin": {"xyz": [0, 0, 1]}}
    # SDF's defaults where the inertial gives no tensor: unit moments; no effort or velocity limit
    # (-1, unlimited): a stated 1e9, not 0 (a passive joint, which Gazebo cannot drive), said above it
    assert recipe["links"]["arm"]["inertial"] == {"mass": 2, "inertia": {"ixx": 1, "iyy": 1, "izz": 1}}
    assert _joints(recipe)["j"]["limit"] == {"lower": 0, "upper": 0.5, "effort": 1e9, "velocity": 1e9}
    assert "  # no effort or velocity limit in the SDF (unlimited): 1e+09\n  j:" in result.recipe_path.read_text()


def test_model_name_becomes_a_ros_package_name_stated(tmp_path):
    """The robot's name is its ROS package's: catkin refuses a '.' or a leading digit and warns
    of capitals (REP 144); the import names it so and says so above the recipe."""
    (tmp_path / "m.sdf").write_text("""<sdf version="1.9"><model name="2Wheel.Bot">
<link name="base"><inertial><mass>1</mass></inertial></link></model></sdf>
""")
    result = import_sdf(tmp_path / "m.sdf", tmp_path / "m.yaml")
    line = ("robot '2Wheel.Bot' (the SDF's model name) named 'robot_2wheel_bot': the robot's name is its ROS "
            "package's, which holds lower case letters, digits and '_', a letter first (REP 144)")
    assert result.robot == "robot_2wheel_bot" and result.notes == [line]
    text = result.recipe_path.read_text()
    assert f"# {line}\n" in text and yaml.safe_load(text)["robot"] == "robot_2wheel_bot"


@pytest.mark.parametrize("name, package", [("Skydio_X2", "skydio_x2"), ("2f85", "robot_2f85"), ("_arm", "arm"),
                                           ("ur-10.e", "ur_10_e"), ("so_arm100", "so_arm100"), ("", "robot")])
def test_package_name(name, package):
    from robotkit.importer.names import package_name

    assert package_name(name) == package
