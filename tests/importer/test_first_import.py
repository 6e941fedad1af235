"""A newcomer's first import (issue 31): a robot from a ROS workspace outside the project, with a
hand-typed tyre tensor and a mesh in millimetres referenced without ``scale``.  The import says
what it changed with the URDF's lines, copies the meshes the build could not read (with the
package's licence) and ends with the build command, which works as printed; the built robot
passes ``robotkit check``."""

from __future__ import annotations

import shlex
from pathlib import Path

import pytest
import yaml

from robotkit.errors import RobotkitError
from robotkit.importer import import_file
from tests.conftest import run_cli

CAR = """\
<?xml version="1.0"?>
<robot name="car">
  <link name="base">
    <visual><geometry><box size="0.2 0.1 0.05"/></geometry></visual>
    <inertial><mass value="1"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.0035" iyz="0" izz="0.0042"/></inertial>
  </link>
  <link name="wheel">
    <visual><geometry><mesh filename="{uri}"/></geometry></visual>
    {inertial}
  </link>
  <joint name="axle" type="continuous">
    <parent link="base"/><child link="wheel"/><origin xyz="0 0.08 0" rpy="1.5707963267948966 0 0"/>
    <axis xyz="0 0 1"/>
  </joint>
</robot>
"""
TYRE = '<inertial><mass value="0.2"/><inertia ixx="0.5" ixy="0" ixz="0" iyy="0.5" iyz="0" izz="2"/></inertial>'
PACKAGE_XML = """\
<?xml version="1.0"?>
<package format="3">
  <name>tyre_pkg</name>
  <version>1.0.0</version>
  <description>A car</description>
  <maintainer email="ada@example.com">Ada</maintainer>
  <license>BSD-3-Clause</license>
</package>
"""


def workspace(tmp_path: Path, uri: str = "package://tyre_pkg/meshes/tyre.stl", inertial: str = TYRE) -> Path:
    """A ROS package outside the project (tmp_path/proj, a repository): the car's URDF and its
    tyre, a cylinder 66 mm across and 18 mm thick exported in millimetres."""
    import trimesh

    pkg = tmp_path / "ws" / "tyre_pkg"
    (pkg / "meshes").mkdir(parents=True)
    (pkg / "urdf").mkdir()
    trimesh.creation.cylinder(radius=33, height=18, sections=48).export(pkg / "meshes" / "tyre.stl")
    (pkg / "package.xml").write_text(PACKAGE_XML, encoding="utf-8")
    (pkg / "LICENSE").write_text("BSD 3-Clause License\n", encoding="utf-8")
    urdf = pkg / "urdf" / "car.urdf"
    urdf.write_text(CAR.format(uri=uri, inertial=inertial), encoding="utf-8")
    (tmp_path / "proj" / ".git").mkdir(parents=True)
    return urdf


UNITS_WARNING = ("../ws/tyre_pkg/urdf/car.urdf:8: link 'wheel' visual mesh tyre.stl is 66 m across: millimetres "
                 "(its mass of 0.2 kg then gives 3257 kg/m^3; no other unit gives a plausible size and density); "
                 "the recipe sets units: mm")
TENSOR_WARNING = ("../ws/tyre_pkg/urdf/car.urdf:7: link 'wheel': the original's principal moments 0.5, 0.5, 2 "
                  "violate the triangle inequality; repaired, its equivalent inertia box (7.07 x 7.07 x 0.000245 m) "
                  "is 124x larger than the geometry's at uniform density (0.0571 x 0.0571 x 0.018 m), along x, y, "
                  "z: recomputed from its visual geometry, keeping the mass (policy: recompute; the given com and "
                  "inertia are unused)")


