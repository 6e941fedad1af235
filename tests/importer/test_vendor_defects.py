"""Vendor defects (tensors, mesh URIs, namespaced blocks, massless links, dangling transmissions and
mimics) of public robots outside the corpus, each in a small robot written here.

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

import re
import textwrap
from pathlib import Path

import numpy as np
import pytest

from robotkit.pipeline.runner import build
from robotkit.check.consumers import Build, consumer_findings
from robotkit.check.kinematics import compare, read_urdf
from robotkit.importer import import_file
from robotkit.model import inertia_policy as ip
from tests.importer.test_corpus import _with_stated_repairs
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
    assert result.repairs["mount"] == (  # the repair leaves a 1 cm cube a 94 cm plate: recomputed instead
        "the original's principal moments 0.001, 0.001, 0.01 violate the triangle inequality; repaired, its "
        "equivalent inertia box (0.938 x 0.938 x 3.46e-05 m) is 289x smaller than the geometry's at uniform density "
        "(0.01 x 0.01 x 0.01 m), along x, y, z: recomputed from its visual geometry, keeping the mass (policy: "
        "recompute; the given com and inertia are unused)")
    stated = robot_dir.parent / "stated.urdf"  # the original with the stated repair
    stated.write_text(_with_stated_repairs(source, urdf, result.repairs), encoding="utf-8")
    assert compare(read_urdf(stated), read_urdf(urdf), 1e-9, configs=5) == []
    model = mujoco().MjModel.from_xml_path(str(robot_dir / "mjcf" / "traits2.xml"))
    assert model.nbody == 3


def test_a_package_uri_with_an_empty_host_names_the_package(built):
    _, _, result, _ = built
    recipe = result.recipe_path.read_text(encoding="utf-8")
    assert "mesh: ../tpkg/meshes/body.stl" in recipe


@pytest.mark.consumers
def test_every_consumer_reads_gazebo1_namespaced_blocks(built):
    _, _, result, robot_dir = built
    assert "<sensor:contact" in (robot_dir / "urdf" / "traits2.urdf").read_text(encoding="utf-8")
    urdf = robot_dir / "urdf" / "traits2.urdf"
    findings, summary = consumer_findings(Build("traits2", robot_dir, urdf, robot_dir / "model.sdf",
                                                robot_dir / "mjcf" / "traits2.xml"), configs=3)
    assert [str(f) for f in findings if f.severity == "error"] == []
    assert all(s["loaded"] for s in summary.values()), summary


@pytest.mark.consumers
def test_check_on_the_original_reads_the_meshes_and_names_the_refusals(built):
    """The mesh is read (the box's inertia is compared with the given one), the consumers stage
    runs whatever libsdformat prints, and the errors are the robot's real defects (its package:/// URIs, once per geometry, and the tensor)."""
    from robotkit.commands.check import check

    source, packages, _, _ = built
    found = check(str(source), package_paths=packages)
    assert [(f.subject, f.message) for f in found if f.check == "inertia-box"] == [
        ("link 'base_link'", "the equivalent inertia box (0.245 x 0.245 x 0.245 m) is 2.45x larger than the "
                             "geometry's at uniform density (0.3 x 0.2 x 0.1 m), along x, y, z")]
    assert [(f.check, f.subject, f.message) for f in found if f.severity == "error"] == [
        ("mesh-uri", "link 'base_link'", "visual mesh 'package:///tpkg/meshes/body.stl' names no package "
                                         "('package:///' leaves the package name empty): ROS's resource retriever, "
                                         "RViz, Drake and PyBullet cannot find it"),
        ("mesh-uri", "link 'base_link'", "collision mesh 'package:///tpkg/meshes/body.stl' names no package "
                                         "('package:///' leaves the package name empty): ROS's resource retriever, "
                                         "RViz, Drake and PyBullet cannot find it"),
        ("triangle-inequality", "link 'mount'", "principal moments 0.001, 0.001, 0.01 violate the triangle "
                                                "inequality (I1 + I2 >= I3): no real body has them")]
    assert [f for f in found if f.check in ("mesh-file", "consumers")] == []


# ---------------------------------------------------------------- iCub and Go1

URDF_ICUB = textwrap.dedent("""\
    <?xml version="1.0"?>
    <robot name="traits2b">
      <link name="base_link">
        <inertial><mass value="2"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
        <visual><geometry><mesh filename="package://tpkg/meshes/dense.stl"/></geometry></visual>
      </link>
      <link name="hip">
        <inertial><mass value="0.2675"/><inertia ixx="0" ixy="0" ixz="1.35525e-20" iyy="0" iyz="0" izz="0"/></inertial>
      </link>
      <link name="ft_frame">
        <inertial><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>
      </link>
      <link name="leg">
        <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
      </link>
      <link name="imu">
        <inertial><mass value="1e-6"/><inertia ixx="1e-12" ixy="0" ixz="0" iyy="1e-12" iyz="0" izz="1e-12"/></inertial>
      </link>
      <joint name="imu_joint" type="fixed"><parent link="base_link"/><child link="imu"/></joint>
      <joint name="hip_pitch" type="revolute">
        <parent link="base_link"/><child link="hip"/><axis xyz="0 1 0"/>
        <limit lower="-1" upper="1" effort="5" velocity="1"/>
      </joint>
      <joint name="ft_sensor" type="fixed">
        <parent link="hip"/><child link="ft_frame"/><origin xyz="0 0 -0.05"/>
      </joint>
      <joint name="hip_yaw" type="revolute">
        <parent link="ft_frame"/><child link="leg"/><origin xyz="0 0 -0.05"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="5" velocity="1"/>
      </joint>
    </robot>
    """)


@pytest.fixture(scope="module")
def built_icub(tmp_path_factory):
    """A rounding-noise tensor (iCub's ankle: one product of inertia of 1.4e-20), a massless
    frame between a moving link and the moving leg below it (iCub's l_hip_3, which libsdformat
    drops with the leg, unless its point mass is above the 1e-6 kg of iCub's lightest link), and a binary STL of 204,800 triangles (Go1's trunk has 351,394)."""
    import trimesh

    mujoco()
    root = tmp_path_factory.mktemp("traits2b")
    (root / "tpkg" / "meshes").mkdir(parents=True)
    (root / "tpkg" / "urdf").mkdir()
    sphere = trimesh.creation.icosphere(subdivisions=6, radius=0.1)  # 81,920 triangles
    dense = trimesh.util.concatenate([sphere.copy().apply_translation([0.25 * i, 0, 0]) for i in range(3)])
    assert len(dense.faces) == 245760
    dense.export(root / "tpkg" / "meshes" / "dense.stl")
    source = root / "tpkg" / "urdf" / "traits2b.urdf"
    source.write_text(URDF_ICUB, encoding="utf-8")
    packages = {"tpkg": str(root / "tpkg")}
    result = import_file(source, root / "recipe" / "robot.yaml", packages, {})
    out = build([result.recipe_path], root / "build")
    assert not out.errors, out.errors
    return source, packages, result, root / "build" / result.robot


def test_a_rounding_noise_tensor_is_floored_as_a_zero_one():
    # the least moment a repair leaves is never below what MuJoCo takes (1e-14)
    fixed = ip.repair(0.2675, np.array([[0, 0, 1.35525e-20], [0, 0, 0], [1.35525e-20, 0, 0]]), 1.0)
    assert fixed.changes == ("principal moments -1.35525e-20, 0, 1.35525e-20 raised to at least 1.07e-07 kg m^2",)
    assert np.linalg.eigvalsh(fixed.inertia).min() > 1e-7
    assert ip.moment_floor(1e-9) == ip.MIN_MOMENT == 1e-13  # 0.4 * 1e-9 kg * (1 mm)^2 is 4e-16


@pytest.mark.consumers
@pytest.mark.slow
def test_the_icub_traits_build_and_every_consumer_loads_them(built_icub):
    source, _, result, robot_dir = built_icub
    urdf = robot_dir / "urdf" / "traits2b.urdf"
    check_urdf(urdf)
    assert result.repairs == {
        "hip": "the original's inertia is not positive definite (principal moments -1.35525e-20, 0, 1.35525e-20): "
               "repaired (principal moments -1.35525e-20, 0, 1.35525e-20 raised to at least 1.07e-07 kg m^2)",
        "ft_frame": "no mass in the original (nor on the links welded below it), and joint 'hip_yaw' moves below "
                    "it: Gazebo's URDF conversion drops everything that moves below it, though it is welded to a "
                    "link with mass; it has no geometry: a point mass of "
                    "1.0e-05 kg (ten times the 1e-06 kg up to which libsdformat drops a link) with the smallest "
                    "inertia a repair leaves"}
    stated = robot_dir.parent / "stated.urdf"
    stated.write_text(_with_stated_repairs(source, urdf, result.repairs), encoding="utf-8")
    want = read_urdf(stated)
    want.links["ft_frame"] = read_urdf(urdf).links["ft_frame"]  # the stated point mass
    assert compare(want, read_urdf(urdf), 1e-9, configs=5) == []
    mjcf = (robot_dir / "mjcf" / "traits2b.xml").read_text(encoding="utf-8")
    assert 'file="mjcf/dense.obj"' in mjcf  # MuJoCo's STL reader takes at most 200,000 triangles
    findings, summary = consumer_findings(Build("traits2b", robot_dir, urdf, robot_dir / "model.sdf",
                                                robot_dir / "mjcf" / "traits2b.xml"), configs=3)
    assert [str(f) for f in findings if f.severity == "error"] == []
    assert all(s["loaded"] for s in summary.values()), summary


@pytest.mark.consumers
@pytest.mark.slow
def test_check_names_the_massless_link_gazebo_drops(built_icub):
    from robotkit.commands.check import check

    source, packages, _, _ = built_icub
    found = [(f.check, f.subject, f.message) for f in check(str(source), package_paths=packages)
             if f.severity == "error"]
    assert found == [
        ("inertia", "link 'hip'", "inertia is not positive definite (principal moments -1.355e-20, 0, 1.355e-20)"),
        ("massless-moving", "link 'ft_frame'", "joint 'hip_yaw' moves below it but it has no mass, nor the links "
         "welded below it: Gazebo's URDF conversion drops everything that moves below it, though it is welded to a "
         "link with mass")]


@pytest.mark.consumers
def test_check_names_the_leg_gazebo_drops_when_mujoco_reads_the_original(tmp_path):
    """Without the ankle's tensor, MuJoCo reads the original and the consumers are compared."""
    from robotkit.commands.check import check

    source = tmp_path / "frame.urdf"
    source.write_text(URDF_ICUB.replace('ixz="1.35525e-20"', 'ixz="0"').replace('ixx="0" ixy="0" ixz="0" iyy="0" '
                      'iyz="0" izz="0"/></inertial>\n  </link>\n  <link name="ft_frame">', 'ixx="0.001" ixy="0" '
                      'ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>\n  </link>\n  <link name="ft_frame">')
                      .replace('<visual><geometry><mesh filename="package://tpkg/meshes/dense.stl"/></geometry>'
                               '</visual>', ''), encoding="utf-8")
    found = [(f.check, f.message) for f in check(str(source)) if f.severity == "error"]
    assert found == [
        ("massless-moving", "joint 'hip_yaw' moves below it but it has no mass, nor the links welded below it: "
                            "Gazebo's URDF conversion drops everything that moves below it, though it is welded to "
                            "a link with mass"),
        ("consumer", "Gazebo (URDF): total mass 2.267501 kg, the description's is 3.267501 kg"),
        ("consumer", "Gazebo (URDF): link 'leg' (1 kg) is missing")]


# ---------------------------------------------------------------- Jackal

XACRO_JACKAL = textwrap.dedent("""\
    <?xml version="1.0"?>
    <robot name="rover" xmlns:xacro="http://www.ros.org/wiki/xacro">
      <xacro:arg name="extras" default="extras.urdf"/>
      <xacro:macro name="wheel" params="prefix *joint_pose">
        <link name="${prefix}_wheel_link">
          <inertial><mass value="0.5"/><inertia ixx="0.0013" ixy="0" ixz="0" iyy="0.0024" iyz="0" izz="0.0013"/></inertial>
          <collision><geometry><cylinder radius="0.1" length="0.04"/></geometry></collision>
        </link>
        <joint name="${prefix}_wheel_joint" type="continuous">
          <parent link="chassis"/><child link="${prefix}_wheel_link"/>
          <xacro:insert_block name="joint_pose"/><axis xyz="0 1 0"/>
        </joint>
        <transmission name="${prefix}_wheel_trans">
          <type>transmission_interface/SimpleTransmission</type>
          <joint name="${prefix}_wheel"><hardwareInterface>VelocityJointInterface</hardwareInterface></joint>
          <actuator name="${prefix}_actuator"><mechanicalReduction>1</mechanicalReduction></actuator>
        </transmission>
      </xacro:macro>
      <link name="chassis">
        <inertial><mass value="16"/><inertia ixx="0.3" ixy="0" ixz="0" iyy="0.4" iyz="0" izz="0.45"/></inertial>
      </link>
      <xacro:wheel prefix="left"><origin xyz="0 0.19 0"/></xacro:wheel>
      <xacro:wheel prefix="right"><origin xyz="0 -0.19 0"/></xacro:wheel>
      <transmission name="spare_trans">
        <type>transmission_interface/SimpleTransmission</type>
        <joint name="left_wheel_joint"><hardwareInterface>VelocityJointInterface</hardwareInterface></joint>
        <actuator name="spare_actuator"><mechanicalReduction>1</mechanicalReduction></actuator>
      </transmission>
      <xacro:include filename="$(arg extras)"/>
      <xacro:include filename="$(optenv ROVER_URDF_EXTRAS extras.urdf)"/>
    </robot>
    """)


@pytest.mark.consumers
@pytest.mark.slow
def test_a_transmission_naming_no_joint_is_left_out_and_stated(tmp_path):
    """The Jackal's wheel transmissions name joint 'front_left_wheel' where the joint is
    'front_left_wheel_joint' (and it includes a placeholder file twice, by $(arg) and by
    $(optenv), whose <robot> holds a stray character): Drake refuses such a URDF, so import
    leaves those transmissions out, says so in the recipe, and check names them."""
    from robotkit.commands.check import check

    (tmp_path / "extras.urdf").write_text("<robot>\n  <!-- placeholder -->\ne</robot>\n", encoding="utf-8")
    source = tmp_path / "rover.urdf.xacro"
    source.write_text(XACRO_JACKAL, encoding="utf-8")
    result = import_file(source, tmp_path / "recipe" / "robot.yaml", {}, {})
    assert result.left_out == [
        f"transmission '{side}_wheel_trans' is left out: it names joint '{side}_wheel', which the robot does not "
        "have (Drake refuses the URDF, ros_control the transmission)" for side in ("left", "right")]
    assert result.extras == ['<transmission name="spare_trans">']
    recipe = result.recipe_path.read_text(encoding="utf-8")
    assert "# transmission 'left_wheel_trans' is left out: it names joint 'left_wheel', which the robot does\n" \
           "# not have (Drake refuses the URDF, ros_control the transmission)\n" in recipe
    out = build([result.recipe_path], tmp_path / "build")
    assert not out.errors, out.errors
    robot_dir = tmp_path / "build" / "rover"
    findings, summary = consumer_findings(Build("rover", robot_dir, robot_dir / "urdf" / "rover.urdf",
                                                robot_dir / "model.sdf", robot_dir / "mjcf" / "rover.xml"), configs=3)
    assert [str(f) for f in findings if f.severity == "error"] == []
    assert all(s["loaded"] for s in summary.values()), summary
    found = [(f.subject, f.message) for f in check(str(source)) if f.check == "transmission"]
    assert found == [(f"transmission '{side}_wheel_trans'", f"names joint '{side}_wheel', which the robot does not "
                      "have: Drake refuses the URDF and ros_control the transmission") for side in ("left", "right")]


# ---------------------------------------------------------------- Alex (example-robot-data)

URDF_ALEX = textwrap.dedent("""\
    <?xml version="1.0"?>
    <robot name="hand">
      <link name="palm">
        <inertial><mass value="0.5"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
      </link>
      <link name="L1">
        <inertial><mass value="0.01"/><inertia ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"/></inertial>
      </link>
      <link name="L2">
        <inertial><mass value="0.01"/><inertia ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"/></inertial>
      </link>
      <joint name="Left_index_q1" type="revolute">
        <parent link="palm"/><child link="L1"/><axis xyz="0 0 1"/>
        <limit lower="0" upper="2" effort="1" velocity="1"/>
      </joint>
      <joint name="Left_index_q2" type="revolute">
        <parent link="L1"/><child link="L2"/><origin xyz="0.04 0 0"/><axis xyz="0 0 1"/>
        <limit lower="0" upper="2.6" effort="1" velocity="1"/>
        <mimic joint = "index_q1" multiplier =  "1.05851325" offset = "0.72349796"/>
      </joint>
    </robot>
    """)


@pytest.mark.consumers
@pytest.mark.slow
def test_a_mimic_of_a_joint_the_robot_lacks_is_dropped_and_stated(tmp_path):
    """Alex's hands mimic 'index_q1' where the joint is 'Left_index_q1': check_urdf accepts it,
    Drake refuses it.  Import drops the mimic (the joint moves on its own, stated above it),
    the build loads everywhere, and check names the mimic."""
    from robotkit.commands.check import check

    mujoco()
    source = tmp_path / "hand.urdf"
    source.write_text(URDF_ALEX, encoding="utf-8")
    result = import_file(source, tmp_path / "recipe" / "robot.yaml", {}, {})
    note = ("mimicked joint 'index_q1' in the original, which the robot does not have (Drake refuses such a URDF): "
            "the mimic is dropped and the joint moves on its own")
    assert result.joint_notes == {"Left_index_q2": note}
    assert " ".join(line.strip(" #") for line in result.recipe_path.read_text(encoding="utf-8").splitlines()
                    if line.startswith("  # ")) == note
    out = build([result.recipe_path], tmp_path / "build")
    assert not out.errors, out.errors
    robot_dir = tmp_path / "build" / "hand"
    urdf = robot_dir / "urdf" / "hand.urdf"
    check_urdf(urdf)
    stated = tmp_path / "stated.urdf"  # the original without the mimic
    stated.write_text(re.sub(r"<mimic[^>]*/>", "", URDF_ALEX), encoding="utf-8")
    assert compare(read_urdf(stated), read_urdf(urdf), 1e-9, configs=5) == []
    findings, summary = consumer_findings(Build("hand", robot_dir, urdf, robot_dir / "model.sdf",
                                                robot_dir / "mjcf" / "hand.xml"), configs=3)
    assert [str(f) for f in findings if f.severity == "error"] == []
    assert all(s["loaded"] for s in summary.values()), summary
    found = [(f.check, f.subject, f.message) for f in check(str(source)) if f.check == "mimic-missing"]
    assert found == [("mimic-missing", "joint 'Left_index_q2'", "mimics joint 'index_q1', which the robot does not "
                      "have: Drake refuses the URDF")]


# ---------------------------------------------------------------- Talos (example-robot-data)

URDF_TALOS = textwrap.dedent("""\
    <?xml version="1.0"?>
    <robot name="head">
      <link name="rgbd_link">
        <inertial><mass value="0.2"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>
      </link>
      <link name="rgbd_depth_frame">
        <inertial><mass value="0"/><origin xyz="0 0 0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>
      </link>
      <link name="rgbd_depth_optical_frame">
        <inertial><mass value="0"/><origin xyz="0 0 0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>
      </link>
      <joint name="rgbd_depth_joint" type="fixed">
        <parent link="rgbd_link"/><child link="rgbd_depth_frame"/><origin xyz="0 0.0375 0"/>
      </joint>
      <joint name="rgbd_depth_optical_joint" type="fixed">
        <parent link="rgbd_depth_frame"/><child link="rgbd_depth_optical_frame"/><origin rpy="-1.5708 0 -1.5708"/>
      </joint>
    </robot>
    """)


@pytest.mark.consumers
@pytest.mark.slow
def test_frames_with_inertials_of_mass_0_welded_together(tmp_path):
    """Talos's camera frames each carry an <inertial> of mass 0, one welded to the next: Gazebo
    refuses the original ("Pose values must be finite"); the build, whose frames carry no
    inertial, loads everywhere, and check names the pair."""
    from robotkit.commands.check import check

    mujoco()
    source = tmp_path / "head.urdf"
    source.write_text(URDF_TALOS, encoding="utf-8")
    found = [(f.check, f.subject, f.message) for f in check(str(source)) if f.severity == "error"]
    assert found == [
        ("zero-mass-welded", "link 'rgbd_depth_optical_frame'", "has an <inertial> of mass 0 and is welded (joint "
         "'rgbd_depth_optical_joint') to 'rgbd_depth_frame', which has one too: libsdformat lumps them into a "
         "centre of mass of 0/0 and Gazebo refuses the robot (\"Pose values must be finite\")"),
        ("consumer", "robot 'head'", "Gazebo (URDF) refuses the robot: Error [Param.cc:576] Pose values must be "
                                     "finite.")]
    result = import_file(source, tmp_path / "recipe" / "robot.yaml", {}, {})
    assert result.repairs == {} and result.joint_notes == {}
    out = build([result.recipe_path], tmp_path / "build")
    assert not out.errors, out.errors
    robot_dir = tmp_path / "build" / "head"
    urdf = robot_dir / "urdf" / "head.urdf"
    assert compare(read_urdf(source), read_urdf(urdf), 1e-9, configs=2) == []
    findings, summary = consumer_findings(Build("head", robot_dir, urdf, robot_dir / "model.sdf",
                                                robot_dir / "mjcf" / "head.xml"), configs=2)
    assert [str(f) for f in findings if f.severity == "error"] == []
    assert all(s["loaded"] for s in summary.values()), summary
