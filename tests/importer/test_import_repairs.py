"""Issue 32: import gives robots that check clean, and says what it changed.

Each rule on a small robot of the shape the public corpus showed, written here:

- names with a leading '/' (the Interbotix PincherX 100 / WidowX 200 and 250: ``/base_link``,
  ``${robot_name}/...`` with an empty name) lose it, in joints, mimics, gazebo blocks and
  transmissions too;
- a ``<mimic>`` on a fixed joint is dropped (TALOS reduced: its locked gripper joints keep theirs);
- position limits of about +-1e16 (the Iris drone's rotors: "unlimited") make a continuous joint,
  or are clamped to the recipe's range on one side of a prismatic joint;
- a tensor that does not fit its geometry (a placeholder of 1 kg m^2 on a 5 cm part, the rotor's
  axes swapped) is recomputed from it, a mass that is the geometry's volume at density 1
  (MeshLab's) is computed at the recipe's density; ``--inertia-policy keep`` keeps both and check
  reports them;
- an effort or velocity limit of 0 on a joint that nothing drives is a passive joint (kept and
  stated), on a joint a transmission drives an error check names.

Each change is one comment above the thing in the recipe and one warning, word for word; the
imported recipe builds, and the real ``robotkit check`` of the build has no error (but the one the
original's driven joint with effort 0 is).
"""

from __future__ import annotations

import textwrap

import pytest
import yaml

from robotkit.check.lints import lint_joints, read_urdf_facts
from robotkit.importer import import_file
from robotkit.pipeline.runner import build


def _link(name: str, mass: float, moments, size: str = "0.05 0.05 0.05") -> str:
    ixx, iyy, izz = moments
    return (f'  <link name="{name}">\n    <inertial><mass value="{mass}"/><inertia ixx="{ixx}" ixy="0" ixz="0" '
            f'iyy="{iyy}" iyz="0" izz="{izz}"/></inertial>\n    <visual><geometry><box size="{size}"/></geometry>'
            "</visual>\n  </link>\n")


def _cube(name: str, mass: float, side: float = 0.05) -> str:
    """A cube whose tensor is its geometry's."""
    moment = mass * side * side / 6
    return _link(name, mass, (moment,) * 3, f"{side} {side} {side}")


def _joint(name: str, parent: str, child: str, jtype: str = "revolute", limit: str = 'lower="-1" upper="1" '
           'effort="5" velocity="1"', more: str = "") -> str:
    axis = '<axis xyz="0 0 1"/>' if jtype != "fixed" else ""
    lim = f"<limit {limit}/>" if jtype != "fixed" else ""
    return (f'  <joint name="{name}" type="{jtype}">\n    <parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="0 0 0.1"/>{axis}{lim}{more}\n  </joint>\n')


def _robot(name: str, body: str) -> str:
    return f'<?xml version="1.0"?>\n<robot name="{name}">\n{body}</robot>\n'


SLASH = _robot("px100", _cube("/base_link", 1.0) + _cube("/shoulder_link", 0.2) + _cube("/finger_link", 0.05)
               + _joint("/waist", "/base_link", "/shoulder_link")
               + _joint("finger", "/shoulder_link", "/finger_link", more='<mimic joint="/waist"/>')
               + '  <gazebo reference="/base_link">\n    <self_collide>true</self_collide>\n  </gazebo>\n'
               + textwrap.indent(textwrap.dedent("""\
                   <transmission name="waist_trans">
                     <type>transmission_interface/SimpleTransmission</type>
                     <joint name="/waist"><hardwareInterface>EffortJointInterface</hardwareInterface></joint>
                     <actuator name="waist_motor"><mechanicalReduction>1</mechanicalReduction></actuator>
                   </transmission>
                   """), "  "))

MIMIC = _robot("talos_gripper", _cube("base", 1.0) + _cube("finger", 0.1) + _cube("finger_inner", 0.1)
               + _joint("gripper_joint", "base", "finger")
               + _joint("gripper_inner_joint", "finger", "finger_inner", "fixed",
                        more='<mimic joint="gripper_joint" multiplier="-1" offset="0"/>'))

UNLIMITED = _robot("iris", _cube("base_link", 1.5, 0.2) + _cube("rotor_0", 0.05) + _cube("slider", 0.05)
                   + _joint("rotor_0_joint", "base_link", "rotor_0",
                            limit='effort="10" lower="-1e+16" upper="1e+16" velocity="1"')
                   + _joint("slide", "base_link", "slider", "prismatic",
                            limit='effort="10" lower="0" upper="1e+16" velocity="1"'))

