"""Imported MJCF models in the programs that read their builds (the consumers): what the shared
Menagerie set showed (docs/performance.md, "Imported Menagerie models in the consumers"), each on
a small MJCF of that shape."""

from __future__ import annotations

from pathlib import Path

import pytest

from robotkit.check.equivalence import equivalence
from robotkit.importer import import_mjcf

# a body and its joint share a name (Menagerie's Cassie: body 'left-knee', joint 'left-knee')
TWIN = """<mujoco model="twin">
  <worldbody>
    <body name="upper" pos="0 0 0.1">
      <joint name="upper" type="hinge" axis="0 1 0" range="-1 1"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.3" size="0.02" mass="0.5"/>
      <body name="fore" pos="0 0 0.3">
        <joint name="fore" type="hinge" axis="0 1 0" range="-1 1"/>
        <geom type="box" size="0.02 0.02 0.1" pos="0 0 0.1" mass="0.2"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.fixture(scope="module")
def twin(tmp_path_factory) -> Path:
    from robotkit.pipeline.runner import build

    folder = tmp_path_factory.mktemp("twin")
    (folder / "twin.xml").write_text(TWIN)
    import_mjcf(folder / "twin.xml", folder / "twin.yaml")
    build([folder / "twin.yaml"], folder / "out", report=False)
    return folder / "out" / "twin"


def test_joints_named_like_their_bodies_are_renamed_in_model_sdf(twin):
    sdf = (twin / "model.sdf").read_text()
    assert '<joint name="upper_joint" type="revolute">' in sdf
    assert '<joint name="upper"' in (twin / "urdf" / "twin.urdf").read_text()


def test_equivalence_reads_a_renamed_joint_as_the_same_joint(twin):
    """model.sdf's 'upper_joint' is the URDF's 'upper' (robotkit.emit.sdf.joint_names): the
    check compared the names and found every joint missing ("movable joints differ")."""
    assert equivalence(twin) == {"URDF (MuJoCo) vs MJCF (MuJoCo)": [], "URDF (MuJoCo) vs SDF": [],
                                 "URDF (libsdformat) vs URDF lumped as Gazebo does": []}
