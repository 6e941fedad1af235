"""The mesh pipeline inside builds: collision strategies per link and per format, processed
visuals, the cache, the fidelity report, and bad meshes."""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import trimesh

from conftest import RECIPES, run_cli, tree_bytes, write_recipe
from robotkit.pipeline.runner import build
from validators import check_urdf, ign_sdf_check, mujoco


def report(out: Path, robot: str) -> dict:
    return json.loads((out / robot / "report.json").read_text())


@pytest.mark.slow
def test_ur5_collision_pieces_are_closed_convex_and_cached(tmp_path):
    out1, out2 = tmp_path / "cold", tmp_path / "warm"
    cache = tmp_path / "cache"
    import os
    import subprocess
    import sys

    env = {**os.environ, "ROBOTKIT_CACHE": str(cache)}
    cmd = [sys.executable, "-m", "robotkit", "build", str(RECIPES / "ur5.yaml"), "-j", "2", "--out"]
    proc = subprocess.run(cmd + [str(out1)], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr
    pieces = sorted((out1 / "ur5" / "meshes" / "collision").glob("*.obj"))  # OBJ: Drake's convex meshes
    assert len(pieces) >= 7
    for path in pieces:
        m = trimesh.load(path)
        assert m.is_volume, path.name
        assert m.convex_hull.volume == pytest.approx(m.volume, rel=1e-6), path.name  # convex
        assert len(m.vertices) <= 64, path.name
    entries = sorted(p.name for p in cache.rglob("*.json"))
    stamps = {p: p.stat().st_mtime_ns for p in cache.rglob("*") if p.is_file()}
    proc = subprocess.run(cmd + [str(out2)], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr
    # everything came from the cache: no entry added or rewritten, the same bytes out
    assert sorted(p.name for p in cache.rglob("*.json")) == entries
    assert {p: p.stat().st_mtime_ns for p in cache.rglob("*") if p.is_file() and not p.name.endswith(".lock")} \
        == {p: t for p, t in stamps.items() if not p.name.endswith(".lock")}
    assert tree_bytes(out2) == tree_bytes(out1)
    data = report(out1, "ur5")
    assert len(data["collision"]) == 7
    fids = [entry["fidelity"] for entry in data["collision"].values()]
    for f in fids:
        assert f["pieces"] >= 1 and 1 <= f["volume_ratio"]
    # the recipe's fidelity target (benchmarks/bench_coacd.py): no worse than the slower settings
    # before it (threshold 0.08, 40 iterations, CoACD's voxel remeshing of the overlapping bodies)
    assert max(f["distance_relative"] for f in fids) <= 0.1962
    assert max(f["volume_ratio"] for f in fids) <= 1.1997
    assert sum(f["volume_ratio"] for f in fids) / 7 <= 1.0880
    assert sum(f["distance"]["mean"] for f in fids) / 7 <= 3.38e-3
    check_urdf(out1 / "ur5" / "urdf" / "ur5.urdf")
    ign_sdf_check(out1 / "ur5" / "model.sdf")
    mujoco().MjModel.from_xml_path(str(out1 / "ur5" / "mjcf" / "scene.xml"))


@pytest.mark.slow
def test_fidelity_numbers_on_known_shapes(tmp_path):
    sphere = trimesh.creation.icosphere(subdivisions=5, radius=0.1)
    cube = trimesh.creation.box([0.1, 0.2, 0.3])
    recipe = write_recipe(tmp_path, """
        robot: fid
        links:
          a: {visual: {mesh: cube.stl}, collision: {strategy: hull}}
          b: {visual: {mesh: sphere.stl}, collision: {strategy: box}}
        joints:
          j: {type: fixed, parent: a, child: b, origin: {xyz: [1, 0, 0]}}
        """, meshes={"cube.stl": cube, "sphere.stl": sphere})
    build([recipe], tmp_path / "out")
    by_source = {Path(e["source"]).name: e for e in report(tmp_path / "out", "fid")["collision"].values()}
    hull = by_source["cube.stl"]["fidelity"]
    assert hull["volume_ratio"] == pytest.approx(1.0, abs=1e-6)
    assert hull["distance"]["max"] < 1e-6
    box = by_source["sphere.stl"]["fidelity"]
    stored = trimesh.load(tmp_path / "sphere.stl")
    assert box["volume_ratio"] == pytest.approx(0.2 ** 3 / stored.volume, rel=1e-3)
    assert box["volume_ratio"] == pytest.approx(6 / math.pi, rel=2e-3)  # cube around a sphere


@pytest.mark.slow
def test_collision_strategy_per_format(tmp_path):
    mesh = trimesh.creation.cylinder(radius=0.05, height=0.3, sections=64)
    recipe = write_recipe(tmp_path, """
        robot: perfmt
        links:
          a:
            visual: {mesh: rod.stl}
            collision: {strategy: mesh, mjcf: {strategy: capsule}}
        """, meshes={"rod.stl": mesh})
    build([recipe], tmp_path / "out")
    robot = tmp_path / "out" / "perfmt"
    urdf = ET.parse(robot / "urdf" / "perfmt.urdf").getroot()
    assert urdf.find("link/collision/geometry/mesh").get("filename") == "package://perfmt/meshes/collision/rod_mesh.obj"
    sdf = ET.parse(robot / "model.sdf").getroot()
    assert sdf.find(".//collision/geometry/mesh/uri").text == "model://perfmt/meshes/collision/rod_mesh.obj"
    mj = mujoco()
    model = mj.MjModel.from_xml_path(str(robot / "mjcf" / "scene.xml"))
    geom = mj.mj_name2id(model, mj.mjtObj.mjOBJ_GEOM, "a_collision_0")
    assert model.geom_type[geom] == mj.mjtGeom.mjGEOM_CAPSULE
    check_urdf(robot / "urdf" / "perfmt.urdf")
    ign_sdf_check(robot / "model.sdf")


@pytest.mark.slow
def test_decimated_visual_is_written_in_metres(tmp_path):
    mesh = trimesh.creation.icosphere(subdivisions=5, radius=50.0)  # millimetres, 20k faces
    recipe = write_recipe(tmp_path, """
        robot: dec
        links:
          a: {visual: {mesh: ball.stl, units: mm, decimate: {faces: 1000}}}
        """, meshes={"ball.stl": mesh})
    build([recipe], tmp_path / "out")
    out = trimesh.load(tmp_path / "out" / "dec" / "meshes" / "visual" / "ball.stl")
    assert len(out.faces) <= 1000
    assert out.extents.max() == pytest.approx(0.1, rel=1e-2)  # metres now
    urdf = ET.parse(tmp_path / "out" / "dec" / "urdf" / "dec.urdf").getroot()
    assert urdf.find("link/visual/geometry/mesh").get("scale") is None
    # the inertial still comes from the full-resolution source
    mass = float(urdf.find("link/inertial/mass").get("value"))
    assert mass == pytest.approx(1000 * trimesh.load(tmp_path / "ball.stl").volume * 1e-9, rel=1e-12)


BAD = {
    "decimation target above the face count": (
        lambda: trimesh.creation.box([0.1, 0.1, 0.1]),
        "a: {visual: {mesh: m.stl, decimate: {faces: 500}}}",
        "robot.yaml:3: links.a.visual.mesh: decimation target 500 faces is above the mesh's 12 faces ('m.stl')"),
    "NaN vertices": (
        lambda: trimesh.Trimesh(np.array([[0, 0, 0], [1, 0, 0], [0, float("nan"), 0]]), [[0, 1, 2]], process=False),
        "a: {visual: {mesh: m.stl}}",
        "robot.yaml:3: links.a.visual.mesh: mesh file 'm.stl' has vertices that are not finite numbers (NaN or inf)"),
    "zero volume": (
        lambda: trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2]]),
        "a: {visual: {mesh: m.stl}, inertial: {open_mesh: hull}}",
        None),
}


@pytest.mark.slow
@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_meshes(tmp_path, case):
    make, link, expected = BAD[case]
    make().export(tmp_path / "m.stl")
    (tmp_path / "robot.yaml").write_text(f"robot: bad\nlinks:\n  {link}\n")
    proc = run_cli("build", "robot.yaml", "--out", "out", cwd=tmp_path)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr
    if expected:
        assert lines == [expected]
    else:
        assert lines[0].startswith("robot.yaml:3: links.a.visual.mesh: ")