PLACEHOLDERS = _robot("placeholders", _cube("base_link", 2.0, 0.1) + _link("sensor", 0.1, (1, 1, 1))
                      + _link("rotor", 0.005, (9.75e-07, 0.000273104, 0.000274004), "0.25 0.25 0.005")
                      + _cube("shell", 0.001, 0.1)
                      + _joint("sensor_joint", "base_link", "sensor", "fixed")
                      + _joint("rotor_joint", "base_link", "rotor", "continuous", 'effort="1" velocity="10"')
                      + _joint("shell_joint", "base_link", "shell"))

ZERO_LIMITS = _robot("wheels", _cube("base_link", 2.0, 0.1) + _cube("caster", 0.27) + _cube("arm", 0.27)
                     + _joint("caster_joint", "base_link", "caster", limit='lower="-3" upper="3" effort="0" velocity="0"')
                     + _joint("arm_joint", "base_link", "arm", limit='lower="-3" upper="3" effort="0" velocity="1"')
                     + textwrap.indent(textwrap.dedent("""\
                         <transmission name="arm_trans">
                           <type>transmission_interface/SimpleTransmission</type>
                           <joint name="arm_joint"><hardwareInterface>EffortJointInterface</hardwareInterface></joint>
                           <actuator name="arm_motor"><mechanicalReduction>1</mechanicalReduction></actuator>
                         </transmission>
                         """), "  "))

# SO-ARM100 (example-robot-data): its joint 'gripper' moves the jaw on the link 'gripper'
GRIPPER = _robot("so100", _cube("base", 1.0) + _cube("gripper", 0.2) + _cube("jaw", 0.05) + _cube("jaw2", 0.05)
                 + _joint("wrist_roll", "base", "gripper") + _joint("gripper", "gripper", "jaw")
                 + _joint("jaw_mirror", "gripper", "jaw2", more='<mimic joint="gripper"/>')
                 + '  <gazebo reference="gripper"><mu1>0.9</mu1></gazebo>\n'
                 '  <transmission name="gripper_trans"><type>transmission_interface/SimpleTransmission</type>'
                 '<joint name="gripper"><hardwareInterface>hardware_interface/PositionJointInterface'
                 '</hardwareInterface></joint><actuator name="motor6"><mechanicalReduction>1</mechanicalReduction>'
                 '</actuator></transmission>\n')

ROBOTS = {"slash": SLASH, "mimic": MIMIC, "unlimited": UNLIMITED, "placeholders": PLACEHOLDERS,
          "zero_limits": ZERO_LIMITS, "gripper": GRIPPER}


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # warnings name the input relative to here


def _import(tmp_path, name: str, **kw):
    source = tmp_path / f"{name}.urdf"
    source.write_text(ROBOTS[name], encoding="utf-8")
    result = import_file(source, tmp_path / "recipe" / "robot.yaml", {}, {}, **kw)
    text = result.recipe_path.read_text(encoding="utf-8")
    return result, text, yaml.safe_load(text)


def _comment_above(text: str, key: str) -> str:
    """The comment lines right above ``  key:`` in the recipe, joined."""
    lines = text.splitlines()
    at = lines.index(f"  {key}:")
    above = []
    for line in reversed(lines[:at]):
        if not line.startswith("  # "):
            break
        above.insert(0, line[4:])
    return " ".join(above)


RENAMED = ("named '/{}' in the original: a recipe name cannot start with '/' (the old tf_prefix style), so the '/' "
           "is dropped here and where {} name it")


def test_a_leading_slash_is_dropped_from_names_and_references(tmp_path):
    result, text, recipe = _import(tmp_path, "slash")
    links = RENAMED.replace("{}", "{}", 1)
    assert [w for w in result.warnings if "named '/" in w] == [
        f"link '{n}': " + links.format(n, "its joints and gazebo blocks")
        for n in ("base_link", "shoulder_link", "finger_link")] + [
        "joint 'waist': " + RENAMED.format("waist", "mimics and transmissions")]
    assert _comment_above(text, "base_link") == RENAMED.format("base_link", "its joints and gazebo blocks")
    assert _comment_above(text, "waist") == RENAMED.format("waist", "mimics and transmissions")
    assert list(recipe["links"]) == ["base_link", "shoulder_link", "finger_link"]
    assert recipe["joints"]["waist"]["parent"] == "base_link"
    assert recipe["joints"]["finger"]["mimic"] == {"joint": "waist"}
    assert '<gazebo reference="base_link">' in recipe["urdf_extras"][0]
    assert '<joint name="waist">' in recipe["urdf_extras"][1]


