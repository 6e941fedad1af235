"""The turret_bot example end to end: reference inertials, check_urdf, golden files,
determinism, and incremental rebuilds asserted through doit's own record."""

from __future__ import annotations

import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import trimesh

from conftest import GOLDEN, assert_golden, RECIPES, run_cli, tree_bytes
from robotkit.pipeline.runner import build
from validators import check_urdf

# REFERENCE_NUMBERS.md, "trimesh check" column (printed to 6 decimals): mass, com, (ixx, iyy, izz)
REFERENCE = {
    "base": (16.0000, (0, 0.5, 0.029844), (1.376466, 0.317266, 1.607467)),
    "slider": (9.80763, (0, 0.05, 0.164697), (0.152061, 0.229388, 0.092386)),
    "rotor": (2.11418, (0.130661, 0, 0.03), (0.002149, 0.020742, 0.022010)),
}


def urdf_inertials(path: Path) -> dict:
    out = {}
    for link in ET.parse(path).getroot().iter("link"):
        inertial = link.find("inertial")
        i = inertial.find("inertia").attrib
        out[link.get("name")] = (
            float(inertial.find("mass").get("value")),
            np.array([float(v) for v in inertial.find("origin").get("xyz").split()]),
            np.array([[float(i["ixx"]), float(i["ixy"]), float(i["ixz"])],
                      [float(i["ixy"]), float(i["iyy"]), float(i["iyz"])],
                      [float(i["ixz"]), float(i["iyz"]), float(i["izz"])]]),
        )
    return out


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("turret")
    proc = run_cli("build", RECIPES / "turret_bot.yaml", "--out", out)
    assert proc.returncode == 0, proc.stderr
    return out


@pytest.mark.slow
def test_writes_the_promised_files(built):
    root = built / "turret_bot"
    for rel in ("urdf/turret_bot.urdf", "urdf/turret_bot.urdf.xacro", "model.sdf", "mjcf/turret_bot.xml", "mjcf/scene.xml", "report.json",
                "model.config", "package.xml", "meshes/visual/base.stl",
                "meshes/visual/slider.stl", "meshes/visual/rotor.stl"):
        assert (root / rel).is_file(), rel


def test_urdf_passes_check_urdf(built):
    out = check_urdf(built / "turret_bot" / "urdf" / "turret_bot.urdf")
    assert "robot name is: turret_bot" in out
    assert "child(1):  slider" in out and "child(1):  rotor" in out


def test_inertials_match_reference_numbers(built, assets):
    got = urdf_inertials(built / "turret_bot" / "urdf" / "turret_bot.urdf")
    for link, (mass, com, diag) in REFERENCE.items():
        m, c, I = got[link]
        # independent computation: trimesh's own mass properties of the asset mesh at 1250 kg/m^3
        mesh = trimesh.load(assets / "turret_bot" / "meshes" / f"{link}.stl")
        mesh.density = 1250.0
        assert m == pytest.approx(mesh.mass, rel=1e-6)
        np.testing.assert_allclose(c, mesh.center_mass, rtol=1e-6, atol=1e-12)
        np.testing.assert_allclose(I, mesh.moment_inertia, rtol=1e-6, atol=1e-9 * np.abs(I).max())
        # the table in REFERENCE_NUMBERS.md, to the digits it prints
        assert m == pytest.approx(mass, abs=5e-5 if link == "base" else 5e-6)
        np.testing.assert_allclose(c, com, atol=5e-7)
        np.testing.assert_allclose(np.diag(I), diag, atol=5e-7)
        assert np.abs(I - np.diag(np.diag(I))).max() < 1e-9  # symmetric parts: no products of inertia


def test_base_keeps_its_centre_of_mass_height(built):
    # the shipped URDF drops z = 0.029844 (REFERENCE_NUMBERS.md)
    _, com, _ = urdf_inertials(built / "turret_bot" / "urdf" / "turret_bot.urdf")["base"]
    assert com[2] == pytest.approx(0.029844, abs=5e-7)


def test_joints_match_the_original_urdf(built, assets):
    ours = ET.parse(built / "turret_bot" / "urdf" / "turret_bot.urdf").getroot()
    theirs = ET.parse(assets / "turret_bot" / "urdf" / "turret_bot.urdf").getroot()
    for name in ("j1", "j2"):
        a = ours.find(f"joint[@name='{name}']")
        b = theirs.find(f"joint[@name='{name}']")
        assert a.get("type") == b.get("type")
        for tag in ("parent", "child"):
            assert a.find(tag).get("link") == b.find(tag).get("link")
        for tag, attrs in (("axis", ["xyz"]), ("origin", ["xyz", "rpy"]),
                           ("limit", ["lower", "upper", "effort", "velocity"]), ("dynamics", ["damping", "friction"])):
            for attr in attrs:
                va = [float(v) for v in a.find(tag).get(attr).split()]
                vb = [float(v) for v in b.find(tag).get(attr).split()]
                assert va == vb, (name, tag, attr)


@pytest.mark.parametrize("rel", ["urdf/turret_bot.urdf", "model.config", "package.xml"])
def test_golden_files(built, rel):
    assert_golden(built / "turret_bot" / rel, GOLDEN / "turret_bot" / rel)


@pytest.mark.slow
def test_two_builds_are_byte_identical(built, tmp_path):
    proc = run_cli("build", RECIPES / "turret_bot.yaml", "--out", tmp_path, "-j", "2")
    assert proc.returncode == 0, proc.stderr
    assert tree_bytes(tmp_path) == tree_bytes(built)


