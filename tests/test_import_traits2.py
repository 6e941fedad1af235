"""Issue 14: traits of public robots outside the corpus, each in a small robot written here.

- A vendor tensor whose principal moments break the triangle inequality (the PR2's
  sensor_mount_link: 0.001, 0.001, 0.01 at 50 g): the repair must leave a + b above c, not on
  it, or the rounding of the written numbers makes MuJoCo refuse the build.
- Mesh URIs with an empty host, ``package:///PKG/path`` (the Talos of example-robot-data):
  check_urdf and Pinocchio accept them, so import reads them as ``package://PKG/path``; check
  on the original reads their geometry, and names Drake's refusal.
- Gazebo 1 extension blocks with namespace prefixes (``<sensor:contact>``,
  ``<controller:gazebo_ros_bumper>``, the PR2's): libsdformat prints them without their
  namespace declaration, which must not stop the consumers' comparison.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
import pytest

from robotkit.build import build
from robotkit.check.consumers import Build, consumer_findings
from robotkit.check.kinematics import compare, read_urdf
from robotkit.importer import import_file
from robotkit.model import inertia_policy as ip
from tests.test_corpus import _with_stated_repairs
from tests.validators import check_urdf, mujoco

URDF = textwrap.dedent("""\
    <?xml version="1.0"?>
    <robot name="traits2" xmlns:sensor="http://playerstage.sourceforge.net/gazebo/xmlschema/#sensor"
           xmlns:controller="http://playerstage.sourceforge.net/gazebo/xmlschema/#controller">
      <link name="base_link">
        <inertial><mass value="2"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
        <visual><geometry><mesh filename="package:///tpkg/meshes/body.stl"/></geometry></visual>
        <collision><geometry><mesh filename="package:///tpkg/meshes/body.stl"/></geometry></collision>
      </link>
      <link name="mount">
        <inertial><mass value="0.05"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.01"/></inertial>
        <visual><geometry><box size="0.01 0.01 0.01"/></geometry></visual>
      </link>
      <joint name="pan" type="revolute">
        <parent link="base_link"/><child link="mount"/><origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="5" velocity="1"/>
      </joint>
      <gazebo reference="base_link">
        <sensor:contact name="base_contact_sensor">
          <geom>base_link_geom</geom>
          <controller:gazebo_ros_bumper name="bumper" plugin="libgazebo_ros_bumper.so">
            <bumperTopicName>base_bumper</bumperTopicName>
          </controller:gazebo_ros_bumper>
        </sensor:contact>
      </gazebo>
    </robot>
    """)


def write_package(folder: Path) -> Path:
    import trimesh

    (folder / "meshes").mkdir(parents=True)
    (folder / "urdf").mkdir()
    trimesh.creation.box([0.3, 0.2, 0.1]).export(folder / "meshes" / "body.stl")
    (folder / "urdf" / "traits2.urdf").write_text(URDF, encoding="utf-8")
    return folder / "urdf" / "traits2.urdf"


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    mujoco()
    root = tmp_path_factory.mktemp("traits2")
    source = write_package(root / "tpkg")
    packages = {"tpkg": str(root / "tpkg")}
    result = import_file(source, root / "recipe" / "robot.yaml", packages, {})
    out = build([result.recipe_path], root / "build")
    assert not out.errors, out.errors
    return source, packages, result, root / "build" / result.robot


def test_a_repaired_triangle_tensor_ends_inside_the_inequality():
    # a third of the excess each way lands on a + b == c, which rounds to 0.0036666666666666666 * 2
    # < 0.007333333333333334: MuJoCo refused the PR2 built from that
    fixed = ip.repair(0.05, np.diag([0.001, 0.001, 0.01]), 1.0)
    a, b, c = np.diag(fixed.inertia)
    assert a + b > c and a + b - c == pytest.approx(0.01 * ip.TRIANGLE_TOL, rel=1e-3)
    assert fixed.changes == ("principal moments 0.001, 0.001, 0.01 moved to 0.00366667, 0.00366667, 0.00733333 to "
                             "meet the triangle inequality",)


def test_the_build_equals_the_original_and_mujoco_loads_it(built):
    source, _, result, robot_dir = built
    urdf = robot_dir / "urdf" / "traits2.urdf"
    check_urdf(urdf)
    assert list(result.repairs) == ["mount"]
    assert result.repairs["mount"].startswith("the original's principal moments 0.001, 0.001, 0.01 violate the "
                                              "triangle inequality: repaired")
    stated = robot_dir.parent / "stated.urdf"  # the original with the stated repair
    stated.write_text(_with_stated_repairs(source, urdf, result.repairs), encoding="utf-8")
    assert compare(read_urdf(stated), read_urdf(urdf), 1e-9, configs=5) == []
    model = mujoco().MjModel.from_xml_path(str(robot_dir / "mjcf" / "traits2.xml"))
    assert model.nbody == 3


def test_a_package_uri_with_an_empty_host_names_the_package(built):
    _, _, result, _ = built
    recipe = result.recipe_path.read_text(encoding="utf-8")
    assert "mesh: ../tpkg/meshes/body.stl" in recipe


def test_every_consumer_reads_gazebo1_namespaced_blocks(built):
    _, _, result, robot_dir = built
    assert "<sensor:contact" in (robot_dir / "urdf" / "traits2.urdf").read_text(encoding="utf-8")
    urdf = robot_dir / "urdf" / "traits2.urdf"
    findings, summary = consumer_findings(Build("traits2", robot_dir, urdf, robot_dir / "model.sdf",
                                                robot_dir / "mjcf" / "traits2.xml"), configs=3)
    assert [str(f) for f in findings if f.severity == "error"] == []
    assert all(s["loaded"] for s in summary.values()), summary


def test_check_on_the_original_reads_the_meshes_and_names_the_refusals(built):
    """The mesh is read (the box's inertia is compared with the given one), the consumers stage
    runs whatever libsdformat prints, and the errors are the robot's two real defects."""
    from robotkit.check import check

    source, packages, _, _ = built
    found = check(str(source), package_paths=packages)
    assert [(f.subject, f.message) for f in found if f.check == "inertia-box"] == [
        ("link 'base_link'", "the equivalent inertia box (0.245 x 0.245 x 0.245 m) is 2.45x larger than the "
                             "geometry's at uniform density (0.3 x 0.2 x 0.1 m)")]
    assert [(f.check, f.subject, f.message) for f in found if f.severity == "error"] == [
        ("triangle-inequality", "link 'mount'", "principal moments 0.001, 0.001, 0.01 violate the triangle "
                                                "inequality (I1 + I2 >= I3): no real body has them"),
        ("consumer", "robot 'traits2'", f"Drake (URDF) refuses the robot: {source}:6: error: URI "
                                        "'package:///tpkg/meshes/body.stl' refers to unknown package ''")]
    assert [f for f in found if f.check in ("mesh-file", "consumers")] == []
