"""Vendor descriptions' traits (xacro packages, massless welds, materials, transmissions), each in a
small description written here.

Held-back robots of the kinds the issue names (UR, Franka, Robotiq, Allegro, ABB, KUKA, ANYmal,
Husky, TIAGo, Kinova, Sawyer, Romeo) were rebuilt from their public sources and run through
import, build, the consumers and check; what broke is reproduced below without their files:

- a package whose xacro reads YAML (``xacro.load_yaml`` with ``!degrees``), passes the loaded
  dictionaries through macro parameters, takes ``^`` defaults from the caller's scope, computes
  argument defaults from other arguments and recurses (the UR and Franka descriptions) imports,
  builds and equals the xacro package's own expansion;
- ``robotkit check`` on such an original, its meshes behind ``package://`` in STL and DAE and
  its frames without ``<inertial>`` (a clean robot): PyBullet loads it (it knows no ROS
  packages, and loses characters of the long line a xacro expansion is), Drake is given the
  meshes it cannot read as OBJ, and PyBullet's 1 kg for a frame is a warning, not an error;
- a massless link welded to a link with mass, with a moving joint below it (Franka's hand,
  Robotiq's outer fingers): libsdformat's URDF conversion drops everything that moves below
  it, so import gives it mass, check names it on the original, and a hand-written recipe does
  not build a URDF that Gazebo would read without it;
- a material defined inside one link's visual and named alone by the next links (Allegro):
  the colour urdfdom gives them, not grey;
- ``xacro:attribute`` with a number (xacro itself fails writing it), a URDF planar joint in
  Gazebo's reading, transmissions in ros2_control's form (TIAGo: Drake wants ``<type>``),
  verbatim elements written the same whether or not xacro was imported, and a tensor repaired
  to the triangle inequality that MuJoCo accepts once rotated (Romeo).
"""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import pytest
import yaml

from robotkit.pipeline.runner import build
from robotkit.check.consumers import Build, consumer_findings
from robotkit.check.kinematics import compare, read_urdf
from robotkit.importer import import_file
from tests.conftest import run_cli
from tests.importer.test_import import xacro_reference
from tests.validators import check_urdf, mujoco

TOL = 1e-9


def _write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text).lstrip(), encoding="utf-8")
    return path


def _box_mesh(path: Path, size: float) -> None:
    import trimesh

    path.parent.mkdir(parents=True, exist_ok=True)
    trimesh.creation.box(extents=[size] * 3).export(path)


PANEL = 1.0 / 6 * 0.1 ** 2  # a 1 kg cube of 0.1 m: its principal moments