def test_a_bare_name_taken_keeps_its_slash_and_is_refused(tmp_path):
    from robotkit.errors import RobotkitError

    source = tmp_path / "both.urdf"
    source.write_text(_robot("both", _cube("base_link", 1.0) + _cube("/base_link", 0.2)
                             + _joint("j", "base_link", "/base_link")), encoding="utf-8")
    with pytest.raises(RobotkitError) as info:
        import_file(source, tmp_path / "recipe" / "robot.yaml", {}, {})
    assert [p.message for p in info.value.problems] == [
        "link name '/base_link' is not a valid recipe name (a name starts with a letter or '_' and holds only "
        "letters, digits, '_', '-' and '.', with '/' between parts (a ROS frame name such as arm/link_1))"]


def test_a_mimic_on_a_fixed_joint_is_dropped(tmp_path):
    result, text, recipe = _import(tmp_path, "mimic")
    note = ("a fixed joint mimicking joint 'gripper_joint' in the original: a fixed joint follows no other joint, so "
            "the mimic is dropped")
    assert f"joint 'gripper_inner_joint': {note}" in result.warnings
    assert result.joint_notes == {"gripper_inner_joint": note}
    assert _comment_above(text, "gripper_inner_joint") == note
    assert "mimic" not in recipe["joints"]["gripper_inner_joint"]


def test_limits_beyond_the_physical_range_are_unlimited(tmp_path):
    result, text, recipe = _import(tmp_path, "unlimited")
    rotor = ("limit lower -1e+16 and upper 1e+16 in the original, beyond any physical range (a recipe's is +-10000): "
             "read as no position limit, the joint is continuous")
    slide = ("limit upper 1e+16 in the original, beyond any physical range (a recipe's is +-10000): read as no limit "
             "on that side, clamped to the recipe's")
    assert [w for w in result.warnings if "1e+16" in w] == [f"joint 'rotor_0_joint': {rotor}", f"joint 'slide': {slide}"]
    assert result.joint_notes == {"rotor_0_joint": rotor, "slide": slide}
    assert _comment_above(text, "rotor_0_joint") == rotor
    assert recipe["joints"]["rotor_0_joint"]["type"] == "continuous"
    assert recipe["joints"]["rotor_0_joint"]["limit"] == {"effort": 10, "velocity": 1}
    assert recipe["joints"]["slide"]["limit"] == {"lower": 0, "upper": 10000, "effort": 10, "velocity": 1}


SENSOR = ("the given inertial does not fit its geometry: its equivalent inertia box (7.75 x 7.75 x 7.75 m) is 155x "
          "larger than the geometry's at uniform density (0.05 x 0.05 x 0.05 m), along x, y, z")
ROTOR = ("the given inertial does not fit its geometry: its equivalent inertia box (0.81 x 0.0474 x 0.00949 m) is "
         "5.27x smaller than the geometry's at uniform density (0.25 x 0.25 x 0.005 m), along x, y, z")
SHELL = ("the original's mass 0.001 kg over its geometry's 0.001 m^3 implies 1 kg/m^3, below 10 (the mass is the "
         "mesh volume at density 1, MeshLab's default)")


def test_tensors_that_do_not_fit_and_meshlab_masses_are_recomputed(tmp_path):
    result, text, recipe = _import(tmp_path, "placeholders")
    recomputed = ": recomputed from its visual geometry, keeping the mass (policy: recompute; the given com and " \
                 "inertia are unused)"
    at_density = ": mass and inertia computed from its visual geometry at the recipe's density (the given ones are " \
                 "unused)"
    assert result.repairs == {"sensor": SENSOR + recomputed, "rotor": ROTOR + recomputed, "shell": SHELL + at_density}
    source = "placeholders.urdf"
    assert [w for w in result.warnings if "link '" in w] == [
        f"{source}:7: link 'sensor': {SENSOR}{recomputed}", f"{source}:11: link 'rotor': {ROTOR}{recomputed}",
        f"{source}:15: link 'shell': {SHELL}{at_density}"]
    assert _comment_above(text, "sensor") == SENSOR + recomputed
    assert _comment_above(text, "shell") == SHELL + at_density
    assert recipe["links"]["sensor"]["inertial"]["policy"] == "recompute"
    assert "inertial" not in recipe["links"]["shell"]
    assert recipe["links"]["base_link"]["inertial"]["mass"] == 2.0  # a tensor that fits is the vendor's


