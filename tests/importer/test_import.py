"""Issue 8: `robotkit import` of URDF and xacro into a recipe.

Round trips: import, build, and the rebuilt URDF read through MuJoCo's URDF compiler must be
equivalent to the original (robotkit.check.kinematics.compare: links, joints, masses,
centres of mass, inertia tensors, limits, damping, friction, mimic, link poses at 100 random
configurations) at 1e-9.  Also: the xacro macro output, untrusted xacro expressions, and the
exact error messages for missing packages and meshes.
"""

from __future__ import annotations

import os
import re
import shutil
import textwrap
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml

from robotkit.pipeline.runner import build
from robotkit.errors import RobotkitError
from robotkit.importer import import_file
from robotkit.importer.inertials import no_inertial_form
from robotkit.check.kinematics import KModel, compare, read_urdf
from tests.validators import check_urdf, mujoco

ASSETS = Path(__file__).resolve().parents[2].parent / "shared" / "assets"
PACKAGES = {name: str(ASSETS / name) for name in
            ("turret_bot", "turtlebot3_description", "ur_description", "realsense2_description")}
TOL = 1e-9


@pytest.fixture(autouse=True)
def _assets():
    if not ASSETS.is_dir():
        pytest.fail(f"test assets not found at {ASSETS} (CI clones the repository next to shared/)")
    mujoco()


def xacro_reference(path: Path, packages: dict[str, str], args: dict[str, str], out: Path) -> Path:
    """The xacro package's own expansion (not robotkit's code), with the documented
    $(find) patch (docs/libraries.md, section 2), as a URDF file."""
    import xacro
    import xacro.substitution_args as sa

    def find(pkg):
        return packages[pkg]

    saved = sa._eval_find, sa._eval_dict.get("find")
    sa._eval_find = find
    sa._eval_dict["find"] = find
    try:
        xacro.all_includes.clear()
        doc = xacro.process_file(str(path), mappings=dict(args))
    finally:
        sa._eval_find = saved[0]
        sa._eval_dict["find"] = saved[1]
        xacro.all_includes.clear()
    out.write_text(doc.toprettyxml(indent="  "), encoding="utf-8")
    return out


def import_and_build(tmp_path: Path, source: Path, packages=PACKAGES, args=None, **kw):
    result = import_file(source, tmp_path / "recipe" / "robot.yaml", packages, args or {}, **kw)
    built = build([result.recipe_path], tmp_path / "build")
    assert not built.errors, built.errors
    urdf = tmp_path / "build" / result.robot / "urdf" / f"{result.robot}.urdf"
    check_urdf(urdf)
    return result, urdf


# ---------------------------------------------------------------- round trips on the assets


ROUND_TRIPS = {
    "turret_bot": ("turret_bot/urdf/turret_bot.urdf", {}),
    "turtlebot3_burger": ("turtlebot3_description/urdf/turtlebot3_burger.urdf.xacro", {}),
    "ur5": ("ur_description/urdf/ur5.xacro", {}),
    "d435": ("realsense2_description/urdf/test_d435_camera.urdf.xacro", {}),
}


@pytest.mark.slow
@pytest.mark.parametrize("case", sorted(ROUND_TRIPS))
def test_round_trip(tmp_path, case):
    rel, args = ROUND_TRIPS[case]
    source = ASSETS / rel
    result, urdf = import_and_build(tmp_path, source, args=args)
    original = source if source.suffix == ".urdf" else xacro_reference(source, PACKAGES, args, tmp_path / "ref.urdf")
    a, b = read_urdf(_stated(original, urdf, result.repairs, tmp_path)), read_urdf(urdf)
    assert compare(a, b, TOL, configs=100) == []
    # every link and movable joint is there (compare checks it; this makes the count visible)
    assert set(a.links) == set(b.links) and len(a.links) >= 3


def test_turret_bot_recipe_is_readable(tmp_path):
    result = import_file(ASSETS / "turret_bot/urdf/turret_bot.urdf", tmp_path / "turret_bot.yaml", PACKAGES, {})
    text = result.recipe_path.read_text(encoding="utf-8")
    data = yaml.safe_load(text)
    assert [k for k in data] == ["robot", "units", "density", "values", "materials", "links", "joints", "urdf_extras"]
    # inertials as given, flow style for short vectors, no identity origins, shortest floats
    assert "    inertial: {mass: 16, com: [0, 0.5, 0], inertia: {ixx: 1.376, iyy: 0.317, izz: 1.607}}\n" in text
    assert "    origin: {xyz: [0, 0.05, 0.475]}\n" in text
    assert "origin: {xyz: [0, 0, 0]" not in text and "rpy: [0, 0, 0]" not in text
    assert "    limit: {lower: -3.14, upper: 3.14, effort: 1000, velocity: 50}\n" in text
    assert "collision" not in data["links"]["base"]  # same as the visual: the default
    # mesh paths relative to the recipe, their shared folder named once
    assert data["links"]["base"]["visual"]["mesh"] == "${turret_bot_meshes}/base.stl"
    folder = data["values"]["turret_bot_meshes"]
    assert not os.path.isabs(folder) and (tmp_path / folder / "base.stl").resolve() == \
        (ASSETS / "turret_bot/meshes/base.stl").resolve()
    # gazebo materials map onto the recipe's materials (the original paints base red, Gazebo/Green)
    assert data["materials"]["red"] == {"rgba": [0.8, 0, 0, 1], "gazebo": "Gazebo/Green"}
    # transmissions and the plugin block: verbatim, and listed in a warning
    assert len(data["urdf_extras"]) == 3 and data["urdf_extras"][0].startswith('<transmission name="t1">')
    assert any("carried through verbatim" in w and 'transmission name="t2"' in w for w in result.warnings)


def _gazebo_content(urdf: Path) -> tuple[dict, list[str]]:
    """(reference -> sorted (tag, value) of <gazebo reference> children, canonical other extras)."""
    root = ET.parse(urdf).getroot()
    joints = {j.get("name"): j.get("type") for j in root.findall("joint")}
    refs: dict[str, list] = {}
    others = []
    for el in root:
        if el.tag in ("link", "joint", "material"):
            continue
        if el.tag == "gazebo" and el.get("reference"):
            for child in el:
                if child.tag == "preserveFixedJoint" and joints.get(el.get("reference")) == "fixed":
                    continue  # robotkit writes it for every fixed joint
                text = (child.text or "").strip()
                try:
                    value = float(text) if len(child) == 0 else ET.canonicalize(ET.tostring(child), strip_text=True)
                except ValueError:
                    value = text
                refs.setdefault(el.get("reference"), []).append((child.tag, value))
        else:
            others.append(ET.canonicalize(ET.tostring(el), strip_text=True))
    return {k: sorted(v, key=repr) for k, v in refs.items()}, others


