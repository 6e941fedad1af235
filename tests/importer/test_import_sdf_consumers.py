"""The rebuilt URDF of an imported SDF model in its consumers: what Gazebo reads (libsdformat's
URDF reader) keeps every link the recipe has."""

from __future__ import annotations

import shutil
from pathlib import Path

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
    assert links == {"body": 2.0, "wheel_steer_spin_1_link": 1e-5, "wheel": 0.5}
    assert sorted(el.get("name") for el in model.findall("joint")) == ["steer_spin_1", "steer_spin_2"]