def test_keep_keeps_them_with_a_warning(tmp_path):
    result, text, recipe = _import(tmp_path, "placeholders", inertia_policy="keep")
    source = "placeholders.urdf"
    assert result.repairs == {}
    assert [w for w in result.warnings if "link '" in w] == [
        f"{source}:7: link 'sensor': {SENSOR}; recompute it from the geometry (inertial: {{mass: 0.1}} on the link "
        "in the recipe, or import with --recompute-inertials)",
        f"{source}:11: link 'rotor': {ROTOR}; recompute it from the geometry (inertial: {{mass: 0.005}} on the link "
        "in the recipe, or import with --recompute-inertials)",
        f"{source}:15: link 'shell': {SHELL}; compute it from the geometry at the recipe's density (no inertial on "
        "the link in the recipe)"]
    assert recipe["links"]["sensor"]["inertial"] == {"mass": 0.1, "inertia": {"ixx": 1, "iyy": 1, "izz": 1}}
    assert recipe["links"]["shell"]["inertial"]["mass"] == 0.001


def test_a_zero_limit_is_passive_unless_something_drives_the_joint(tmp_path):
    result, text, recipe = _import(tmp_path, "zero_limits")
    passive = ("effort and velocity limits 0 in the original: nothing drives it (no transmission or ros2_control "
               "command names it), so it is kept as a passive joint")
    assert result.joint_notes == {"caster_joint": passive}
    assert _comment_above(text, "caster_joint") == passive
    source = "zero_limits.urdf"
    assert [w for w in result.warnings if "limit" in w] == [
        f"joint 'caster_joint': {passive}",
        f"{source}:18: joint 'arm_joint': effort limit 0 in the original, and transmission 'arm_trans' drives it: a "
        "driven joint with zero effort cannot move (check reports it; give it the motor's limit)"]
    assert recipe["joints"]["caster_joint"]["limit"] == {"lower": -3, "upper": 3, "effort": 0, "velocity": 0}


def test_check_reads_a_zero_limit_as_passive_unless_driven(tmp_path):
    source = tmp_path / "zero_limits.urdf"
    source.write_text(ZERO_LIMITS.replace("</robot>", textwrap.dedent("""\
        <ros2_control name="hw" type="system">
          <joint name="caster_joint"><state_interface name="position"/></joint>
        </ros2_control>
        </robot>""")), encoding="utf-8")
    links, joints, _ = read_urdf_facts(source)
    found = [(f.severity, f.check, f.subject, f.message) for f in lint_joints(joints)]
    passive = "limit 0: nothing drives it (no transmission or ros2_control command names it), a passive joint"
    assert found == [
        ("warning", "passive-joint", "joint 'caster_joint'", f"effort {passive}"),
        ("warning", "passive-joint", "joint 'caster_joint'", f"velocity {passive}"),
        ("error", "joint-limits", "joint 'arm_joint'", "effort limit 0 is not positive, and transmission 'arm_trans' "
         "drives it: a driven joint with zero effort cannot move")]


EXPECTED_ERRORS = {"zero_limits": [("joint-limits", "joint 'arm_joint'")]}
"""The errors check names on each build: the original's defects the import reports and keeps."""


@pytest.mark.consumers
@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_the_import_builds_and_checks_clean(tmp_path, name):
    from robotkit.commands.check import check

    result, _, _ = _import(tmp_path, name)
    out = build([result.recipe_path], tmp_path / "build")
    assert not out.errors, out.errors
    errors = [(f.check, f.subject) for f in check(str(tmp_path / "build" / result.robot)) if f.severity == "error"]
    assert errors == EXPECTED_ERRORS.get(name, [])


@pytest.mark.consumers
@pytest.mark.slow
def test_with_keep_check_reports_the_kept_tensors(tmp_path):
    from robotkit.commands.check import check

    result, _, _ = _import(tmp_path, "placeholders", inertia_policy="keep")
    out = build([result.recipe_path], tmp_path / "build")
    assert not out.errors, out.errors
    errors = [(f.check, f.subject) for f in check(str(tmp_path / "build" / result.robot)) if f.severity == "error"]
    assert errors == [("inertia-box", "link 'sensor'"), ("inertia-box", "link 'rotor'"),
                      ("implied-density", "link 'shell'")]


