"""Recipe features end to end: units, recentering, primitives, inertial modes, defaults,
includes, the open-mesh policy, and the second example."""

from __future__ import annotations

import json

import math
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import trimesh

from conftest import RECIPES, write_recipe
from robotkit.pipeline.runner import build
from robotkit.model.massprops import box_props, cylinder_props
from robotkit.geometry import rpy_matrix
from tests.examples.test_turret_bot import urdf_inertials
from validators import check_urdf


def stored(mesh):
    """The mesh as an STL file stores it (float32 vertices): the exact reference for a build."""
    import io

    return trimesh.load(io.BytesIO(mesh.export(file_type="stl")), file_type="stl")


def built_urdf(recipe: Path, out: Path) -> Path:
    result = build([recipe], out)
    assert not result.errors, result.errors
    name = recipe.read_text().split("robot:", 1)[1].split()[0]
    urdf = out / name / "urdf" / f"{name}.urdf"
    check_urdf(urdf)
    return urdf


def test_same_mesh_in_cm_and_m_gives_the_same_si_inertial(tmp_path):
    box_m = trimesh.creation.box([0.1, 0.2, 0.3])
    box_m.apply_translation([0.05, 0.0, 0.1])
    box_cm = box_m.copy()
    box_cm.apply_scale(100.0)
    recipe = write_recipe(tmp_path, """
        robot: r
        density: 500
        links:
          a: {visual: {mesh: m.stl}}
          b: {visual: {mesh: cm.stl, units: cm}}
          c: {visual: {mesh: cm.stl, scale: 0.01}}
        joints:
          j1: {type: fixed, parent: a, child: b}
          j2: {type: fixed, parent: a, child: c}
        """, meshes={"m.stl": box_m, "cm.stl": box_cm})
    got = urdf_inertials(built_urdf(recipe, tmp_path / "out"))
    mass, com, I = got["a"]
    ref = stored(box_m)
    assert mass == pytest.approx(500 * ref.volume, rel=1e-12)
    np.testing.assert_allclose(com, ref.center_mass, rtol=1e-12)
    np.testing.assert_allclose(I, 500 * ref.moment_inertia, rtol=1e-10, atol=1e-15)
    ref_cm = stored(box_cm)
    for other in ("b", "c"):
        m2, c2, I2 = got[other]
        # the cm file converted exactly: the s^3 and s^5 rules hold to float64 precision
        assert m2 == pytest.approx(500 * ref_cm.volume * 1e-6, rel=1e-12)
        np.testing.assert_allclose(I2, 500 * ref_cm.moment_inertia * 1e-10, rtol=1e-10, atol=1e-15)
        np.testing.assert_allclose(c2, ref_cm.center_mass * 0.01, rtol=1e-12)
        # and agrees with the metre file to the float32 precision both files are stored at
        assert m2 == pytest.approx(mass, rel=1e-6)
        np.testing.assert_allclose(I2, I, rtol=1e-6)


def test_primitives_get_analytic_inertials(tmp_path):
    recipe = write_recipe(tmp_path, """
        robot: prims
        density: 1000
        links:
          box: {visual: {box: {size: [0.1, 0.2, 0.3]}, origin: {xyz: [0, 0, 0.15]}}}
          rod:
            visual:
              cylinder: {radius: 0.02, length: 0.5}
              origin: {xyz: [0.25, 0, 0], rpy: [0, 1.5707963267948966, 0]}
          ball: {visual: {sphere: {radius: 0.05}}, inertial: {mass: 2}}
        joints:
          j1: {type: fixed, parent: box, child: rod}
          j2: {type: fixed, parent: rod, child: ball}
        """)
    got = urdf_inertials(built_urdf(recipe, tmp_path / "out"))
    m, c, I = got["box"]
    assert m == pytest.approx(6.0, rel=1e-14)
    np.testing.assert_allclose(c, [0, 0, 0.15])
    np.testing.assert_allclose(I, 1000 * box_props([0.1, 0.2, 0.3]).inertia, rtol=1e-14)
    m, c, I = got["rod"]
    cyl = cylinder_props(0.02, 0.5)
    assert m == pytest.approx(1000 * cyl.volume, rel=1e-14)
    np.testing.assert_allclose(c, [0.25, 0, 0])
    R = rpy_matrix((0, math.pi / 2, 0))
    np.testing.assert_allclose(I, R @ (1000 * cyl.inertia) @ R.T, rtol=1e-12, atol=1e-18)
    assert I[0, 0] == pytest.approx(1000 * cyl.inertia[2, 2], rel=1e-12)  # rod axis is now x
    m, c, I = got["ball"]
    assert m == 2.0
    np.testing.assert_allclose(I, np.eye(3) * 0.4 * 2 * 0.05 ** 2, rtol=1e-14)