@pytest.mark.slow
@pytest.mark.parametrize("case", ["turret_bot", "turtlebot3_burger"])
def test_gazebo_and_transmissions_survive(tmp_path, case):
    rel, args = ROUND_TRIPS[case]
    source = ASSETS / rel
    _, urdf = import_and_build(tmp_path, source, args=args)
    original = source if source.suffix == ".urdf" else xacro_reference(source, PACKAGES, args, tmp_path / "ref.urdf")
    assert _gazebo_content(urdf) == _gazebo_content(original)


def test_recompute_inertials_reports_the_d435_difference(tmp_path):
    source = ASSETS / "realsense2_description/urdf/test_d435_camera.urdf.xacro"
    result, urdf = import_and_build(tmp_path, source, recompute_inertials=True)
    report = result.inertials["camera_link"]
    assert report["computed"]["mass"] == pytest.approx(0.072, rel=1e-12)  # the given mass is kept
    given, computed = np.diag(report["given"]["inertia"]), np.diag(report["computed"]["inertia"])
    assert given[0] / computed[0] > 50  # the hand-entered inertia is about 70x too large
    # a uniform 0.072 kg box of 25.05 x 90 x 25 mm
    a, b, c = 0.02505, 0.09, 0.025
    assert computed == pytest.approx([0.072 * (b * b + c * c) / 12, 0.072 * (a * a + c * c) / 12,
                                      0.072 * (a * a + b * b) / 12], rel=1e-9)
    assert any(w.startswith("link 'camera_link': recomputed inertial") and "differs by" in w for w in result.warnings)
    data = yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))
    assert data["links"]["camera_link"]["inertial"]["mass"] == 0.072
    built = read_urdf(urdf).links["camera_link"]
    assert np.allclose(np.sort(np.linalg.eigvalsh(built.inertia)), np.sort(computed), rtol=1e-9)


def test_recompute_at_density_finds_the_turret_bot_base_com(tmp_path):
    """At the tutorial's 1250 kg/m^3 the meshes give the given masses back, and the base's
    centre of mass height that the shipped URDF leaves out (z = 0.029844, REFERENCE_NUMBERS.md)."""
    source = ASSETS / "turret_bot/urdf/turret_bot.urdf"
    result, urdf = import_and_build(tmp_path, source, recompute_inertials=True, density=1250.0)
    data = yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))
    assert data["density"] == 1250 and "inertial" not in data["links"]["base"]  # the recipe's density
    base = result.inertials["base"]
    assert base["computed"]["mass"] == pytest.approx(0.0128 * 1250, rel=1e-6)  # MeshLab: volume 0.012800
    assert base["computed"]["com"] == pytest.approx([0, 0.5, 0.029844], abs=1e-6)
    assert base["com_shift"] == pytest.approx(0.029844, abs=1e-6)
    assert read_urdf(urdf).links["base"].com[2] == pytest.approx(0.029844, abs=1e-6)
    assert any(w.startswith("link 'base': recomputed inertial") and "given 16" in w for w in result.warnings)


VENDOR = """
    <?xml version="1.0"?>
    <robot name="vendor">
      <link name="base">
        <visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual>
        <inertial><mass value="1"/><inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.002"/></inertial>
      </link>
      <link name="arm">
        <visual><origin xyz="0 0 0.2"/><geometry><box size="0.1 0.2 0.4"/></geometry></visual>
        <inertial><mass value="2"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.05"/></inertial>
      </link>
      <link name="tip">
        <inertial><mass value="0.1"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>
      </link>
      <joint name="j1" type="continuous"><parent link="base"/><child link="arm"/></joint>
      <joint name="j2" type="continuous"><parent link="arm"/><child link="tip"/><origin xyz="0 0 0.4"/></joint>
    </robot>
    """
TRIANGLE = "the original's principal moments 0.01, 0.01, 0.05 violate the triangle inequality"


@pytest.mark.slow
@pytest.mark.parametrize("policy", ["repair", "recompute", "estimate"])
def test_import_inertia_policy(tmp_path, policy):
    """Physical inertials are kept; the arm's tensor breaks the triangle inequality and gets the
    policy asked for, stated above its link; the tip has no geometry and is repaired."""
    from tests.conftest import run_cli

    source = _write(tmp_path / "vendor.urdf", VENDOR)
    recipe = tmp_path / "recipe" / "robot.yaml"
    proc = run_cli("import", source, "-o", recipe, "--inertia-policy", policy)
    assert proc.returncode == 0, proc.stderr
    result = import_file(source, recipe, {}, {}, inertia_policy=policy)
    arm = {"repair": f"{TRIANGLE}: repaired (principal moments 0.01, 0.01, 0.05 moved to 0.02, 0.02, 0.04 to "
                     "meet the triangle inequality)",
           "recompute": f"{TRIANGLE}: recomputed from its visual geometry, keeping the mass (policy: recompute; "
                        "the given com and inertia are unused)",
           "estimate": f"{TRIANGLE}: estimated as the bounding primitive of its visual geometry, keeping the mass "
                       "(policy: estimate; the given com and inertia are unused)"}[policy]
    alone = {"repair": "", "recompute": "; it has no geometry to recompute it from",
             "estimate": "; it has no geometry to estimate it from"}[policy]
    assert result.repairs == {"arm": arm, "tip": f"the original's inertia is zero{alone}: repaired (principal "
                                                 "moments 0, 0, 0 raised to at least 4e-08 kg m^2)"}
    text = recipe.read_text(encoding="utf-8")
    assert f"  # {TRIANGLE}" in text and "  # the original's inertia is zero" in text
    data = yaml.safe_load(text)
    assert data["links"]["base"]["inertial"] == {"mass": 1, "inertia": {"ixx": 0.002, "iyy": 0.002, "izz": 0.002}}
    if policy != "repair":  # the given values stay in the recipe, for the record
        assert data["links"]["arm"]["inertial"] == {"mass": 2, "inertia": {"ixx": 0.01, "iyy": 0.01, "izz": 0.05},
                                                    "policy": policy}
    built = build([recipe], tmp_path / "build")
    assert not built.errors
    links = read_urdf(tmp_path / "build" / "vendor" / "urdf" / "vendor.urdf").links
    box = 2.0 / 12 * np.diag([0.2 ** 2 + 0.4 ** 2, 0.1 ** 2 + 0.4 ** 2, 0.1 ** 2 + 0.2 ** 2])
    repaired = np.diag([0.02, 0.02, 0.04]) + np.diag([1, 1, -1]) * 0.05e-9 / 3  # a + b 1e-9 of c above c
    want = repaired if policy == "repair" else box  # a box is its own bounding primitive
    assert np.allclose(links["arm"].inertia, want, rtol=1e-12, atol=1e-15)
    assert np.allclose(links["arm"].com, [0, 0, 0] if policy == "repair" else [0, 0, 0.2], rtol=0, atol=1e-12)
    assert links["arm"].mass == 2.0 and links["base"].mass == 1.0
    assert np.allclose(links["base"].inertia, np.eye(3) * 0.002, rtol=0, atol=0)
    assert np.allclose(links["tip"].inertia, np.eye(3) * 4e-8, rtol=1e-12, atol=0)