def test_second_build_runs_nothing_and_rewrites_no_file(built):
    before = {p: p.stat().st_mtime_ns for p in (built / "turret_bot").rglob("*") if p.is_file()}
    proc = run_cli("build", RECIPES / "turret_bot.yaml", "--out", built)
    assert proc.returncode == 0, proc.stderr
    assert "up to date" in proc.stdout
    after = {p: p.stat().st_mtime_ns for p in (built / "turret_bot").rglob("*") if p.is_file()}
    assert after == before


# ------------------------------------------------------------ incremental behaviour


@pytest.fixture
def project(tmp_path) -> Path:
    """A copy of the turret_bot recipe and meshes that the test may edit."""
    shutil.copytree(RECIPES / "meshes" / "turret_bot", tmp_path / "meshes" / "turret_bot")
    shutil.copyfile(RECIPES / "turret_bot.yaml", tmp_path / "turret_bot.yaml")
    return tmp_path


def test_first_build_runs_every_task_once_then_nothing(project):
    out = project / "build"
    first = build([project / "turret_bot.yaml"], out)
    assert sorted(first.ran) == sorted([
        "turret_bot:mesh:" + k for k in _mesh_keys(first)] + [
        "turret_bot:copy:base.stl", "turret_bot:copy:slider.stl", "turret_bot:copy:rotor.stl",
        # collision geometry as OBJ (Drake's convex meshes), in every format; the base's and the
        # slider's are boxes and a cylinder
        "turret_bot:convert:collision/rotor.obj",
        "turret_bot:inertial:base", "turret_bot:inertial:slider", "turret_bot:inertial:rotor", "turret_bot:drives",
        "turret_bot:urdf", "turret_bot:sdf", "turret_bot:mjcf", "turret_bot:mjcf-scene", "turret_bot:report",
        "turret_bot:model.config", "turret_bot:package.xml", "turret_bot:CMakeLists.txt",
        "turret_bot:controllers", "turret_bot:xacro", "turret_bot:env-hook", "turret_bot:display-launch",
        "turret_bot:gazebo-launch", "turret_bot:rviz", "turret_bot:self-collision", "turret_bot:srdf"])
    second = build([project / "turret_bot.yaml"], out)
    assert second.ran == []
    assert sorted(second.uptodate) == sorted(first.ran)


def _mesh_keys(result):
    return sorted(n.split(":", 2)[2] for n in result.ran if n.startswith("turret_bot:mesh:"))


def test_editing_one_links_density_reruns_that_inertial_and_the_urdf(project):
    recipe = project / "turret_bot.yaml"
    out = project / "build"
    build([recipe], out)
    text = recipe.read_text()
    recipe.write_text(text.replace("    visual: {mesh: meshes/turret_bot/rotor.stl, material: blue}",
                                   "    visual: {mesh: meshes/turret_bot/rotor.stl, material: blue}\n"
                                   "    inertial: {density: 2700}"))
    again = build([recipe], out)
    # the outputs that contain inertials rerun, and the scene (its floor makes room for a robot fixed to
    # the world below z = 0: it reads the robot); model.config, package.xml and the meshes do not, and
    # the drives' checks (turret_bot's gains are given: controllers.yaml does not rerun)
    assert sorted(again.ran) == ["turret_bot:drives", "turret_bot:inertial:rotor", "turret_bot:mjcf",
                                 "turret_bot:mjcf-scene", "turret_bot:report", "turret_bot:sdf", "turret_bot:urdf",
                                 "turret_bot:xacro"]
    mass = urdf_inertials(out / "turret_bot" / "urdf" / "turret_bot.urdf")["rotor"][0]
    assert mass == pytest.approx(2.1141772435614743 / 1250 * 2700, rel=1e-12)


def test_changing_one_mesh_file_reruns_only_what_depends_on_it(project):
    recipe = project / "turret_bot.yaml"
    out = project / "build"
    build([recipe], out)
    mesh = trimesh.load(project / "meshes" / "turret_bot" / "slider.stl")
    mesh.apply_scale(1.01)
    mesh.export(project / "meshes" / "turret_bot" / "slider.stl")
    again = build([recipe], out)
    assert sorted(again.ran) == sorted([
        next(n for n in again.uptodate + again.ran if n.startswith("turret_bot:mesh:slider")),
        "turret_bot:copy:slider.stl", "turret_bot:inertial:slider",
        # the self-collision matrix is sampled again, and is the same (the slider collides as its
        # boxes and cylinder): the SRDF does not rerun
        "turret_bot:drives", "turret_bot:urdf", "turret_bot:sdf", "turret_bot:self-collision",
        "turret_bot:mjcf", "turret_bot:report", "turret_bot:xacro", "turret_bot:rviz",  # rviz: the robot's extent
        "turret_bot:mjcf-scene"])  # the scene: the robot's lowest point (a floor below a world-rooted robot)


@pytest.mark.slow
def test_doit_in_a_project_root_runs_the_same_tasks(tmp_path):
    """`doit` in the repository root builds recipes/ with the tasks `robotkit build` runs."""
    import subprocess
    import sys

    repo = Path(__file__).resolve().parents[2]
    shutil.copytree(repo / "recipes", tmp_path / "recipes")
    shutil.copyfile(repo / "dodo.py", tmp_path / "dodo.py")
    proc = subprocess.run([sys.executable, "-m", "doit"], cwd=tmp_path, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert ".  turret_bot:urdf" in proc.stdout
    # the CLI sees the same state: nothing left to do
    proc = run_cli("build", *sorted((tmp_path / "recipes").glob("*.yaml")), "--out", tmp_path / "build")
    assert proc.returncode == 0 and "up to date" in proc.stdout, proc.stdout + proc.stderr