def make_arm_kit(root: Path) -> Path:
    """A package 'arm_kit': a chain of segments made by a recursive macro from YAML limits (in
    degrees), a frame 'tool0' without <inertial>, STL collision and DAE visual meshes, and text
    in <robot> outside any element."""
    pkg = root / "arm_kit"
    _write(pkg / "package.xml", """
        <?xml version="1.0"?>
        <package format="3"><name>arm_kit</name><version>0.1.0</version><description>test arm</description>
          <maintainer email="arm@example.com">Arm</maintainer><license>BSD</license></package>
    """)
    _box_mesh(pkg / "meshes" / "segment.stl", 0.1)
    import trimesh

    trimesh.creation.box(extents=[0.1] * 3).export(pkg / "meshes" / "segment.dae")
    _write(pkg / "config" / "arm7" / "limits.yaml", """
        segment:
          lower: !degrees -170
          upper: !degrees 170.0
          effort: 50
        links: {mass: 1.0}
    """)
    _write(pkg / "urdf" / "common.xacro", f"""
        <?xml version="1.0"?>
        <robot xmlns:xacro="http://wiki.ros.org/xacro">
          <xacro:macro name="cube_inertial" params="mass:=^">
            <inertial><mass value="${{mass}}"/>
              <inertia ixx="${{mass * {PANEL!r}}}" ixy="0" ixz="0" iyy="${{mass * {PANEL!r}}}" iyz="0"
                       izz="${{mass * {PANEL!r}}}"/></inertial>
          </xacro:macro>
          <xacro:macro name="arm" params="prefix limits **shape">
            <xacro:segment n="1"/>  <!-- prefix, limits and the block from this scope -->
          </xacro:macro>
          <xacro:macro name="segment" params="n prefix:=^ limits:=^">
            <link name="${{prefix}}seg${{n}}">
              <visual><geometry><mesh filename="package://arm_kit/meshes/segment.dae"/></geometry></visual>
              <collision><xacro:insert_block name="shape"/></collision>
              <xacro:property name="mass" value="${{limits['links']['mass']}}"/>
              <xacro:cube_inertial/>
            </link>
            <xacro:if value="${{n > 1}}">
              <joint name="${{prefix}}j${{n - 1}}" type="revolute">
                <parent link="${{prefix}}seg${{n - 1}}"/><child link="${{prefix}}seg${{n}}"/>
                <origin xyz="0 0 0.1" rpy="0 ${{radians(5) if n % 2 else -pi / 36}} 0"/>
                <axis xyz="0 1 0"/>
                <xacro:property name="lim" value="${{limits['segment']}}" lazy_eval="false"/>
                <limit lower="${{lim['lower']}}" upper="${{lim['upper']}}" effort="${{lim.effort}}" velocity="1"/>
              </joint>
            </xacro:if>
            <xacro:if value="${{count > n}}">
              <xacro:segment n="${{n + 1}}"/>
            </xacro:if>
          </xacro:macro>
        </robot>
    """)
    return _write(pkg / "urdf" / "arm.urdf.xacro", """
        <?xml version="1.0"?>
        <robot xmlns:xacro="http://wiki.ros.org/xacro" name="arm7">
          <xacro:arg name="model" default="arm7"/>
          <xacro:arg name="limits" default="$(find arm_kit)/config/$(arg model)/limits.yaml"/>
          <xacro:property name="count" value="${len('$(arg model)') * 7}"/>
          <xacro:include filename="$(find arm_kit)/urdf/common.xacro"/>
          <xacro:arm prefix="" limits="${xacro.load_yaml('$(arg limits)')}">
            <shape><geometry><mesh filename="package://arm_kit/meshes/segment.stl"/></geometry></shape>
          </xacro:arm>
          <link name="tool0"/>
            the tool frame, a note left outside any comment (ANYmal's URDF has one) -->
          <joint name="flange" type="fixed"><parent link="seg${count}"/><child link="tool0"/>
            <origin xyz="0 0 0.1"/></joint>
        </robot>
    """)


@pytest.fixture(scope="module")
def arm_kit(tmp_path_factory):
    """The arm package, its import and build (once for the module)."""
    mujoco()
    root = tmp_path_factory.mktemp("arm_kit")
    entry = make_arm_kit(root)
    packages = {"arm_kit": str(root / "arm_kit")}
    result = import_file(entry, root / "recipe" / "robot.yaml", packages, {})
    built = build([result.recipe_path], root / "build")
    return root, entry, packages, result, root / "build" / result.robot, built.errors


@pytest.mark.slow
def test_a_yaml_driven_recursive_xacro_imports_and_equals_the_xacro_expansion(arm_kit, tmp_path):
    root, entry, packages, result, robot_dir, errors = arm_kit
    assert not errors, errors
    urdf = robot_dir / "urdf" / f"{result.robot}.urdf"
    check_urdf(urdf)
    original = read_urdf(xacro_reference(entry, packages, {}, tmp_path / "original.urdf"))
    assert len(original.links) == 29 and original.joints["j27"].lower == pytest.approx(-170 / 180 * 3.141592653589793)
    assert result.repairs == {}
    assert compare(original, read_urdf(urdf), TOL, configs=20) == []


@pytest.mark.consumers
@pytest.mark.slow
def test_every_consumer_loads_the_build_of_the_yaml_driven_xacro(arm_kit):
    root, entry, packages, result, robot_dir, errors = arm_kit
    assert not errors
    build_ = Build(result.robot, robot_dir, robot_dir / "urdf" / f"{result.robot}.urdf", robot_dir / "model.sdf",
                   robot_dir / "mjcf" / f"{result.robot}.xml")
    findings, summary = consumer_findings(build_, configs=3)
    assert [str(f) for f in findings if f.severity == "error"] == []
    assert all(s["loaded"] for s in summary.values()), summary