def test_import_inertia_policy_keep_stops_on_the_tensor(tmp_path):
    source = _write(tmp_path / "vendor.urdf", VENDOR)
    with pytest.raises(RobotkitError) as info:
        import_file(source, tmp_path / "recipe" / "robot.yaml", {}, {}, inertia_policy="keep")
    assert info.value.lines() == [
        f"{source}:7: links.arm.inertial.inertia: principal moments 0.01, 0.01, 0.05 violate the triangle "
        "inequality (no real body has them; 'policy: repair', 'recompute' or 'estimate' gives the link a physical "
        "one)",
        f"{source}:11: links.tip.inertial.inertia: inertia is not positive definite (principal moments 0, 0, 0; "
        "no real body has them; 'policy: repair', 'recompute' or 'estimate' gives the link a physical one)"]
    assert not (tmp_path / "recipe" / "robot.yaml").exists()


@pytest.mark.slow
def test_copy_meshes(tmp_path):
    source = ASSETS / "turtlebot3_description/urdf/turtlebot3_burger.urdf.xacro"
    result, urdf = import_and_build(tmp_path, source, copy_meshes=True)
    data = yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))
    mesh = data["links"]["base_link"]["visual"]["mesh"]
    assert mesh == "meshes/turtlebot3_description/meshes/bases/burger_base.stl"
    assert data["links"]["base_link"]["visual"]["units"] == "mm"
    copied = result.recipe_path.parent / mesh
    assert copied.read_bytes() == (ASSETS / "turtlebot3_description/meshes/bases/burger_base.stl").read_bytes()
    ref = xacro_reference(source, PACKAGES, {}, tmp_path / "ref.urdf")
    assert compare(read_urdf(_stated(ref, urdf, result.repairs, tmp_path)), read_urdf(urdf), TOL) == []


def _stated(original: Path, built: Path, repairs: dict[str, str], tmp_path: Path) -> Path:
    """The original with the inertials the import says it changed (a tensor that does not fit
    the part: the d435's camera_link, the burger's base_scan) taken from the build."""
    from tests.importer.test_corpus import _with_stated_repairs

    stated = tmp_path / "stated.urdf"
    stated.write_text(_with_stated_repairs(original, built, repairs), encoding="utf-8")
    return stated


# ---------------------------------------------------------------- acceptance: a robot not in the assets


def _write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text).lstrip(), encoding="utf-8")
    return path