def test_rotated_visual_origin_rotates_the_tensor(tmp_path):
    mesh = trimesh.creation.box([0.1, 0.3, 0.5])
    mesh.apply_translation([0.02, 0.03, 0.04])
    rpy = (0.4, -0.7, 1.3)
    recipe = write_recipe(tmp_path, f"""
        robot: rot
        links:
          a: {{visual: {{mesh: part.stl, origin: {{xyz: [1, 2, 3], rpy: [{rpy[0]}, {rpy[1]}, {rpy[2]}]}}}}}}
        """, meshes={"part.stl": mesh})
    mass, com, I = urdf_inertials(built_urdf(recipe, tmp_path / "out"))["a"]
    R = rpy_matrix(rpy)
    ref = stored(mesh)
    np.testing.assert_allclose(com, R @ ref.center_mass + [1, 2, 3], rtol=1e-13)
    np.testing.assert_allclose(I, R @ (1000 * ref.moment_inertia) @ R.T, rtol=1e-10, atol=1e-14)
    assert abs(I[0, 1]) > 1e-3


def test_recenter_moves_the_mesh_and_its_centre_of_mass(tmp_path):
    mesh = trimesh.creation.box([0.2, 0.2, 0.2])
    mesh.apply_translation([0.5, 0.5, 0.5])
    recipe = write_recipe(tmp_path, """
        robot: rc
        links:
          a: {visual: {mesh: off.stl, recenter: bbox}}
          b: {visual: {mesh: off.stl, recenter: com, origin: {xyz: [0, 0, 1]}}}
        joints:
          j: {type: fixed, parent: a, child: b}
        """, meshes={"off.stl": mesh})
    urdf = built_urdf(recipe, tmp_path / "out")
    got = urdf_inertials(urdf)
    np.testing.assert_allclose(got["a"][1], 0, atol=1e-15)  # box: bbox centre = centre of mass
    np.testing.assert_allclose(got["b"][1], [0, 0, 1], atol=1e-15)
    visual = ET.parse(urdf).getroot().find("link[@name='a']/visual/origin")
    ref = stored(mesh)
    # written to 15 significant digits (robotkit.emit.env.SIGNIFICANT_DIGITS)
    np.testing.assert_allclose([float(v) for v in visual.get("xyz").split()], -ref.bounds.mean(axis=0), rtol=5e-15)


def test_explicit_inertial_is_written_as_given(tmp_path):
    recipe = write_recipe(tmp_path, """
        robot: ex
        links:
          a:
            visual: {box: {size: [1, 1, 1]}}
            inertial:
              mass: 3.5
              com: [0.1, 0.2, 0.3]
              inertia: {ixx: 0.5, iyy: 0.6, izz: 0.7, ixy: 0.01, ixz: -0.02, iyz: 0.03}
        """)
    mass, com, I = urdf_inertials(built_urdf(recipe, tmp_path / "out"))["a"]
    assert mass == 3.5
    assert list(com) == [0.1, 0.2, 0.3]
    assert I.tolist() == [[0.5, 0.01, -0.02], [0.01, 0.6, 0.03], [-0.02, 0.03, 0.7]]


def test_defaults_and_includes(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "arm.yaml").write_text(
        "materials:\n  blue: {rgba: [0, 0, 1, 1]}\n"
        "links:\n  arm: {visual: {box: {size: [0.1, 0.1, 0.5]}, material: blue}}\n"
        "joints:\n  shoulder: {type: revolute, parent: base, child: arm, limit: {lower: -1, upper: 1}}\n")
    recipe = write_recipe(tmp_path, """
        robot: inc
        include: [parts/arm.yaml]
        defaults:
          joint:
            limit: {effort: 10, velocity: 2}
            dynamics: {damping: 0.5}
        links:
          base: {visual: {box: {size: [0.3, 0.3, 0.1]}}}
        """)
    root = ET.parse(built_urdf(recipe, tmp_path / "out")).getroot()
    joint = root.find("joint[@name='shoulder']")
    assert joint.find("limit").attrib == {"lower": "-1", "upper": "1", "effort": "10", "velocity": "2"}
    assert joint.find("dynamics").attrib == {"damping": "0.5", "friction": "0"}
    assert root.find("material[@name='blue']/color").get("rgba") == "0 0 1 1"


def mesh_warnings(result) -> list[str]:
    """The build's warnings but the ROS package's (these recipes name no maintainer)."""
    return [w for w in result.warnings if ": ROS package: " not in w]