@pytest.mark.consumers
@pytest.mark.slow
def test_check_passes_a_clean_original_with_package_meshes_and_frames(arm_kit):
    """PyBullet and Drake read the original as a ROS user has it: nothing refuses it, and what
    each program does on its own (Drake reads no STL or DAE, PyBullet weighs frames 1 kg) is a
    warning."""
    root, entry, packages, result, robot_dir, errors = arm_kit
    proc = run_cli("check", entry, "--package-path", f"arm_kit={packages['arm_kit']}", cwd=root)
    lines = proc.stdout.splitlines()
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "refuses" not in proc.stdout
    assert ("  warning: Drake (URDF): reads meshes only as OBJ, VTK or glTF: 'package://arm_kit/meshes/segment.dae', "
            "'package://arm_kit/meshes/segment.stl' given to it as OBJ here (a build converts them) "
            "[consumer]") in lines
    assert ("  warning: PyBullet (URDF): gives each link without <inertial> 1 kg: 'tool0' (1 kg more than the "
            "description; a build writes a token mass that PyBullet keeps) [consumer]") in lines
    assert re.search(r": \d+ stages? passed, 0 errors, 2 warnings \(\d+\.\d s\)$", lines[-1]), lines[-1]


@pytest.mark.consumers
@pytest.mark.slow
def test_the_package_around_the_file_needs_no_package_path(arm_kit):
    """As ROS finds a package's own files, import and check find the package the file sits in
    (by its package.xml) for its ``$(find)`` and ``package://``."""
    root, entry, packages, result, robot_dir, errors = arm_kit
    again = import_file(entry, root / "recipe_own" / "robot.yaml", {}, {})
    assert yaml.safe_load(again.recipe_path.read_text(encoding="utf-8")) == \
        yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))
    proc = run_cli("check", entry, cwd=root)
    assert proc.returncode == 0, proc.stdout + proc.stderr


# ---------------------------------------------------------------- a massless link welded above a moving joint

GRIPPER = """
    <robot name="gripper">
      <link name="arm">
        <inertial><mass value="2"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
      </link>
      <joint name="mount_joint" type="fixed"><parent link="arm"/><child link="mount"/><origin xyz="0 0 0.3"/></joint>
      <link name="mount">
        <visual><geometry><box size="0.08 0.08 0.02"/></geometry></visual>
      </link>
      <joint name="slide" type="prismatic"><parent link="mount"/><child link="finger"/><axis xyz="0 1 0"/>
        <limit lower="0" upper="0.04" effort="20" velocity="0.1"/></joint>
      <link name="finger">
        <inertial><mass value="0.05"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial>
        <visual><geometry><box size="0.01 0.01 0.05"/></geometry></visual>
      </link>
      <joint name="tcp_joint" type="fixed"><parent link="mount"/><child link="tcp"/><origin xyz="0 0 0.1"/></joint>
      <link name="tcp"/>
    </robot>
"""


@pytest.mark.consumers
def test_gazebo_drops_what_moves_below_a_massless_welded_link(tmp_path):
    """The premise, measured with libsdformat: the finger below the massless 'mount' is gone
    from Gazebo's reading of the original, though 'mount' is welded to a link with mass."""
    urdf = _write(tmp_path / "gripper.urdf", GRIPPER)
    findings, summary = consumer_findings(Build("gripper", tmp_path, urdf, None, None), ["Gazebo (URDF)"])
    assert "error: robot 'gripper': Gazebo (URDF): link 'finger' (0.05 kg) is missing [consumer]" in \
        [str(f) for f in findings]