def make_gripper_arm(root: Path) -> tuple[Path, dict[str, str]]:
    """Two packages of xacro files: an arm, and a hand with a mimic finger (included through
    $(find)), Gazebo tags, a transmission, xacro arguments, load_yaml, STL and OBJ meshes in
    mm and m, a rotated inertial frame, inline, global and texture-only materials."""
    import trimesh

    arm, hand = root / "gripper_arm_description", root / "hand_description"
    for folder in (arm / "meshes", hand / "meshes"):
        folder.mkdir(parents=True)
    base = trimesh.creation.cylinder(radius=80.0, height=50.0, sections=48)  # millimetres
    base.apply_translation([0, 0, 25.0])
    base.export(arm / "meshes" / "base.stl")
    trimesh.creation.box(extents=[0.05, 0.05, 0.3]).export(arm / "meshes" / "forearm.obj")
    trimesh.creation.box(extents=[0.08, 0.04, 0.03]).export(hand / "meshes" / "palm.stl")
    _write(arm / "config" / "arm.yaml", """
        base: {mass: 2.5}
        limits: {effort: 40.0, velocity: !degrees 120}
    """)
    _write(arm / "urdf" / "materials.xacro", """
        <?xml version="1.0"?>
        <robot xmlns:xacro="http://www.ros.org/wiki/xacro">
          <material name="steel"><color rgba="0.6 0.6 0.65 1"/></material>
          <material name="black"><color rgba="0.05 0.05 0.05 1"/></material>
        </robot>
    """)
    _write(hand / "urdf" / "hand.xacro", """
        <?xml version="1.0"?>
        <robot xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:macro name="finger" params="name parent y sign mimic:=''">
            <joint name="${name}_joint" type="revolute">
              <parent link="${parent}"/>
              <child link="${name}"/>
              <origin xyz="0 ${y} 0.015" rpy="0 0 ${(sign - 1) * pi / 2}"/>
              <axis xyz="1 0 0"/>
              <limit lower="-0.1" upper="0.8" effort="2.5" velocity="1.5"/>
              <dynamics damping="0.01"/>
              <xacro:if value="${mimic != ''}">
                <mimic joint="${mimic}" multiplier="-1" offset="0.05"/>
              </xacro:if>
            </joint>
            <link name="${name}">
              <visual>
                <origin xyz="0 0 0.02"/>
                <geometry><box size="0.01 0.012 0.04"/></geometry>
                <material name="black"/>
              </visual>
              <collision>
                <origin xyz="0 0 0.02"/>
                <geometry><box size="0.01 0.012 0.04"/></geometry>
              </collision>
              <inertial>
                <origin xyz="0 0 0.02"/>
                <mass value="0.015"/>
                <inertia ixx="2.18e-6" iyy="2.125e-6" izz="0.305e-6" ixy="0" ixz="0" iyz="0"/>
              </inertial>
            </link>
            <gazebo reference="${name}">
              <mu1>1.5</mu1>
              <mu2>1.5</mu2>
              <kp>1e6</kp>
              <kd>100</kd>
            </gazebo>
          </xacro:macro>

          <xacro:macro name="hand" params="parent prefix mass *origin">
            <joint name="${prefix}mount" type="fixed">
              <parent link="${parent}"/>
              <child link="${prefix}palm"/>
              <xacro:insert_block name="origin"/>
            </joint>
            <link name="${prefix}palm">
              <visual>
                <geometry><mesh filename="package://hand_description/meshes/palm.stl"/></geometry>
                <material name="carbon"><texture filename="package://hand_description/textures/carbon.png"/></material>
              </visual>
              <collision><geometry><box size="0.08 0.04 0.03"/></geometry></collision>
              <inertial>
                <mass value="${mass}"/>
                <inertia ixx="${mass * (0.04**2 + 0.03**2) / 12}" iyy="${mass * (0.08**2 + 0.03**2) / 12}"
                         izz="${mass * (0.08**2 + 0.04**2) / 12}" ixy="0" ixz="0" iyz="0"/>
              </inertial>
            </link>
            <xacro:finger name="${prefix}finger_left" parent="${prefix}palm" y="0.015" sign="1"/>
            <xacro:finger name="${prefix}finger_right" parent="${prefix}palm" y="-0.015" sign="-1"
                          mimic="${prefix}finger_left_joint"/>
          </xacro:macro>
        </robot>
    """)
    top = _write(arm / "urdf" / "gripper_arm.urdf.xacro", """
        <?xml version="1.0"?>
        <robot name="gripper_arm" xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:arg name="arm_length" default="0.4"/>
          <xacro:arg name="hand_mass" default="0.3"/>
          <xacro:arg name="use_hand" default="true"/>
          <xacro:property name="cfg" value="${xacro.load_yaml('$(find gripper_arm_description)/config/arm.yaml')}"/>
          <xacro:property name="L" value="$(arg arm_length)"/>
          <xacro:include filename="$(find gripper_arm_description)/urdf/materials.xacro"/>
          <xacro:include filename="$(find hand_description)/urdf/hand.xacro"/>

          <link name="base_link">
            <visual>
              <geometry>
                <mesh filename="package://gripper_arm_description/meshes/base.stl" scale="0.001 0.001 0.001"/>
              </geometry>
              <material name="steel"/>
            </visual>
            <collision>
              <origin xyz="0 0 0.025" rpy="0 0 0"/>
              <geometry><cylinder radius="0.08" length="0.05"/></geometry>
            </collision>
            <inertial>
              <origin xyz="0 0 0.025" rpy="0 0 0"/>
              <mass value="${cfg['base']['mass']}"/>
              <inertia ixx="0.0045" ixy="0" ixz="0" iyy="0.0045" iyz="0" izz="0.008"/>
            </inertial>
          </link>

          <joint name="shoulder" type="revolute">
            <parent link="base_link"/>
            <child link="upper_arm"/>
            <origin xyz="0 0 0.05" rpy="0 0 ${pi/4}"/>
            <axis xyz="0 0 1"/>
            <limit lower="${-pi}" upper="${pi}" effort="${cfg['limits']['effort']}"
                   velocity="${cfg['limits']['velocity']}"/>
            <dynamics damping="0.5" friction="0.1"/>
          </joint>

          <link name="upper_arm">
            <visual>
              <origin xyz="0 0 ${L/2}"/>
              <geometry><box size="0.06 0.06 ${L}"/></geometry>
              <material name="orange"><color rgba="1 0.42 0.04 1"/></material>
            </visual>
            <collision>
              <origin xyz="0 0 ${L/2}"/>
              <geometry><box size="0.06 0.06 ${L}"/></geometry>
            </collision>
            <inertial>
              <origin xyz="0.001 -0.002 ${L/2}" rpy="0.3 -0.2 0.7"/>
              <mass value="1.2"/>
              <inertia ixx="0.015" iyy="0.0148" izz="0.0009" ixy="0.0001" ixz="-0.00005" iyz="0.00002"/>
            </inertial>
          </link>

          <joint name="elbow" type="revolute">
            <parent link="upper_arm"/>
            <child link="forearm"/>
            <origin xyz="0 0 ${L}"/>
            <axis xyz="0 1 0"/>
            <limit lower="-2.0" upper="2.0" effort="25" velocity="2.5"/>
            <dynamics damping="0.3" friction="0.05"/>
          </joint>

          <link name="forearm">
            <visual>
              <origin xyz="0 0 0.15"/>
              <geometry><mesh filename="package://gripper_arm_description/meshes/forearm.obj"/></geometry>
              <material name="steel"><color rgba="0.6 0.6 0.65 1"/></material>
            </visual>
            <collision>
              <origin xyz="0 0 0.15"/>
              <geometry><box size="0.05 0.05 0.3"/></geometry>
            </collision>
            <inertial>
              <origin xyz="0 0 0.15"/>
              <mass value="0.8"/>
              <inertia ixx="0.0062" iyy="0.0062" izz="0.00033" ixy="0" ixz="0" iyz="0"/>
            </inertial>
          </link>

          <joint name="wrist" type="continuous">
            <parent link="forearm"/>
            <child link="wrist_link"/>
            <origin xyz="0 0 0.3"/>
            <axis xyz="0 0 1"/>
            <limit effort="5" velocity="3"/>
          </joint>

          <link name="wrist_link">
            <visual><geometry><cylinder radius="0.03" length="0.04"/></geometry><material name="black"/></visual>
            <inertial>
              <mass value="0.2"/>
              <inertia ixx="7.17e-5" iyy="7.17e-5" izz="9e-5" ixy="0" ixz="0" iyz="0"/>
            </inertial>
          </link>

          <xacro:if value="$(arg use_hand)">
            <xacro:hand parent="wrist_link" prefix="hand_" mass="$(arg hand_mass)">
              <origin xyz="0 0 0.035" rpy="0 0 ${pi/2}"/>
            </xacro:hand>
          </xacro:if>

          <joint name="tool_joint" type="fixed">
            <parent link="wrist_link"/>
            <child link="tool0"/>
            <origin xyz="0 0 0.12" rpy="${pi} 0 0"/>
          </joint>
          <link name="tool0"/>

          <gazebo reference="base_link">
            <material>Gazebo/Grey</material>
          </gazebo>
          <gazebo reference="upper_arm">
            <material>Gazebo/Orange</material>
            <mu1>0.8</mu1>
            <mu2>0.7</mu2>
            <selfCollide>true</selfCollide>
          </gazebo>
          <gazebo>
            <plugin name="gazebo_ros_control" filename="libgazebo_ros_control.so">
              <robotNamespace>/gripper_arm</robotNamespace>
            </plugin>
          </gazebo>
          <transmission name="shoulder_trans">
            <type>transmission_interface/SimpleTransmission</type>
            <joint name="shoulder">
              <hardwareInterface>hardware_interface/EffortJointInterface</hardwareInterface>
            </joint>
            <actuator name="shoulder_motor">
              <mechanicalReduction>50</mechanicalReduction>
            </actuator>
          </transmission>
        </robot>
    """)
    return top, {"gripper_arm_description": str(arm), "hand_description": str(hand)}


