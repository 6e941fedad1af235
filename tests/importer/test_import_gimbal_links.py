"""Issue 32, the 36-DoF human (example-robot-data): each ball joint is three hinges with two links
between them that have neither mass nor geometry.  The import gives such a link mass (MuJoCo
refuses a moving body without); with only the smallest inertia a repair leaves (6e-11 kg m^2)
the hinges around it are ill-conditioned near their gimbal lock and the built scene's simulation
exploded (5.8e3 rad/s after 2 s).  A link between two moving joints gets a hundredth of the least
principal moment of the links it carries, stated; a massless leaf keeps the smallest."""

from __future__ import annotations

import pytest
import yaml

from robotkit.importer import import_file
from robotkit.pipeline.runner import build

# a shoulder split into hinges Z, X, Y, the first and third aligned at the zero pose (gimbal lock),
# carrying a 2 kg arm whose least principal moment is 0.002 kg m^2; a massless sensor frame on a
# hinge of its own at the hand
SHOULDER = """<?xml version="1.0"?>
<robot name="shoulder">
  <link name="torso">
    <inertial><mass value="20"/><inertia ixx="0.5" ixy="0" ixz="0" iyy="0.5" iyz="0" izz="0.3"/></inertial>
  </link>
  <link name="arm_virtual"/>
  <link name="arm_virtual_2"/>
  <link name="arm">
    <inertial><origin xyz="0.05 0 -0.15"/><mass value="2"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.002"/></inertial>
  </link>
  <link name="hand_frame"/>
  <joint name="shoulder_Z" type="continuous">
    <parent link="torso"/><child link="arm_virtual"/><origin xyz="0 0.2 1.2"/><axis xyz="0 0 1"/>
  </joint>
  <joint name="shoulder_X" type="continuous">
    <parent link="arm_virtual"/><child link="arm_virtual_2"/><axis xyz="1 0 0"/>
  </joint>
  <joint name="shoulder_Y" type="continuous">
    <parent link="arm_virtual_2"/><child link="arm"/><axis xyz="0 0 1"/>
  </joint>
  <joint name="hand_roll" type="continuous">
    <parent link="arm"/><child link="hand_frame"/><origin xyz="0 0 -0.3"/><axis xyz="0 0 1"/>
  </joint>
</robot>
"""

WHY = ("link '{link}': no mass in the original, and it moves (joint '{joint}'): MuJoCo refuses a moving body "
       "without mass and Gazebo drops it; it has no geometry: a point mass of 0.002 kg (a thousandth of the lightest "
       "link) ")
GIMBAL = ("with moments of 2e-05 kg m^2, a hundredth of the least of the links it carries (the joints above and "
          "below it are a gimbal, which a smaller inertia leaves ill-conditioned)")


def _import(tmp_path):
    urdf = tmp_path / "shoulder.urdf"
    urdf.write_text(SHOULDER, encoding="utf-8")
    result = import_file(urdf, tmp_path / "recipe" / "robot.yaml")
    return result, yaml.safe_load((tmp_path / "recipe" / "robot.yaml").read_text(encoding="utf-8"))


def test_a_link_between_two_hinges_gets_a_share_of_what_it_carries(tmp_path):
    result, recipe = _import(tmp_path)
    said = "\n".join(result.warnings)
    assert WHY.format(link="arm_virtual", joint="shoulder_Z") + GIMBAL in said
    assert WHY.format(link="arm_virtual_2", joint="shoulder_X") + GIMBAL in said
    assert recipe["links"]["arm_virtual"]["inertial"] == {"mass": 0.002, "inertia": {"ixx": 2e-05, "iyy": 2e-05,
                                                                                      "izz": 2e-05}}
    leaf = recipe["links"]["hand_frame"]["inertial"]
    assert leaf["mass"] == 0.002 and leaf["inertia"]["ixx"] < 1e-9
    assert WHY.format(link="hand_frame", joint="hand_roll") + "with the smallest inertia a repair leaves" in said


@pytest.mark.slow
def test_its_scene_stays_still_at_the_gimbal_lock(tmp_path):
    from robotkit.check.simulation import smoke_test

    result, _ = _import(tmp_path)
    build([result.recipe_path], tmp_path / "build")
    scene = tmp_path / "build" / "shoulder" / "mjcf" / "scene.xml"
    assert [p for p in smoke_test(scene) if "exploded" in p or "NaN" in p] == []