@pytest.mark.consumers
def test_import_gives_the_welded_link_mass_and_gazebo_keeps_the_finger(tmp_path):
    urdf = _write(tmp_path / "gripper.urdf", GRIPPER)
    result = import_file(urdf, tmp_path / "recipe" / "robot.yaml", {}, {})
    assert result.repairs == {"mount": "no mass in the original (nor on the links welded below it), and joint 'slide' "
                                       "moves below it: Gazebo's URDF conversion drops everything that moves below "
                                       "it, though it is welded to a link with mass; computed from its visual "
                                       "geometry at the recipe's density",
                              # the finger's tensor, a 3.46 cm cube's on a 5 cm rod of 1 cm, is the part's
                              "finger": "the given inertial does not fit its geometry: its equivalent inertia box "
                                        "(0.0346 x 0.0346 x 0.0346 m) is 3.46x larger than the geometry's at uniform "
                                        "density (0.01 x 0.01 x 0.05 m), along x, y, z: recomputed from its visual "
                                        "geometry, keeping the mass (policy: recompute; the given com and inertia are "
                                        "unused)"}
    assert "  # no mass in the original (nor on the links welded below it), and joint 'slide'" in \
        result.recipe_path.read_text(encoding="utf-8")
    built = build([result.recipe_path], tmp_path / "build")
    assert not built.errors, built.errors
    robot_dir = tmp_path / "build" / "gripper"
    findings, summary = consumer_findings(Build("gripper", robot_dir, robot_dir / "urdf" / "gripper.urdf", None, None),
                                          ["Gazebo (URDF)"])
    assert [str(f) for f in findings if f.severity == "error"] == []
    assert summary["Gazebo (URDF)"]["links"] == 2  # arm (with mount and tcp lumped in) and finger


@pytest.mark.consumers
@pytest.mark.slow
def test_check_names_the_massless_welded_link_on_the_original(tmp_path):
    urdf = _write(tmp_path / "gripper.urdf", GRIPPER)
    proc = run_cli("check", urdf, cwd=tmp_path)
    assert proc.returncode == 1
    assert "  error: joint 'slide' moves below it but it has no mass, nor the links welded below it: Gazebo's URDF " \
           "conversion drops everything that moves below it, though it is welded to a link with mass " \
           "[massless-moving]" in proc.stdout.splitlines()
    assert "link 'mount' (gripper.urdf:6)" in proc.stdout.splitlines()
    assert not [line for line in proc.stdout.splitlines() if line.startswith("link 'tcp'")]  # a frame: fine


@pytest.mark.slow
def test_a_recipe_with_a_massless_welded_link_above_a_moving_joint_builds_no_urdf(tmp_path):
    recipe = _write(tmp_path / "robot.yaml", """
        robot: gripper
        links:
          arm: {inertial: {mass: 2, inertia: {ixx: 0.01, iyy: 0.01, izz: 0.01}}}
          mount: {}
          finger: {inertial: {mass: 0.05, inertia: {ixx: 1e-5, iyy: 1e-5, izz: 1e-5}}}
        joints:
          mount_joint: {type: fixed, parent: arm, child: mount, origin: {xyz: [0, 0, 0.3]}}
          slide:
            type: prismatic
            parent: mount
            child: finger
            axis: [0, 1, 0]
            limit: {lower: 0, upper: 0.04, effort: 20, velocity: 0.1}
    """)
    proc = run_cli("build", recipe, "--out", tmp_path / "out", cwd=tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert proc.stderr.splitlines() == [
        "robot.yaml:4: links.mount: link 'mount' has no mass, nor the links welded below it, and joint 'slide' moves "
        "below it: Gazebo's URDF conversion drops everything that moves below it; give links.mount an inertial",
        "robot.yaml: gripper: left out (refused by a consumer, or naming a file that is): " + ", ".join(
            f"gripper/{f}" for f in ("urdf/gripper.urdf", "urdf/gripper.urdf.xacro", "srdf/gripper.srdf",
                                     "package.xml", "CMakeLists.txt", "hooks/gripper.dsv.in", "launch/display.launch.py",
                                     "launch/gazebo.launch.py", "rviz/gripper.rviz", "report/report.html"))]
    assert not (tmp_path / "out" / "gripper" / "urdf" / "gripper.urdf").exists()
    assert (tmp_path / "out" / "gripper" / "model.sdf").exists()  # robotkit's own SDF keeps the finger


# ---------------------------------------------------------------- materials


def test_a_material_defined_in_a_link_colours_the_links_that_name_it_after(tmp_path):
    """urdfdom keeps the first definition of a material's name, also one inside a link's
    visual, for the visuals after it that give the name alone."""
    urdf = _write(tmp_path / "hand.urdf", """
        <robot name="hand">
          <link name="palm">
            <visual><geometry><box size="0.1 0.1 0.02"/></geometry>
              <material name="black"><color rgba="0.2 0.2 0.2 1"/></material></visual>
            <inertial><mass value="0.5"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial>
          </link>
          <joint name="j" type="revolute"><parent link="palm"/><child link="finger"/><axis xyz="0 1 0"/>
            <limit lower="0" upper="1" effort="1" velocity="1"/></joint>
          <link name="finger">
            <visual><geometry><box size="0.02 0.02 0.05"/></geometry><material name="black"/></visual>
            <visual><geometry><sphere radius="0.01"/></geometry><material name="black"></material></visual>
            <inertial><mass value="0.05"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial>
          </link>
        </robot>
    """)
    result = import_file(urdf, tmp_path / "recipe" / "robot.yaml", {}, {})
    data = yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))
    assert data["materials"] == {"black": {"rgba": [0.2, 0.2, 0.2, 1]}}
    assert [v["material"] for v in data["links"]["finger"]["visual"]] == ["black", "black"]
    assert not [w for w in result.warnings if "material '" in w], result.warnings