ARM_ARGS = {"arm_length": "0.35", "hand_mass": "0.25"}


@pytest.fixture
def gripper_arm(tmp_path):
    return make_gripper_arm(tmp_path / "src")


def test_acceptance_gripper_arm(tmp_path, gripper_arm):
    top, packages = gripper_arm
    result, urdf = import_and_build(tmp_path, top, packages, ARM_ARGS)
    reference = xacro_reference(top, packages, ARM_ARGS, tmp_path / "reference.urdf")
    a, b = read_urdf(reference), read_urdf(urdf)
    assert compare(a, b, TOL, configs=100) == []
    assert {"hand_finger_left", "hand_finger_right", "tool0", "hand_palm"} <= set(b.links)
    assert b.joints["hand_finger_right_joint"].mimic == ("hand_finger_left_joint", -1.0, 0.05)
    assert b.links["hand_palm"].mass == 0.25 and b.joints["shoulder"].effort == 40.0  # args and load_yaml
    # the rotated inertial frame: the recipe holds the tensor in link axes (R I R^T)
    data = yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))
    inertial = data["links"]["upper_arm"]["inertial"]
    assert inertial["com"] == [0.001, -0.002, 0.175] and inertial["mass"] == 1.2
    from robotkit.geometry import rpy_matrix

    R = rpy_matrix((0.3, -0.2, 0.7))
    I0 = np.array([[0.015, 0.0001, -0.00005], [0.0001, 0.0148, 0.00002], [-0.00005, 0.00002, 0.0009]])
    t = inertial["inertia"]
    got = np.array([[t["ixx"], t["ixy"], t["ixz"]], [t["ixy"], t["iyy"], t["iyz"]], [t["ixz"], t["iyz"], t["izz"]]])
    assert np.allclose(got, R @ I0 @ R.T, rtol=0, atol=1e-15)
    # materials: global + inline of the same colour deduplicated; texture-only kept with grey
    assert data["materials"]["steel"] == {"rgba": [0.6, 0.6, 0.65, 1]}
    assert data["materials"]["carbon"] == {"rgba": [0.5, 0.5, 0.5, 1]}
    assert data["materials"]["orange"] == {"rgba": [1, 0.42, 0.04, 1], "gazebo": "Gazebo/Orange"}
    assert any("material 'carbon'" in w and "texture" in w for w in result.warnings)
    # gazebo: contact values into the recipe, the rest (selfCollide, plugin, transmission) verbatim
    assert data["links"]["hand_finger_left"]["contact"] == {"mu1": 1.5, "mu2": 1.5, "kp": 1000000, "kd": 100}
    assert data["links"]["upper_arm"]["contact"] == {"mu1": 0.8, "mu2": 0.7}
    assert any("<selfCollide>true</selfCollide>" in x for x in data["urdf_extras"])
    assert _gazebo_content(urdf) == _gazebo_content(reference)
    # the continuous joint keeps effort and velocity only; the link-less tool frame has no inertial
    assert data["joints"]["wrist"]["limit"] == {"effort": 5, "velocity": 3}
    assert data["links"]["tool0"] == {}
    assert {str(Path(p)) for p in result.inputs} >= {str(top), str(Path(packages["hand_description"]) / "urdf/hand.xacro"),
                                                     str(Path(packages["gripper_arm_description"]) / "config/arm.yaml")}


def test_cli_module(tmp_path, gripper_arm, capsys):
    """robotkit import through the command line's parser and robotkit/commands/import_.py."""
    from robotkit.cli import main

    top, packages = gripper_arm
    argv = ["import", str(top), "-o", str(tmp_path / "arm.yaml"), "--arg", "arm_length:=0.35",
            "--arg", "hand_mass:=0.25"]
    for name, folder in packages.items():
        argv += ["--package-path", f"{name}={folder}"]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert "wrote" in out and "warning: " in err
    assert "xacro arguments: arm_length:=0.35 hand_mass:=0.25" in (tmp_path / "arm.yaml").read_text()
    with pytest.raises(SystemExit):
        main(["import", str(top), "-o", "x.yaml", "--arg", "arm_length=0.35"])


def test_link_without_inertial_but_with_geometry(tmp_path):
    """robotkit computes an inertial when a recipe gives none; a URDF link with geometry and no
    inertial must not gain mass.  Uses the schema's "no inertial" form when it has one,
    otherwise says so in a warning."""
    urdf = _write(tmp_path / "r.urdf", """
        <robot name="r">
          <link name="base"><inertial><mass value="1"/>
            <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
          <joint name="j" type="fixed"><parent link="base"/><child link="cover"/></joint>
          <link name="cover"><visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual></link>
        </robot>
    """)
    result = import_file(urdf, tmp_path / "r.yaml", {}, {})
    data = yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))
    form = no_inertial_form()
    if form is None:
        assert "inertial" not in data["links"]["cover"]
        assert any("link 'cover' has no inertial" in w and "adds mass" in w for w in result.warnings)
    else:
        assert data["links"]["cover"]["inertial"] == form
        build([result.recipe_path], tmp_path / "build")
        assert compare(read_urdf(urdf), read_urdf(tmp_path / "build/r/urdf/r.urdf"), TOL) == []


def test_material_conflicts(tmp_path):
    urdf = _write(tmp_path / "m.urdf", """
        <robot name="m">
          <material name="paint"><color rgba="1 0 0 1"/></material>
          <link name="a">
            <visual><geometry><box size="1 1 1"/></geometry><material name="paint"/></visual>
            <inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1"/></inertial>
          </link>
          <joint name="j" type="fixed"><parent link="a"/><child link="b"/></joint>
          <link name="b">
            <visual><geometry><box size="1 1 1"/></geometry><material name="paint"><color rgba="0 0 1 1"/></material></visual>
            <visual><geometry><sphere radius="0.1"/></geometry><material name="paint"><color rgba="1 0 0 1"/></material></visual>
            <inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1"/></inertial>
          </link>
        </robot>
    """)
    result = import_file(urdf, tmp_path / "m.yaml", {}, {})
    data = yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))
    assert data["materials"] == {"paint": {"rgba": [1, 0, 0, 1]}, "paint_2": {"rgba": [0, 0, 1, 1]}}
    assert [v["material"] for v in data["links"]["b"]["visual"]] == ["paint_2", "paint"]
    assert data["links"]["b"]["collision"] == "none"
    assert any("defined with different colours" in w for w in result.warnings)