def test_the_tyre_gets_units_and_a_recomputed_inertial_and_its_mesh_is_copied(tmp_path, monkeypatch):
    urdf = workspace(tmp_path)
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)  # the read rules as a user has them (conftest widens them)
    monkeypatch.chdir(tmp_path / "proj")
    result = import_file(urdf, "car.yaml")
    assert [w for w in result.warnings if "car.urdf" in w] == [UNITS_WARNING, TENSOR_WARNING]
    text = Path("car.yaml").read_text(encoding="utf-8")
    said = ("visual mesh tyre.stl is 66 m across as the original scales it: millimetres (its mass of 0.2 kg then "
            "gives 3257 kg/m^3; no other unit gives a plausible size and density); "
            + TENSOR_WARNING.split("link 'wheel': ")[1])
    assert result.repairs == {"wheel": said}
    above = text.split("\n  wheel:")[0].split("\n  base:")[1]  # the comment above the wheel
    assert " ".join(line.strip()[2:] for line in above.splitlines() if line.startswith("  # ")) == said
    wheel = yaml.safe_load(text)["links"]["wheel"]
    assert wheel == {"visual": {"mesh": "meshes/tyre_pkg/meshes/tyre.stl", "units": "mm"}, "collision": "none",
                     "inertial": {"mass": 0.2, "inertia": {"ixx": 0.5, "iyy": 0.5, "izz": 2}, "policy": "recompute"}}
    copied = tmp_path / "proj" / "meshes" / "tyre_pkg"
    assert sorted(p.relative_to(copied).as_posix() for p in copied.rglob("*") if p.is_file()) == [
        "LICENSE", "meshes/tyre.stl"]
    assert (copied / "meshes" / "tyre.stl").read_bytes() == (tmp_path / "ws/tyre_pkg/meshes/tyre.stl").read_bytes()
    assert sorted(result.copied) == [str(copied / "LICENSE"), str(copied / "meshes" / "tyre.stl")]


def test_an_ambiguous_unit_is_offered_not_chosen(tmp_path, monkeypatch):
    """Without a mass on the mesh, millimetres, centimetres and inches all make a plausible part:
    the import offers millimetres and leaves the scale as the URDF has it."""
    urdf = workspace(tmp_path, inertial="")
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)
    monkeypatch.chdir(tmp_path / "proj")
    result = import_file(urdf, "car.yaml")
    assert [w for w in result.warnings if "tyre.stl" in w] == [
        "../ws/tyre_pkg/urdf/car.urdf:8: link 'wheel' visual mesh tyre.stl is 66 m across: millimetres? "
        "add scale=\"0.001 0.001 0.001\" (or units: mm in the recipe)"]
    assert yaml.safe_load(Path("car.yaml").read_text(encoding="utf-8"))["links"]["wheel"]["visual"] == {
        "mesh": "meshes/tyre_pkg/meshes/tyre.stl"}


def test_a_package_uri_leaving_its_package_is_refused_with_its_line(tmp_path, monkeypatch):
    urdf = workspace(tmp_path, uri="package://tyre_pkg/../../Y/x.stl")
    (tmp_path / "Y").mkdir()
    (tmp_path / "Y" / "x.stl").write_bytes((tmp_path / "ws/tyre_pkg/meshes/tyre.stl").read_bytes())
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)
    monkeypatch.chdir(tmp_path)
    for copy in (True, False):  # --copy-meshes, and the copy of a mesh outside the project
        with pytest.raises(RobotkitError) as info:
            import_file(urdf, "proj/car.yaml", copy_meshes=copy)
        assert [str(p) for p in info.value.problems] == [
            "ws/tyre_pkg/urdf/car.urdf:8: link 'wheel' visual mesh: package://tyre_pkg/../../Y/x.stl leaves "
            "package 'tyre_pkg'"]
        assert not (tmp_path / "proj" / "car.yaml").exists() and not (tmp_path / "proj" / "meshes").exists()


def test_a_mesh_inside_the_project_is_referenced_where_it_is(tmp_path, monkeypatch):
    urdf = workspace(tmp_path)
    (tmp_path / "ws" / ".git").mkdir()  # the workspace is the project
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)
    result = import_file(urdf, tmp_path / "ws" / "car.yaml")
    assert result.copied == []
    wheel = yaml.safe_load((tmp_path / "ws" / "car.yaml").read_text(encoding="utf-8"))["links"]["wheel"]
    assert wheel["visual"] == {"mesh": "tyre_pkg/meshes/tyre.stl", "units": "mm"}