# ---------------------------------------------------------------- xacro's generated elements and attributes


TRAITS_XACRO = """
    <robot xmlns:xacro="http://wiki.ros.org/xacro" name="traits">
      <xacro:property name="late" value="${early * 2}"/>
      <xacro:property name="early" value="0.25"/>
      <xacro:include filename="parts.xacro" ns="parts"/>
      <xacro:parts.box name="base"/>
      <xacro:call macro="parts.box" name="arm"/>
      <xacro:element xacro:name="joint" name="shoulder" type="revolute">
        <parent link="base"/><child link="arm"/>
        <origin xyz="0 ${late} 0.3" rpy="${radians(90)} 0 ${pi/4}"/>
        <axis xyz="0 0 1"/>
        <limit effort="10" velocity="1"><xacro:attribute name="lower" value="LOWER"/>
          <xacro:attribute name="upper" value="UPPER"/></limit>
      </xacro:element>
    </robot>
"""


@pytest.mark.consumers
@pytest.mark.slow
def test_a_number_set_by_xacro_attribute_is_written_as_xacro_writes_attributes(tmp_path):
    """``<xacro:attribute value="${-pi/2}"/>`` leaves a number where xacro's writer wants text
    (xacro 2.1 fails with AttributeError on such a file); robotkit writes it as xacro writes every
    other attribute, str() of the value, and the robot equals xacro's expansion of the same file
    with the value given as text."""
    _write(tmp_path / "parts.xacro", """
        <robot xmlns:xacro="http://wiki.ros.org/xacro">
          <xacro:macro name="box" params="name">
            <link name="${name}">
              <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
              <visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual>
            </link>
          </xacro:macro>
        </robot>
    """)
    source = _write(tmp_path / "traits.urdf.xacro",
                    TRAITS_XACRO.replace("LOWER", "${-pi/2}").replace("UPPER", "${math.pi/2}"))
    text = _write(tmp_path / "traits_text.urdf.xacro",
                  TRAITS_XACRO.replace("LOWER", "${str(-pi/2)}").replace("UPPER", "${str(math.pi/2)}"))
    result = import_file(source, tmp_path / "recipe" / "robot.yaml", {}, {})
    limit = yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))["joints"]["shoulder"]["limit"]
    assert (limit["lower"], limit["upper"]) == (-3.141592653589793 / 2, 3.141592653589793 / 2)
    built = build([result.recipe_path], tmp_path / "build")
    assert not built.errors, built.errors
    original = xacro_reference(text, {}, {}, tmp_path / "original.urdf")
    assert compare(read_urdf(original), read_urdf(tmp_path / "build" / "traits" / "urdf" / "traits.urdf"), TOL) == []
    proc = run_cli("check", source, cwd=tmp_path)
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stdout + proc.stderr