# ---------------------------------------------------------------- the xacro macro output


def _finalized_robot(recipe: Path, out: Path):
    """The robot as the build's emitters see it (explicit inertials need no mesh facts)."""
    from robotkit.pipeline.actions import read_facts
    from robotkit.model.resolve import finalize
    from robotkit.model.load import load_robots
    from robotkit.pipeline.publish import STATE

    (_, robot), = load_robots([recipe])
    facts_dir = out / STATE / robot.name / "mesh"
    facts = read_facts({p.stem: str(p) for p in facts_dir.glob("*.json")})
    return finalize(robot, facts)


def _sub_model(model: KModel, prefix: str) -> KModel:
    """The part of an assembly whose names carry ``prefix``, with the prefix removed."""
    def strip(name):
        return name[len(prefix):] if name.startswith(prefix) else name

    def strip_fixed(name):
        m = re.fullmatch(r"\(fixed (.*)\)", name)
        return f"(fixed {strip(m.group(1))})" if m else strip(name)

    links = {strip(n): replace(link, name=strip(n)) for n, link in model.links.items() if n.startswith(prefix)}
    joints = {}
    for name, j in model.joints.items():
        if not (j.child.startswith(prefix) and j.parent.startswith(prefix)):
            continue
        mimic = (strip(j.mimic[0]),) + tuple(j.mimic[1:]) if j.mimic else None
        joints[strip_fixed(name)] = replace(j, name=strip_fixed(name), parent=strip(j.parent),
                                            child=strip(j.child), mimic=mimic)
    return KModel(f"{model.source} [{prefix}*]", links, joints)


@pytest.mark.slow
def test_xacro_macro_in_an_assembly(tmp_path, gripper_arm):
    import xacro

    from robotkit.emit.xacro_macro import render_xacro_macro

    top, packages = gripper_arm
    result, urdf = import_and_build(tmp_path, top, packages, ARM_ARGS)
    robot = _finalized_robot(result.recipe_path, tmp_path / "build")
    macro = tmp_path / "gripper_arm.urdf.xacro"
    macro.write_text(render_xacro_macro(robot), encoding="utf-8")
    wrapper = _write(tmp_path / "cell.urdf.xacro", """
        <?xml version="1.0"?>
        <robot name="cell" xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:include filename="gripper_arm.urdf.xacro"/>
          <link name="table"/>
          <xacro:gripper_arm prefix="left_" parent="table">
            <origin xyz="0 0.4 0.75" rpy="0 0 0.3"/>
          </xacro:gripper_arm>
          <xacro:gripper_arm prefix="right_" parent="table">
            <origin xyz="0 -0.4 0.75" rpy="0 0 -0.3"/>
          </xacro:gripper_arm>
        </robot>
    """)
    xacro.all_includes.clear()
    doc = xacro.process_file(str(wrapper))
    cell = tmp_path / "cell.urdf"
    cell.write_text(doc.toprettyxml(indent="  "), encoding="utf-8")
    check_urdf(cell)
    assembly, single = read_urdf(cell), read_urdf(urdf)
    for prefix, xyz, yaw in (("left_", (0, 0.4, 0.75), 0.3), ("right_", (0, -0.4, 0.75), -0.3)):
        assert compare(single, _sub_model(assembly, prefix), TOL, configs=100) == []
        pose = assembly.fk({})[f"{prefix}base_link"]
        assert np.allclose(pose[:3, 3], xyz, atol=1e-12)
        assert np.allclose(pose[:2, 0], (np.cos(yaw), np.sin(yaw)), atol=1e-12)
    # names in the verbatim extras follow the prefix; ${...} in them is not evaluated
    root = ET.parse(cell).getroot()
    refs = {g.get("reference") for g in root.findall("gazebo") if g.get("reference")}
    assert {"left_upper_arm", "right_upper_arm", "left_hand_finger_left"} <= refs
    assert {t.get("name") for t in root.findall("transmission")} == {"left_shoulder_trans", "right_shoulder_trans"}
    assert {j.get("name") for t in root.findall("transmission") for j in t.findall("joint")} == {
        "left_shoulder", "right_shoulder"}
    assert not [m.get("name") for m in root.findall("material") if not m.get("name").startswith(("left_", "right_"))]


def test_xacro_macro_escapes_dollars_in_extras(tmp_path):
    import xacro

    from robotkit.emit.xacro_macro import render_xacro_macro

    recipe = _write(tmp_path / "d.yaml", """
        robot: d
        links:
          base: {inertial: {mass: 1, inertia: {ixx: 1, iyy: 1, izz: 1}}}
        urdf_extras:
          - '<gazebo reference="base"><plugin name="p" filename="x.so"><expr>${not_xacro}</expr><sub>$(arg q)</sub></plugin></gazebo>'
    """)
    text = render_xacro_macro(_finalized_robot(recipe, tmp_path / "out"))
    wrapper = _write(tmp_path / "w.xacro", """
        <robot name="w" xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:include filename="d.urdf.xacro"/>
          <link name="world"/>
          <xacro:d prefix="a_" parent="world"><origin xyz="0 0 0" rpy="0 0 0"/></xacro:d>
        </robot>
    """)
    (tmp_path / "d.urdf.xacro").write_text(text, encoding="utf-8")
    xacro.all_includes.clear()
    out = xacro.process_file(str(wrapper)).toxml()
    assert "<expr>${not_xacro}</expr>" in out and "<sub>$(arg q)</sub>" in out and 'reference="a_base"' in out


# ---------------------------------------------------------------- untrusted files


EVIL = {
    "import": "${__import__('os').system('touch PWNED')}",
    "eval-exec": "$(eval exec('import os;os.system(\"touch PWNED\"${'%c'%41}', {}${'%c'%41} or 'a')",
    "eval-open": "$(eval open('PWNED', 'w'${'%c'%41} and 'a')",
    "vars": "${python.vars(python.type(xacro.load_yaml))}",
    "frame": "${[g for g in [(x for x in [1])]][0].gi_frame}",
    "format": "${('%c0.real%c' % (123, 125)).format(1)}",
    "getattr-string": "${python['vars'](xacro)}",
}