def test_a_collision_shared_by_most_links_is_no_default_over_another_shape(tmp_path):
    """The Iris: four rotors with the same collision cylinder, the body with a box; a default
    cylinder would merge into the body's box (both in one geometry), so each keeps its own."""
    def part(name: str, shape: str) -> str:
        return (f'  <link name="{name}"><inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" '
                f'iyz="0" izz="1e-4"/></inertial><visual><geometry><sphere radius="0.03"/></geometry></visual>'
                f'<collision><geometry>{shape}</geometry></collision></link>\n')

    rotors = [f"rotor_{i}" for i in range(4)]
    body = part("base_link", '<box size="0.47 0.47 0.11"/>') + "".join(
        part(r, '<cylinder length="0.005" radius="0.128"/>') + _joint(f"{r}_joint", "base_link", r) for r in rotors)
    source = tmp_path / "rotors.urdf"
    source.write_text(_robot("rotors", body), encoding="utf-8")
    result = import_file(source, tmp_path / "recipe" / "robot.yaml", {}, {})
    recipe = yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))
    assert recipe["links"]["base_link"]["collision"] == {"box": {"size": [0.47, 0.47, 0.11]}}
    assert recipe["links"]["rotor_0"]["collision"] == {"cylinder": {"radius": 0.128, "length": 0.005}}
    assert "link" not in recipe.get("defaults", {})


def test_a_marker_says_nothing_of_the_part_and_the_tensor_is_kept(tmp_path):
    """An IMU frame drawn as a 1 mm box: check reads no part in it (its MARKER), nor does import."""
    source = tmp_path / "marker.urdf"
    source.write_text(_robot("marker", _cube("base_link", 2.0, 0.1) + _link("imu_link", 0.015, (1e-5,) * 3,
                                                                             "0.001 0.001 0.001")
                             + _joint("imu_joint", "base_link", "imu_link", "fixed")), encoding="utf-8")
    result = import_file(source, tmp_path / "recipe" / "robot.yaml", {}, {})
    assert result.repairs == {}
    recipe = yaml.safe_load(result.recipe_path.read_text(encoding="utf-8"))
    assert recipe["links"]["imu_link"]["inertial"] == {"mass": 0.015, "inertia": {"ixx": 1e-5, "iyy": 1e-5,
                                                                                  "izz": 1e-5}}


def test_a_mass_too_heavy_for_its_geometry_is_kept_and_reported(tmp_path):
    """1 kg on a 1 cm box (TIAGo's base_footprint): no one reading (a placeholder on a marker, or a
    part drawn smaller than it is), so the mass is the vendor's, and the import says check's verdict."""
    source = tmp_path / "heavy.urdf"
    source.write_text(_robot("heavy", _cube("base_footprint", 1.0, 0.01)), encoding="utf-8")
    result = import_file(source, tmp_path / "recipe" / "robot.yaml", {}, {})
    assert result.repairs == {}
    assert [w for w in result.warnings if "link '" in w] == [
        "heavy.urdf:3: link 'base_footprint': the original's mass 1 kg over its geometry's 1e-06 m^3 implies 1e+06 "
        "kg/m^3, above 25000 (the mass looks like grams written as kilograms): kept (check reports it)"]


def test_a_mass_too_light_but_not_meshlabs_is_kept_and_reported(tmp_path):
    """simple_humanoid's body: 27 kg in 4.1 m^3 of geometry is no MeshLab mass; the geometry may be
    what is wrong, so the mass is the vendor's and the import says check's verdict."""
    source = tmp_path / "light.urdf"
    source.write_text(_robot("light", _cube("body", 27.0, 1.6)), encoding="utf-8")
    result = import_file(source, tmp_path / "recipe" / "robot.yaml", {}, {})
    assert result.repairs == {}
    assert [w for w in result.warnings if "link '" in w] == [
        "light.urdf:3: link 'body': the original's mass 27 kg over its geometry's 4.096 m^3 implies 6.59 kg/m^3, "
        "below 10 (the density or mass is far too low): kept (check reports it)"]


def test_a_joint_named_like_a_link_is_renamed_with_its_references(tmp_path):
    """libsdformat, reading the URDF for Gazebo, refuses a joint and a link of one name ("Joint with
    non-unique name [gripper]"): the joint gets the name model.sdf gives it, in the URDF too."""
    result, text, recipe = _import(tmp_path, "gripper")
    note = ("named 'gripper' in the original, like a link: links and joints share one namespace in SDF, where "
            "libsdformat (Gazebo) reads the URDF, so it is renamed here and where mimics and transmissions name it")
    assert [w for w in result.warnings if "in the original, like a link" in w] == [f"joint 'gripper_joint': {note}"]
    assert _comment_above(text, "gripper_joint") == note
    assert list(recipe["joints"]) == ["wrist_roll", "gripper_joint", "jaw_mirror"]
    assert recipe["joints"]["gripper_joint"]["parent"] == "gripper"
    assert recipe["joints"]["wrist_roll"]["child"] == "gripper"
    assert recipe["joints"]["jaw_mirror"]["mimic"] == {"joint": "gripper_joint"}
    extras = "".join(recipe["urdf_extras"])
    assert '<gazebo reference="gripper">' in extras  # the link's
    assert '<joint name="gripper_joint">' in extras