@pytest.mark.consumers
def test_gazebo_s_reading_of_a_planar_joint_is_a_refusal_not_a_crash(tmp_path):
    """libsdformat's URDF conversion drops a planar joint and leaves its child posed relative to
    it: the model it prints cannot load, which check reports (it raised KeyError)."""
    urdf = _write(tmp_path / "cart.urdf", """
        <robot name="cart">
          <link name="world"/>
          <joint name="floor" type="planar"><parent link="world"/><child link="base"/><axis xyz="0 0 1"/></joint>
          <link name="base">
            <inertial><mass value="5"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
          </link>
          <joint name="spin" type="continuous"><parent link="base"/><child link="wheel"/><axis xyz="0 1 0"/></joint>
          <link name="wheel">
            <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
          </link>
        </robot>
    """)
    findings, summary = consumer_findings(Build("cart", tmp_path, urdf, None, None), ["Gazebo (URDF)"])
    assert [str(f) for f in findings] == [
        "error: robot 'cart': Gazebo (URDF) refuses the robot: libsdformat's reading is not a model it can load: "
        "a pose is relative to 'floor', which the model does not define [consumer]"]


# ---------------------------------------------------------------- ros2_control's transmissions

ROS2_TRANSMISSION = """
    <robot name="wrist">
      <link name="base">
        <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
      </link>
      <joint name="roll_joint" type="revolute"><parent link="base"/><child link="hand"/><axis xyz="1 0 0"/>
        <limit lower="-2" upper="2" effort="3" velocity="2"/></joint>
      <link name="hand">
        <inertial><mass value="0.5"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
      </link>
      <transmission name="roll_trans">
        <plugin>transmission_interface/SimpleTransmission</plugin>
        <actuator name="roll_motor" role="actuator1"/>
        <joint name="roll_joint" role="joint1"><mechanical_reduction>1.0</mechanical_reduction></joint>
      </transmission>
    </robot>
"""


@pytest.mark.consumers
@pytest.mark.slow
def test_a_transmission_in_ros2_control_s_form_loads_in_drake(tmp_path):
    """TIAGo's transmissions name their class in <plugin>, ros2_control's form, and have no
    <type>, without which Drake refuses the URDF: the build's URDF carries both (and says so),
    and check gives Drake the original that way, with a note instead of a refusal."""
    urdf = _write(tmp_path / "wrist.urdf", ROS2_TRANSMISSION)
    result = import_file(urdf, tmp_path / "recipe" / "robot.yaml", {}, {})
    built = build([result.recipe_path], tmp_path / "build")
    assert not built.errors, built.errors
    robot_dir = tmp_path / "build" / "wrist"
    text = (robot_dir / "urdf" / "wrist.urdf").read_text(encoding="utf-8")
    assert ("<transmission name=\"roll_trans\"><type>transmission_interface/SimpleTransmission</type>\n"
            "  <plugin>transmission_interface/SimpleTransmission</plugin>") in text
    findings, summary = consumer_findings(Build("wrist", robot_dir, robot_dir / "urdf" / "wrist.urdf", None, None),
                                          ["Drake (URDF)"])
    assert [str(f) for f in findings] == [] and summary["Drake (URDF)"]["loaded"]
    report = (robot_dir / "report.json").read_text(encoding="utf-8")
    assert ("transmission 'roll_trans' names its class in <plugin> only: written with "
            "<type>transmission_interface/SimpleTransmission</type> too, without which Drake refuses the "
            "URDF") in report
    proc = run_cli("check", urdf, cwd=tmp_path)
    assert ("  warning: Drake (URDF): reads a <transmission> only with a <type>: 'roll_trans' given to it with the "
            "class of their <plugin> here (a build writes it) [consumer]") in proc.stdout.splitlines(), proc.stdout
    assert "refuses" not in proc.stdout


