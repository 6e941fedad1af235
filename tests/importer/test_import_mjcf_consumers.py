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


# a body moved by two joints: a chain through a massless link (Menagerie's UMI gripper, six joints
# in one body; Cassie's ball joints)
CHAIN = """<mujoco model="chain">
  <worldbody>
    <body name="arm" pos="0 0 0.1">
      <joint name="pitch" type="hinge" axis="0 1 0" range="-1 1"/>
      <joint name="roll" type="hinge" axis="1 0 0" range="-1 1"/>
      <geom type="box" size="0.02 0.02 0.1" pos="0 0 0.1" mass="0.2"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_gazebo_keeps_the_massless_link_of_a_joint_chain(tmp_path):
    """The chain link takes 1e-05 kg from the body (robotkit.importer.mjcf.chainmass): once it had a
    millionth of the lightest body (2e-07 kg here), and libsdformat's URDF reader, which reads a
    mass up to 1e-06 kg as none, dropped it with the arm below it."""
    from robotkit.check.consumers import Build, consumer_findings
    from robotkit.emit.layout import robot_layout
    from robotkit.pipeline.runner import build

    (tmp_path / "chain.xml").write_text(CHAIN)
    import_mjcf(tmp_path / "chain.xml", tmp_path / "chain.yaml")
    build([tmp_path / "chain.yaml"], tmp_path / "out", report=False)
    layout = robot_layout(tmp_path / "out" / "chain")
    robot = Build("chain", layout.root, layout.urdf, layout.sdf, layout.mjcf, "fixed")
    findings, summary = consumer_findings(robot, ["Gazebo (URDF)"])
    assert [f.message for f in findings] == []
    assert summary["Gazebo (URDF)"]["mass"] == pytest.approx(0.2, rel=1e-12)  # taken, not added
    assert summary["Gazebo (URDF)"]["links"] == 2  # 'arm_pitch' (the chain link) and 'arm'


# an effort drive beside a position drive (Menagerie's TIAGo with motor actuators on its arm)
TWO_DRIVES = """<?xml version="1.0"?>
<robot name="two">
  <link name="base"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>
  </inertial></link>
  <link name="a"><inertial><mass value="1"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/>
  </inertial></link>
  <link name="b"><inertial><mass value="1"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/>
  </inertial></link>
  <joint name="a" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="100" velocity="10"/></joint>
  <joint name="b" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="100" velocity="10"/></joint>
</robot>
"""


@pytest.mark.consumers
def test_drake_steps_a_position_drive_beside_an_effort_drive(tmp_path):
    """Drake's desired-state port holds every actuator of the model (2 x 2 here), the effort
    drive's entries ignored: the motion stage gave it the controlled ones only and Drake refused
    ("expected ... size=4 ... but the actual type was ... size=2")."""
    from robotkit.check.motion import SIMULATORS, Drive, Step, metrics

    urdf = tmp_path / "two.urdf"
    urdf.write_text(TWO_DRIVES)
    drives = [Drive("a", "effort", 0.0, 0.0), Drive("b", "position", kp=2.0, kd=0.4, effort=100.0)]
    trace = SIMULATORS["drake"](urdf, drives, Step("b", {}, 0.5), package_dirs={})
    assert trace.diverged is None
    assert metrics(trace, 0.0, 0.5, "position", effort=100.0)["final_error"] < 1e-2
