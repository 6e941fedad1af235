"""The rebuilt URDF of an imported SDF model in its consumers: what Gazebo reads (libsdformat's
URDF reader) keeps every link the recipe has."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from robotkit.commands.import_ import build_sdf
from robotkit.emit.layout import robot_layout
from robotkit.importer import import_sdf
from robotkit.importer.sdf.source import printed
from robotkit.urdfxml import parse_text

pytestmark = pytest.mark.skipif(shutil.which("ign") is None, reason="needs libsdformat's ign sdf")

UNIVERSAL = """<sdf version="1.9"><model name="cart">
<link name="body"><inertial><mass>2</mass><inertia><ixx>0.1</ixx><iyy>0.1</iyy><izz>0.1</izz></inertia></inertial></link>
<link name="wheel"><pose>0.3 0 0 0 0 0</pose>
  <inertial><mass>0.5</mass><inertia><ixx>0.01</ixx><iyy>0.01</iyy><izz>0.01</izz></inertia></inertial></link>
<joint name="steer_spin" type="universal"><parent>body</parent><child>wheel</child>
  <axis><xyz>0 0 1</xyz></axis><axis2><xyz>0 1 0</xyz></axis2></joint>
</model></sdf>
"""


def test_universal_joints_chain_link_survives_libsdformats_urdf_reader(tmp_path):
    # the chain link between the two revolute joints once weighed a millionth of the lightest
    # link (5e-7 kg): libsdformat's URDF reader dropped it and the wheel below it
    (tmp_path / "cart.sdf").write_text(UNIVERSAL)
    reads = []

    def build(recipe, folder):
        path = build_sdf(recipe, folder)
        reads.append(printed(robot_layout(Path(folder) / "cart").urdf, None))
        return path

    result = import_sdf(tmp_path / "cart.sdf", tmp_path / "cart.yaml", build=build)
    assert result.verdict.ok, result.verdict.lines()
    read = reads[0]
    assert read.returncode == 0, read.stderr
    model = parse_text(read.stdout).getroot().find("model")
    links = {el.get("name"): float(el.findtext("inertial/mass")) for el in model.findall("link")}
    assert links == {"body": 2.0, "wheel_steer_spin_1_link": 1e-5, "wheel": 0.49999}  # taken from the wheel
    assert sorted(el.get("name") for el in model.findall("joint")) == ["steer_spin_1", "steer_spin_2"]


def _wheel(name: str, y: float) -> str:
    return f"""<link name="{name}"><pose>0.1 {y} 0.11 0 1.5707 1.5707</pose>
  <inertial><mass>1.5</mass><inertia><ixx>0.0051</ixx><iyy>0.0051</iyy><izz>0.009</izz></inertia></inertial>
  <collision name="c"><geometry><cylinder><radius>0.11</radius><length>0.05</length></cylinder></geometry>
    <surface><friction><ode><mu>100000</mu><mu2>100000</mu2></ode></friction></surface></collision></link>
<joint name="{name}_hinge" type="revolute"><parent>chassis</parent><child>{name}</child><axis><xyz>0 1 0</xyz></axis></joint>
"""


ROVER = f"""<sdf version="1.6"><model name="rover">
<link name="chassis"><pose>0 0 0.16 0 0 0</pose>
  <inertial><mass>5.67</mass><inertia><ixx>0.07</ixx><iyy>0.08</iyy><izz>0.1</izz></inertia></inertial>
  <collision name="castor"><pose>-0.2 0 -0.12 0 0 0</pose><geometry><sphere><radius>0.04</radius></sphere></geometry>
    <surface><friction><ode><mu>0</mu><mu2>0</mu2></ode></friction></surface></collision></link>
{_wheel("left_wheel", 0.17)}{_wheel("right_wheel", -0.17)}</model></sdf>
"""


def test_wheels_that_never_slip_stand_still_in_mujoco(tmp_path):
    # Gazebo's mu 100000 ("never slips", pioneer2dx) under MuJoCo's default pyramidal cone sank
    # the wheels 3.7 cm into the floor and tipped the rover 10 degrees in 3 s: the MJCF asks for
    # the elliptic cone
    import mujoco

    (tmp_path / "rover.sdf").write_text(ROVER)
    scenes = []

    def build(recipe, folder):
        path = build_sdf(recipe, folder)
        layout = robot_layout(Path(folder) / "rover")
        scenes.append((layout.mjcf.read_text(), mujoco.MjModel.from_xml_path(str(layout.scene))))
        return path

    import_sdf(tmp_path / "rover.sdf", tmp_path / "rover.yaml", build=build)
    text, model = scenes[0]
    assert '<option integrator="implicitfast" cone="elliptic"/>' in text
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    start = data.qpos[:7].copy()
    while data.time < 3.0:
        mujoco.mj_step(model, data)
    tilt = 2 * np.degrees(np.arccos(min(1.0, abs(float(np.dot(data.qpos[3:7], start[3:7]))))))
    assert tilt < 0.5 and abs(data.qpos[2] - start[2]) < 1e-3, (tilt, data.qpos[:3], start[:3])


def test_a_chain_link_whose_child_has_no_given_inertial_keeps_an_added_mass(tmp_path):
    """The wheel's tensor breaks the triangle inequality: the build recomputes it from the cylinder,
    so the import cannot take the chain link's mass from it (the mass is added, on the ledger)."""
    (tmp_path / "cart.sdf").write_text(UNIVERSAL.replace(
        "<ixx>0.01</ixx><iyy>0.01</iyy><izz>0.01</izz>", "<ixx>0.01</ixx><iyy>0.01</iyy><izz>0.05</izz>").replace(
        "<pose>0.3 0 0 0 0 0</pose>", "<pose>0.3 0 0 0 0 0</pose><collision name=\"c\"><geometry><cylinder>"
        "<radius>0.1</radius><length>0.05</length></cylinder></geometry></collision>"))
    result = import_sdf(tmp_path / "cart.sdf", tmp_path / "cart.yaml")
    assert [line.split(": ", 1)[1] for line in result.ledger if "(joint chain)" in line] == [
        "link 'wheel' (joint chain): all: approximated: chain link 'wheel_steer_spin_1_link' carries an added point "
        "mass of 1e-05 kg, not taken from the link: its inertial is the build's to compute from its geometry"]