@pytest.mark.parametrize("case", sorted(EVIL))
def test_untrusted_expressions_fail_clearly(tmp_path, monkeypatch, case):
    monkeypatch.chdir(tmp_path)
    target = tmp_path / "PWNED"
    expr = EVIL[case].replace("PWNED", str(target))
    src = tmp_path / "evil.urdf.xacro"
    src.write_text('<robot name="evil" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'
                   f'  <link name="base"><visual><geometry><box size="1 1 1"/></geometry></visual></link>\n'
                   f'  <gazebo><value>{expr.replace("&", "&amp;").replace("<", "&lt;")}</value></gazebo>\n'
                   '</robot>\n', encoding="utf-8")
    with pytest.raises(RobotkitError) as info:
        import_file(src, tmp_path / "evil.yaml", {}, {})
    lines = info.value.lines()
    assert len(lines) == 1 and lines[0].startswith("evil.urdf.xacro:3: ")
    if case != "getattr-string":  # python['vars'] is not there at all: xacro's own error
        assert "refusing to evaluate xacro expression" in lines[0], lines[0]
    assert not target.exists() and not (tmp_path / "evil.yaml").exists()


def test_untrusted_yaml_is_safe_loaded(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "evil.yaml").write_text(f"x: !!python/object/apply:os.system ['touch {tmp_path}/PWNED']\n")
    src = _write(tmp_path / "y.urdf.xacro", """
        <robot name="y" xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:property name="c" value="${xacro.load_yaml('evil.yaml')}"/>
          <link name="${c['x']}"/>
        </robot>
    """)
    with pytest.raises(RobotkitError) as info:
        import_file(src, tmp_path / "y.yaml", {}, {})
    assert info.value.lines()[0].startswith("y.urdf.xacro:3: xacro: ")
    assert not (tmp_path / "PWNED").exists()


@pytest.mark.slow
def test_xacro_state_is_restored(tmp_path):
    """The import patches xacro's module state for its own expansion only."""
    import xacro
    import xacro.substitution_args as sa

    before = (xacro.safe_eval, xacro._global_symbols, sa._eval, sa._eval_find, sa._eval_dict.get("find"))
    degrees = "!degrees" in yaml.SafeLoader.yaml_constructors
    import_file(ASSETS / "ur_description/urdf/ur5.xacro", tmp_path / "u.yaml", PACKAGES, {})  # load_yaml, !degrees
    import_file(ASSETS / "realsense2_description/urdf/test_d435_camera.urdf.xacro", tmp_path / "d.yaml", PACKAGES, {})
    with pytest.raises(RobotkitError):
        import_file(ASSETS / "realsense2_description/urdf/test_d435_camera.urdf.xacro", tmp_path / "e.yaml", {}, {})
    assert before == (xacro.safe_eval, xacro._global_symbols, sa._eval, sa._eval_find, sa._eval_dict.get("find"))
    assert "vars" in xacro._global_symbols["python"]
    assert ("!degrees" in yaml.SafeLoader.yaml_constructors) == degrees


# ---------------------------------------------------------------- error messages


def test_missing_package_in_xacro(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    src = _write(tmp_path / "robot.urdf.xacro", """
        <robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:include filename="$(find foo_description)/urdf/foo.xacro"/>
        </robot>
    """)
    with pytest.raises(RobotkitError) as info:
        import_file(src, tmp_path / "r.yaml", {}, {})
    assert info.value.lines() == [
        "robot.urdf.xacro:2: package 'foo_description' not found; give --package-path foo_description=DIR"]
    assert not (tmp_path / "r.yaml").exists()


def test_missing_package_in_an_included_file(tmp_path, monkeypatch, gripper_arm):
    monkeypatch.chdir(tmp_path)
    top, packages = gripper_arm
    del packages["hand_description"]
    with pytest.raises(RobotkitError) as info:
        import_file(top, tmp_path / "r.yaml", packages, ARM_ARGS)
    assert info.value.lines() == [
        "src/gripper_arm_description/urdf/gripper_arm.urdf.xacro:9: package 'hand_description' not found; "
        "give --package-path hand_description=DIR"]


def test_missing_mesh_package_and_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "pkg" / "meshes").mkdir(parents=True)
    src = _write(tmp_path / "robot.urdf", """
        <robot name="r">
          <link name="base">
            <visual><geometry><mesh filename="package://foo/meshes/a.stl"/></geometry></visual>
            <collision><geometry><mesh filename="package://pkg/meshes/missing.stl"/></geometry></collision>
          </link>
        </robot>
    """)
    with pytest.raises(RobotkitError) as info:
        import_file(src, tmp_path / "r.yaml", {"pkg": str(tmp_path / "pkg")}, {})
    assert info.value.lines() == [
        "robot.urdf:3: link 'base': mesh 'package://foo/meshes/a.stl': package 'foo' not found; "
        "give --package-path foo=DIR",
        "robot.urdf:4: link 'base': mesh 'package://pkg/meshes/missing.stl' not found "
        "(looked for pkg/meshes/missing.stl)",
    ]
    assert not (tmp_path / "r.yaml").exists()


