"""Issue 32, ANYmal B's base and the sensors of TIAGo, HyQ and the racecar: the import's density
warning says what check says of the build, which judges a link's implied density on the rigid body
it is welded to (robotkit.model.rigidbody, one function for both): a warning when that body is in
range, an error as before when the link moves on its own or the body is out of range too."""

from __future__ import annotations

from robotkit.check.lints import lint, read_urdf_facts
from robotkit.importer import import_file
from robotkit.pipeline.runner import build

MOMENT = 1e-6 / 12 * 0.08  # the 20 cm box's own tensor at 1e-6 kg: it fits, only the density is judged


def _urdf(tmp_path, kind: str):
    limit = '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="10" velocity="2"/>' if kind == "revolute" else ""
    urdf = tmp_path / "anymal.urdf"
    urdf.write_text(f"""<?xml version="1.0"?>
<robot name="anymal">
  <link name="base">
    <visual><geometry><box size="0.2 0.2 0.2"/></geometry></visual>
    <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
    <inertial><mass value="1e-6"/><inertia ixx="{MOMENT!r}" ixy="0" ixz="0" iyy="{MOMENT!r}" iyz="0" izz="{MOMENT!r}"/>
    </inertial>
  </link>
  <link name="base_inertia">
    <inertial><mass value="16"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
  </link>
  <joint name="base_to_base_inertia" type="{kind}"><parent link="base"/><child link="base_inertia"/>{limit}</joint>
</robot>
""", encoding="utf-8")
    return urdf


def _warned(result):
    return [w.split("anymal.urdf:3: ", 1)[-1] for w in result.warnings if "implies" in w]


def test_a_placeholder_mass_welded_to_the_body_is_reported_as_check_warns(tmp_path):
    result = import_file(_urdf(tmp_path, "fixed"), tmp_path / "recipe" / "robot.yaml")
    assert _warned(result) == [
        "link 'base': the original's mass 1e-06 kg over its geometry's 0.008 m^3 implies 0.000125 kg/m^3, below 10; "
        "the rigid body it is welded to (base, base_inertia: 16 kg, 0.008 m^3) is 2000 kg/m^3: its mass is a share "
        "of that body's: kept (check warns of it)"]
    out = build([result.recipe_path], tmp_path / "build")
    assert not out.errors, out.errors
    links, joints, _ = read_urdf_facts(next((tmp_path / "build" / result.robot).rglob("*.urdf")))
    assert [(f.severity, f.subject, f.message) for f in lint(links, joints) if f.check == "implied-density"] == [
        ("warning", "link 'base'", "implied density 0.000125 kg/m^3 (mass 1e-06 kg, volume 0.008 m^3) is below 10; "
         "the rigid body it is welded to (base, base_inertia: 16 kg, 0.008 m^3) is 2000 kg/m^3: its mass is a share "
         "of that body's")]


def test_the_same_link_on_a_revolute_joint_is_reported_as_check_errs(tmp_path):
    result = import_file(_urdf(tmp_path, "revolute"), tmp_path / "recipe" / "robot.yaml")
    assert _warned(result) == [
        "link 'base': the original's mass 1e-06 kg over its geometry's 0.008 m^3 implies 0.000125 kg/m^3, below 10 "
        "(the density or mass is far too low): kept (check reports it)"]


def test_the_body_counts_a_mass_the_import_computes_as_the_build_does(tmp_path):
    """A MeshLab mass (the volume at density 1) on a 10 cm box gets the recipe's density; a 1e-6 kg
    sensor of 2 cm welded to it is judged on the body with the computed mass, in the import's
    words and check's alike."""
    urdf = tmp_path / "anymal.urdf"
    side, sensor = 0.1, 0.02
    urdf.write_text(f"""<?xml version="1.0"?>
<robot name="anymal">
  <link name="shell">
    <visual><geometry><box size="{side} {side} {side}"/></geometry></visual>
    <inertial><mass value="{side ** 3!r}"/><inertia ixx="{side ** 5 / 6!r}" ixy="0" ixz="0" iyy="{side ** 5 / 6!r}"
      iyz="0" izz="{side ** 5 / 6!r}"/></inertial>
  </link>
  <link name="sensor">
    <visual><geometry><box size="{sensor} {sensor} {sensor}"/></geometry></visual>
    <inertial><mass value="1e-6"/><inertia ixx="{1e-6 * sensor ** 2 / 6!r}" ixy="0" ixz="0"
      iyy="{1e-6 * sensor ** 2 / 6!r}" iyz="0" izz="{1e-6 * sensor ** 2 / 6!r}"/></inertial>
  </link>
  <joint name="sensor_joint" type="fixed"><parent link="shell"/><child link="sensor"/></joint>
</robot>
""", encoding="utf-8")
    result = import_file(urdf, tmp_path / "recipe" / "robot.yaml")
    assert list(result.repairs) == ["shell"]  # MeshLab's mass: computed at the recipe's density
    body = "the rigid body it is welded to (sensor, shell: 1 kg, 0.001008 m^3) is 992.1 kg/m^3"
    assert [w.split("anymal.urdf:8: ", 1)[-1] for w in result.warnings if "sensor" in w] == [
        f"link 'sensor': the original's mass 1e-06 kg over its geometry's 8e-06 m^3 implies 0.125 kg/m^3, below 10; "
        f"{body}: its mass is a share of that body's: kept (check warns of it)"]
    out = build([result.recipe_path], tmp_path / "build")
    assert not out.errors, out.errors
    links, joints, _ = read_urdf_facts(next((tmp_path / "build" / result.robot).rglob("*.urdf")))
    assert [(f.severity, f.subject, f.message) for f in lint(links, joints) if f.check == "implied-density"] == [
        ("warning", "link 'sensor'", "implied density 0.125 kg/m^3 (mass 1e-06 kg, volume 8e-06 m^3) is below 10; "
         f"{body}: its mass is a share of that body's")]