def test_open_mesh_with_hull_policy_uses_the_hull_and_says_so_in_report_json(tmp_path, monkeypatch):
    """open_mesh: hull is the recipe's choice (the error without it offers it): no warning, the
    fact and its cost in report.json's meshes."""
    monkeypatch.chdir(tmp_path)
    tube = trimesh.creation.cylinder(radius=0.05, height=0.1, sections=32)
    box = trimesh.Trimesh(tube.vertices, tube.faces[tube.face_normals[:, 2] < 0.99])  # a 32-edge hole
    recipe = write_recipe(tmp_path, """
        robot: op
        open_mesh: hull
        links:
          a: {visual: {mesh: open.stl}}
        """, meshes={"open.stl": box})
    result = build([recipe], tmp_path / "out")
    assert mesh_warnings(result) == []
    meshes = json.loads((tmp_path / "out" / "op" / "report.json").read_text())["meshes"]
    assert [(m["used"], m["repairs"]) for m in meshes.values()] == [("hull", [
        "not a closed volume (32 open edges): mass properties from its convex hull (open_mesh: hull), "
        "which overestimates the volume"])]
    mass, _, _ = urdf_inertials(tmp_path / "out" / "op" / "urdf" / "op.urdf")["a"]
    assert mass == pytest.approx(1000 * stored(box).convex_hull.volume, rel=1e-9)


def test_safe_repairs_fix_duplicate_faces_and_inverted_winding(tmp_path):
    box = trimesh.creation.box([0.1, 0.2, 0.3])
    faces = np.vstack([box.faces, box.faces[:3]])  # duplicates
    faces[:, [1, 2]] = faces[:, [2, 1]]  # inside out
    recipe = write_recipe(tmp_path, """
        robot: rep
        links:
          a: {visual: {mesh: bad.stl}}
        """, meshes={"bad.stl": trimesh.Trimesh(box.vertices, faces, process=False)})
    result = build([recipe], tmp_path / "out")
    assert mesh_warnings(result) == []
    mass, _, I = urdf_inertials(tmp_path / "out" / "rep" / "urdf" / "rep.urdf")["a"]
    ref = stored(box)
    assert mass == pytest.approx(1000 * ref.volume, rel=1e-12)
    np.testing.assert_allclose(I, 1000 * ref.moment_inertia, rtol=1e-10)


def test_names_and_text_cannot_break_the_xml(tmp_path):
    recipe = write_recipe(tmp_path, """
        robot: xml
        metadata: {description: "<b>bold</b> & \\"quoted\\""}
        materials:
          m: {rgba: [1, 1, 1, 1], gazebo: "Gazebo/<Evil>&"}
        links:
          a: {visual: {box: {size: [1, 1, 1]}, material: m}}
        """)
    urdf = built_urdf(recipe, tmp_path / "out")
    root = ET.parse(urdf).getroot()
    assert root.find("gazebo/material").text == "Gazebo/<Evil>&"
    config = ET.parse(tmp_path / "out" / "xml" / "model.config").getroot()
    assert config.find("description").text == '<b>bold</b> & "quoted"'


def test_lidar_mast_example_converts_millimetres_exactly(tmp_path, assets):
    urdf = built_urdf(RECIPES / "lidar_mast.yaml", tmp_path)
    mass, com, I = urdf_inertials(urdf)["lidar"]
    assert mass == pytest.approx(0.125, rel=1e-14)
    mesh = trimesh.load(assets / "turtlebot3_description" / "meshes" / "sensors" / "lds.stl")
    mesh.apply_scale(0.001)
    centre = mesh.bounds.mean(axis=0)
    np.testing.assert_allclose(com, mesh.center_mass - centre, atol=1e-12)
    np.testing.assert_allclose(I, mesh.moment_inertia * 0.125 / mesh.volume, rtol=1e-9, atol=1e-15)
    root = ET.parse(urdf).getroot()
    scale = root.find("link[@name='lidar']/visual/geometry/mesh").get("scale")
    assert scale == "0.001 0.001 0.001"
    joint = root.find("joint[@name='scan_joint']")
    assert joint.get("type") == "continuous"
    assert joint.find("limit").attrib == {"effort": "0.5", "velocity": "31.4"}


def test_reference_docs_are_current():
    """docs/recipe.md and docs/recipe.schema.json are generated from the schema (robotkit schema)."""
    from robotkit.recipe.reference import json_schema, markdown

    docs = Path(__file__).resolve().parents[2] / "docs"
    assert (docs / "recipe.schema.json").read_text() == json_schema(), "run: robotkit schema > docs/recipe.schema.json"
    assert (docs / "recipe.md").read_text() == markdown(), "run: robotkit schema --markdown > docs/recipe.md"
    assert (docs / "part.schema.json").read_text() == json_schema(part=True), \
        "run: robotkit schema --part > docs/part.schema.json"