def test_missing_xacro_argument_and_bad_package_path(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    src = _write(tmp_path / "a.xacro", """
        <robot name="a" xmlns:xacro="http://www.ros.org/wiki/xacro">
          <link name="$(arg link_name)"/>
        </robot>
    """)
    with pytest.raises(RobotkitError) as info:
        import_file(src, tmp_path / "a.yaml", {}, {})
    assert info.value.lines() == ["a.xacro:2: xacro argument 'link_name' is not set; give --arg link_name:=VALUE"]
    with pytest.raises(RobotkitError) as info:
        import_file(src, tmp_path / "a.yaml", {"p": str(tmp_path / "nowhere")}, {"link_name": "b"})
    assert info.value.lines() == [f"--package-path p={tmp_path / 'nowhere'}: no such folder"]


def test_metadata_comes_from_the_package_xml(tmp_path):
    """kinova_description's package.xml (format 1, catkin): the recipe gets its metadata and ros: ros1."""
    pkg = tmp_path / "kinova_description"
    (pkg / "urdf").mkdir(parents=True)
    shutil.copyfile(ASSETS / "robots" / "kinova_description" / "package.xml", pkg / "package.xml")
    (pkg / "urdf" / "box.urdf").write_text(
        '<robot name="box"><link name="base"><visual><geometry><box size="1 1 1"/></geometry></visual></link></robot>')
    result = import_file(pkg / "urdf" / "box.urdf", tmp_path / "box.yaml", {}, {})
    assert f"metadata from {pkg / 'package.xml'}" in result.warnings
    data = yaml.safe_load((tmp_path / "box.yaml").read_text())
    assert data["ros"] == "ros1"
    assert data["metadata"] == {
        "version": "0.0.1",
        "description": "3D model of various Kinova robotic arms. Includes the model and URDF files for working "
                       "with an arm in RViz or Gazebo.",
        "authors": [{"name": "Kinova Support"}],
        "maintainers": [{"name": "Kinova Support", "email": "support@kinova.ca"}],
        "license": "BSD",
        "urls": {"website": "http://ros.org/wiki/kinova_description"}}
    build([tmp_path / "box.yaml"], tmp_path / "out")
    assert '<maintainer email="support@kinova.ca">Kinova Support</maintainer>' in (
        tmp_path / "out" / "box" / "package.xml").read_text()


# ---------------------------------------------------------------- the recipe written for people: defaults


SHARED_VALUES = """
    <robot name="d">
      <link name="l0"/><link name="l1"/><link name="l2"/><link name="l3"/><link name="l4"/><link name="l5"/>
      <joint name="j1" type="revolute"><parent link="l0"/><child link="l1"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="10" velocity="2"/><dynamics damping="0.5"/></joint>
      <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><axis xyz="0 0 1"/>
        <limit lower="-2" upper="2" effort="10" velocity="2"/><dynamics damping="0.5"/></joint>
      <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><axis xyz="0 0 1"/>
        <limit lower="-3" upper="3" effort="10" velocity="2"/><dynamics damping="0.5" friction="1"/></joint>
      <joint name="j4" type="continuous"><parent link="l3"/><child link="l4"/>
        <dynamics damping="0.5"/></joint>
      <joint name="tool" type="fixed"><parent link="l4"/><child link="l5"/></joint>
    </robot>
"""


def test_shared_joint_values_go_to_defaults(tmp_path):
    """Values more than half of the joints hold (and at least three) are written once in
    ``defaults``; a joint with another value keeps its own, one with none says so (the schema's
    default, or null); a default limit or axis does not go to a fixed joint.  The recipe builds
    the same robot as the URDF."""
    urdf = _write(tmp_path / "d.urdf", SHARED_VALUES)
    for i in range(6):
        urdf.write_text(urdf.read_text().replace(f'<link name="l{i}"/>', f'<link name="l{i}"><inertial><mass value="1"/>'
                        '<inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>'))
    result = import_file(urdf, tmp_path / "d.yaml", {}, {})
    text = result.recipe_path.read_text(encoding="utf-8")
    assert text.split("\njoints:\n")[1] == "  " + textwrap.dedent("""\
          j1:
            parent: l0
            child: l1
            limit: {lower: -1, upper: 1}
          j2:
            parent: l1
            child: l2
            limit: {lower: -2, upper: 2}
          j3:
            parent: l2
            child: l3
            limit: {lower: -3, upper: 3}
            dynamics: {friction: 1}
          j4:
            type: continuous
            parent: l3
            child: l4
            axis: [1, 0, 0]
            limit: null
          tool:
            type: fixed
            parent: l4
            child: l5
            dynamics: null
        """).replace("\n", "\n  ").rstrip(" ")
    assert "\ndefaults:\n  joint: {type: revolute, axis: [0, 0, 1], limit: {effort: 10, velocity: 2}, " \
           "dynamics: {damping: 0.5}}\n" in text
    built = build([result.recipe_path], tmp_path / "build")
    assert not built.errors, built.errors
    assert compare(read_urdf(urdf), read_urdf(tmp_path / "build/d/urdf/d.urdf"), TOL) == []


def test_prismatic_joint_with_equal_limits_is_fixed_where_it_can_be(tmp_path):
    """lower == upper: the joint can only be there (Gazebo, Drake, Pinocchio hold it; MuJoCo would
    let it slide), so the recipe fixes it there and says so; a mimic it had goes with it."""
    inertia = '<inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>'
    urdf = _write(tmp_path / "p.urdf", f"""
        <robot name="p">
          <link name="a">{inertia}</link><link name="b">{inertia}</link><link name="c">{inertia}</link>
          <joint name="lead" type="prismatic"><parent link="a"/><child link="b"/>
            <limit lower="0" upper="0.1" effort="1" velocity="1"/></joint>
          <joint name="slide" type="prismatic"><parent link="b"/><child link="c"/><origin xyz="0.5 0 0"/>
            <limit lower="0" upper="0" effort="0" velocity="0"/><mimic joint="lead"/></joint>
        </robot>
    """)
    result = import_file(urdf, tmp_path / "p.yaml", {}, {})
    assert result.joint_notes == {"slide": "limit lower == upper (0.0) in the original: the joint can only be at "
                                           "that position, so it is fixed there; MuJoCo would ignore the equal limits "
                                           "and let it slide freely; its mimic is dropped"}
    assert "joint 'slide': a fixed joint follows no other joint: its <mimic> is dropped" in result.warnings
    data = yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))
    assert data["joints"]["slide"] == {"type": "fixed", "parent": "b", "child": "c", "origin": {"xyz": [0.5, 0, 0]}}


@pytest.mark.slow
def test_a_build_imports_back_into_the_same_robot(examples, tmp_path):
    """build -> import -> build: the URDF of every example imports (its massless frame links,
    written as 1e-300 kg with no inertia, come back massless) and builds into the same robot:
    masses, tensors, frames and limits at 1e-9."""
    urdfs = sorted(examples.glob("*/urdf/*.urdf"))
    assert len(urdfs) == 7 and sum('<mass value="1e-300"/>' in u.read_text(encoding="utf-8") for u in urdfs) >= 5
    for urdf in urdfs:
        name = urdf.stem
        result = import_file(urdf, tmp_path / name / "robot.yaml", {name: str(examples / name)}, {})
        assert not any("massless" in w for w in result.warnings), result.warnings
        built = build([result.recipe_path], tmp_path / name / "build")
        assert not built.errors, (name, built.errors)
        again = tmp_path / name / "build" / result.robot / "urdf" / f"{result.robot}.urdf"
        assert compare(read_urdf(urdf), read_urdf(again), TOL, configs=20) == [], name


def test_a_tiny_mass_without_inertia_is_a_massless_link(tmp_path):
    urdf = _write(tmp_path / "t.urdf", """
        <robot name="t">
          <link name="base"><inertial><mass value="1"/>
            <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
          <joint name="j" type="fixed"><parent link="base"/><child link="tip"/></joint>
          <link name="tip"><inertial><mass value="1e-12"/><inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/>
            </inertial></link>
        </robot>
    """)
    result = import_file(urdf, tmp_path / "t.yaml", {}, {})
    assert "link 'tip': mass 1e-12 kg with no inertia, below the smallest mass a recipe takes (1e-9 kg): read " \
           "as a massless link" in result.warnings
    assert yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))["links"]["tip"] == {}