@pytest.mark.slow
def test_the_printed_build_command_builds_a_robot_that_passes_check(tmp_path, monkeypatch):
    """The acceptance: import from outside the project, run the last line it printed, check the build."""
    workspace(tmp_path)
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)
    proj = tmp_path / "proj"
    imported = run_cli("import", "../ws/tyre_pkg/urdf/car.urdf", "-o", "car.yaml", cwd=proj)
    assert imported.returncode == 0, imported.stderr
    assert imported.stdout.splitlines() == [
        "copied 2 files to meshes/ (meshes outside the project, which its build does not read, with their "
        "packages' licences)",
        "wrote car.yaml (robot car); build it with:",
        "robotkit build car.yaml"]
    assert UNITS_WARNING in imported.stderr and TENSOR_WARNING in imported.stderr
    command = shlex.split(imported.stdout.splitlines()[-1])
    assert command[:2] == ["robotkit", "build"]
    built = run_cli(*command[1:], cwd=proj)
    assert built.returncode == 0, built.stderr
    checked = run_cli("check", "build/car", cwd=proj)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    assert "error" not in checked.stdout.replace("0 errors", ""), checked.stdout


def test_a_physical_tensor_that_does_not_fit_is_recomputed(tmp_path, monkeypatch):
    """A tensor some real body has but not this part (check's inertia-box error) is recomputed from
    the geometry by default, keeping the mass, stated above the link and in a warning."""
    urdf = workspace(tmp_path, inertial=TYRE.replace('izz="2"', 'izz="0.9"'))
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)
    monkeypatch.chdir(tmp_path / "proj")
    result = import_file(urdf, "car.yaml")
    why = ("the given inertial does not fit its geometry: its equivalent inertia box (5.2 x 5.2 x 1.73 m) is 96.2x "
           "larger than the geometry's at uniform density (0.0571 x 0.0571 x 0.018 m), along x, y, z: recomputed "
           "from its visual geometry, keeping the mass (policy: recompute; the given com and inertia are unused)")
    assert [w for w in result.warnings if "car.urdf" in w] == [
        UNITS_WARNING, f"../ws/tyre_pkg/urdf/car.urdf:7: link 'wheel': {why}"]
    assert result.repairs["wheel"].endswith(why)
    assert yaml.safe_load(Path("car.yaml").read_text(encoding="utf-8"))["links"]["wheel"]["inertial"] == {
        "mass": 0.2, "inertia": {"ixx": 0.5, "iyy": 0.5, "izz": 0.9}, "policy": "recompute"}


def test_keep_keeps_a_physical_tensor_that_does_not_fit_with_a_warning(tmp_path, monkeypatch):
    """``--inertia-policy keep``: the vendor's tensor as given, with check's verdict and its fix."""
    urdf = workspace(tmp_path, inertial=TYRE.replace('izz="2"', 'izz="0.9"'))
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)
    monkeypatch.chdir(tmp_path / "proj")
    result = import_file(urdf, "car.yaml", inertia_policy="keep")
    assert [w for w in result.warnings if "car.urdf" in w] == [UNITS_WARNING, (
        "../ws/tyre_pkg/urdf/car.urdf:7: link 'wheel': the given inertial does not fit its geometry: its equivalent "
        "inertia box (5.2 x 5.2 x 1.73 m) is 96.2x larger than the geometry's at uniform density (0.0571 x 0.0571 x "
        "0.018 m), along x, y, z; recompute it from the geometry (inertial: {mass: 0.2} on the link in the recipe, "
        "or import with --recompute-inertials)")]
    assert yaml.safe_load(Path("car.yaml").read_text(encoding="utf-8"))["links"]["wheel"]["inertial"] == {
        "mass": 0.2, "inertia": {"ixx": 0.5, "iyy": 0.5, "izz": 0.9}}


def test_an_explicit_repair_stays_the_repair(tmp_path, monkeypatch):
    """``--inertia-policy repair`` asks for the smallest change, fit or not."""
    urdf = workspace(tmp_path)
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)
    monkeypatch.chdir(tmp_path / "proj")
    result = import_file(urdf, "car.yaml", inertia_policy="repair")
    assert result.repairs["wheel"].endswith(
        "the original's principal moments 0.5, 0.5, 2 violate the triangle inequality: repaired (principal moments "
        "0.5, 0.5, 2 moved to 0.833333, 0.833333, 1.66667 to meet the triangle inequality)")
    assert "policy" not in yaml.safe_load(Path("car.yaml").read_text(encoding="utf-8"))["links"]["wheel"]["inertial"]