def test_urdf_extras_are_copied_verbatim(tmp_path):
    recipe = write_recipe(tmp_path, """
        robot: extra
        links: {a: {visual: {box: {size: [1, 1, 1]}}}}
        urdf_extras:
          - <gazebo><plugin name="p" filename="libp.so"><rate>10</rate></plugin></gazebo>
        """)
    urdf = built_urdf(recipe, tmp_path / "out")
    assert '  <gazebo><plugin name="p" filename="libp.so"><rate>10</rate></plugin></gazebo>\n' in urdf.read_text()


def test_urdf_extras_must_be_well_formed(tmp_path):
    from robotkit.errors import RobotkitError

    recipe = write_recipe(tmp_path, """
        robot: extra
        links: {a: {}}
        urdf_extras: ["<gazebo><plugin></gazebo>"]
        """)
    with pytest.raises(RobotkitError) as err:
        build([recipe], tmp_path / "out")
    assert err.value.lines() == [f"{recipe}:3: urdf_extras[0]: not well-formed XML: "
                                 "mismatched tag: line 1, column 18"]


def test_recipe_worlds_are_doit_tasks(tmp_path, assets):
    shutil.copytree(assets / "maps" / "turtlebot3_world", tmp_path / "maps" / "tb3")
    recipe = write_recipe(tmp_path, """
        robot: bot
        links: {base: {visual: {box: {size: [0.2, 0.2, 0.1]}}}}
        worlds:
          tb3_world: {map: maps/tb3/map.yaml, height: 0.5}
        """)
    out = tmp_path / "out"
    first = build([recipe], out)
    assert "world:tb3_world" in first.ran
    for rel in ("model.config", "model.sdf", "meshes/tb3_world.stl", "tb3_world.world", "scene.xml"):
        assert (out / "tb3_world" / rel).is_file(), rel
    assert build([recipe], out).ran == []
    recipe.write_text(recipe.read_text().replace("height: 0.5", "height: 0.6"))
    assert sorted(build([recipe], out).ran) == ["bot:world:tb3_world", "world:tb3_world"]  # + the package's copy
    mesh = trimesh.load(out / "tb3_world" / "meshes" / "tb3_world.stl")
    assert mesh.bounds[1][2] == pytest.approx(0.6)


def test_recipe_world_with_a_missing_map(tmp_path):
    from robotkit.errors import RobotkitError

    recipe = write_recipe(tmp_path, """
        robot: bot
        links: {base: {}}
        worlds:
          w: {map: nowhere.yaml}
        """)
    with pytest.raises(RobotkitError) as err:
        build([recipe], tmp_path / "out")
    assert [str(p).split(": ", 1)[1] for p in err.value.problems] == [
        "worlds.w.map: map file '" + str(tmp_path / "nowhere.yaml") + "' does not exist"]


@pytest.mark.slow
def test_recipe_world_with_the_robot_spawned(tmp_path, assets):
    import os
    import subprocess

    from validators import mujoco, require

    shutil.copytree(assets / "maps" / "turtlebot3_world", tmp_path / "maps" / "tb3")
    text = (RECIPES / "rover.yaml").read_text()
    recipe = tmp_path / "rover.yaml"
    recipe.write_text(text + "\nworlds:\n  tb3: {map: maps/tb3/map.yaml, height: 0.5, "
                             "spawn: {xyz: [-2.0, -0.5, 0.01], rpy: [0, 0, 1.5707963267948966]}}\n")
    build([recipe], tmp_path / "out")
    world = tmp_path / "out" / "tb3" / "tb3.world"
    root = ET.parse(world).getroot()
    assert root.findtext("world/include/uri") == "model://rover"
    assert "gz-sim-sensors-system" in {p.get("filename") for p in root.iter("plugin")}
    # libsdformat finds model://rover through SDF_PATH, as Gazebo does through its resource path
    proc = subprocess.run([require("ign"), "sdf", "-k", str(world)], capture_output=True, text=True,
                          env={**os.environ, "SDF_PATH": str(tmp_path / "out")})
    assert "Valid" in proc.stdout, proc.stdout + proc.stderr
    mj = mujoco()
    model = mj.MjModel.from_xml_path(str(tmp_path / "out" / "tb3" / "scene.xml"))
    data = mj.MjData(model)
    for _ in range(300):
        mj.mj_step(model, data)
    np.testing.assert_allclose(data.qpos[:2], [-2.0, -0.5], atol=1e-3)  # standing where it was put
    assert model.nsensor == 68