def test_verbatim_elements_do_not_depend_on_whether_xacro_was_imported(tmp_path):
    """xacro replaces minidom's writer for the whole process when it is imported (attributes
    sorted, whitespace dropped): the recipe's urdf_extras keep the source's attribute order and
    layout all the same."""
    import xacro  # noqa: F401  (the import is the point)

    urdf = _write(tmp_path / "wrist.urdf", ROS2_TRANSMISSION.replace(
        "</robot>", '  <gazebo reference="hand">\n    <sensor type="ray" name="lidar"/>\n  </gazebo>\n</robot>'))
    result = import_file(urdf, tmp_path / "recipe" / "robot.yaml", {}, {})
    extras = yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))["urdf_extras"]
    assert extras == [
        '<transmission name="roll_trans">\n  <plugin>transmission_interface/SimpleTransmission</plugin>\n'
        '  <actuator name="roll_motor" role="actuator1"/>\n  <joint name="roll_joint" role="joint1">'
        '<mechanical_reduction>1.0</mechanical_reduction></joint>\n</transmission>',
        '<gazebo reference="hand">\n  <sensor type="ray" name="lidar"/>\n</gazebo>']


# ---------------------------------------------------------------- a repaired tensor MuJoCo accepts


def test_a_tensor_repaired_to_the_triangle_inequality_stays_inside_it_once_rotated(tmp_path):
    """A repair that lands exactly on I1 + I2 = I3 comes back from its principal axes a rounding
    short of it, and MuJoCo refused Romeo's arm for it: the repair lands TRIANGLE_TOL inside."""
    import numpy as np

    from robotkit.model.inertia_policy import TRIANGLE_TOL, repair

    c, s = np.cos(0.3), np.sin(0.3)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    given = R @ np.diag([0.00066, 0.00068, 0.0066]) @ R.T
    fixed = repair(0.57, given, 1e-3).inertia
    a, b, big = np.linalg.eigvalsh(fixed)
    assert a + b >= big * (1 + TRIANGLE_TOL / 2)
    ixx, ixy, ixz, iyy, iyz, izz = (float(given[i, j]) for i, j in ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)))
    urdf = _write(tmp_path / "arm.urdf", f"""
        <robot name="arm">
          <link name="base"><inertial><mass value="2"/>
            <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
          <joint name="yaw" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 0 1"/>
            <limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
          <link name="upper"><inertial><mass value="0.57"/>
            <inertia ixx="{ixx!r}" ixy="{ixy!r}" ixz="{ixz!r}" iyy="{iyy!r}" iyz="{iyz!r}" izz="{izz!r}"/>
          </inertial></link>
        </robot>
    """)
    result = import_file(urdf, tmp_path / "recipe" / "robot.yaml", {}, {})
    assert result.repairs["upper"].startswith("the original's principal moments 0.00066, 0.00068, 0.0066 violate "
                                              "the triangle inequality")
    built = build([result.recipe_path], tmp_path / "build")
    assert not built.errors, built.errors
    mujoco().MjModel.from_xml_path(str(tmp_path / "build" / "arm" / "mjcf" / "arm.xml"))


@pytest.mark.consumers
@pytest.mark.slow
def test_check_finds_the_package_around_a_urdf_in_a_folder_named_otherwise(tmp_path):
    """A package checked out as 'kit-main' is package 'kit' by its package.xml: check reads its
    meshes without --package-path (it looked for a folder named 'kit')."""
    pkg = tmp_path / "kit-main"
    _write(pkg / "package.xml", """
        <?xml version="1.0"?>
        <package format="3"><name>kit</name><version>0.1.0</version><description>kit</description>
          <maintainer email="kit@example.com">Kit</maintainer><license>BSD</license></package>
    """)
    _box_mesh(pkg / "meshes" / "part.stl", 0.1)
    urdf = _write(pkg / "urdf" / "kit.urdf", f"""
        <robot name="kit">
          <link name="base">
            <inertial><mass value="1"/><inertia ixx="{PANEL!r}" ixy="0" ixz="0" iyy="{PANEL!r}" iyz="0"
              izz="{PANEL!r}"/></inertial>
            <visual><geometry><mesh filename="package://kit/meshes/part.stl"/></geometry></visual>
          </link>
        </robot>
    """)
    proc = run_cli("check", urdf, cwd=tmp_path)
    assert "[mesh-file]" not in proc.stdout, proc.stdout
    assert proc.returncode == 0, proc.stdout + proc.stderr
