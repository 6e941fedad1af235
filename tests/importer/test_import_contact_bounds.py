"""Issue 32, TIAGo Pro (example-robot-data): a ``<gazebo reference>`` contact stiffness beyond what
the recipe takes (kp 1e13 on head_front_camera_link; the recipe's bound is 1e12) refused the whole
import ("the imported recipe would be invalid: ... contact.kp").  Its block stays as the original
wrote it, carried through verbatim in urdf_extras and written back to the URDF; values the recipe
takes still become the link's ``contact``."""

from __future__ import annotations

import yaml

from robotkit.importer import import_file
from robotkit.pipeline.runner import build
from robotkit.urdfxml import parse_file

CAMERA = """<?xml version="1.0"?>
<robot name="head">
  <link name="head">
    <inertial><mass value="1"/><inertia ixx="0.0017" ixy="0" ixz="0" iyy="0.0017" iyz="0" izz="0.0017"/></inertial>
    <collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision>
    <visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual>
  </link>
  <link name="camera">
    <inertial><mass value="0.1"/><inertia ixx="4e-05" ixy="0" ixz="0" iyy="4e-05" iyz="0" izz="4e-05"/></inertial>
    <collision><geometry><box size="0.05 0.05 0.05"/></geometry></collision>
    <visual><geometry><box size="0.05 0.05 0.05"/></geometry></visual>
  </link>
  <joint name="camera_joint" type="fixed"><parent link="head"/><child link="camera"/><origin xyz="0.1 0 0"/></joint>
  <gazebo reference="head"><mu1>0.8</mu1><mu2>0.8</mu2><kp>1e+5</kp><kd>1</kd></gazebo>
  <gazebo reference="camera"><mu2>1</mu2><kp>1e+13</kp><kd>1</kd></gazebo>
</robot>
"""


def test_a_contact_stiffness_beyond_the_recipe_stays_verbatim(tmp_path):
    urdf = tmp_path / "head.urdf"
    urdf.write_text(CAMERA, encoding="utf-8")
    result = import_file(urdf, tmp_path / "recipe" / "robot.yaml")
    recipe = yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))
    assert recipe["links"]["head"]["contact"] == {"mu1": 0.8, "mu2": 0.8, "kp": 100000.0, "kd": 1.0}
    assert "contact" not in recipe["links"]["camera"]
    assert [x for x in recipe["urdf_extras"] if x.startswith('<gazebo reference="camera">')] == [
        '<gazebo reference="camera">\n  <mu2>1</mu2>\n  <kp>1e+13</kp>\n  <kd>1</kd>\n</gazebo>']
    build([result.recipe_path], tmp_path / "build")
    root = parse_file(tmp_path / "build" / "head" / "urdf" / "head.urdf").getroot()
    assert [g.findtext("kp") for g in root.iter("gazebo") if g.get("reference") == "camera"] == ["1e+13"]
