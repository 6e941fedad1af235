"""Issue 32, G1's ankle roll links, Baxter's head and screen, TIAGo Pro's lasers: a visual mesh that
is open as its file writes it (a face wound the wrong way) and that robotkit's mesh repair closes.
Check reads the file as every consumer does, finds it open and judges the link's implied density on
the collision geometry (contact spheres); the import judged it on the repaired visual and never
reported what check flagged.  Both now take the volume from one rule
(robotkit.mesh.inertia.density_volume on solid_as_written's volumes), so the import warns exactly
when check errors, with the same numbers."""

from __future__ import annotations

import numpy as np
import trimesh

from robotkit.check.lints import lint_link, read_urdf_facts
from robotkit.importer import import_file
from robotkit.importer.meshes import mesh_is_closed
from robotkit.mesh.inertia import density_volume, solid_as_written
from robotkit.pipeline.runner import build

SIDE = 0.1
MASS = 1.0
MOMENT = MASS * SIDE * SIDE / 6  # the cube's own tensor: it fits the visual, only the density is judged


def _flipped_cube(path):
    """A 10 cm cube with one face wound the wrong way: closed, not consistently wound."""
    box = trimesh.creation.box((SIDE, SIDE, SIDE))
    faces = box.faces.copy()
    faces[0] = faces[0][::-1]
    trimesh.Trimesh(box.vertices, faces, process=False).export(path)


def _urdf(tmp_path, collision: str):
    _flipped_cube(tmp_path / "ankle.stl")
    urdf = tmp_path / "ankle.urdf"
    urdf.write_text(f"""<?xml version="1.0"?>
<robot name="ankle">
  <link name="ankle_roll_link">
    <visual><geometry><mesh filename="ankle.stl"/></geometry></visual>
    <collision><geometry>{collision}</geometry></collision>
    <inertial><mass value="{MASS}"/><inertia ixx="{MOMENT}" ixy="0" ixz="0" iyy="{MOMENT}" iyz="0" izz="{MOMENT}"/>
    </inertial>
  </link>
</robot>
""", encoding="utf-8")
    return urdf


def test_the_rule_reads_the_file_as_written():
    box = trimesh.creation.box((SIDE, SIDE, SIDE))
    assert abs(solid_as_written(box.vertices, box.faces).volume - SIDE ** 3) < 1e-12
    faces = box.faces.copy()
    faces[0] = faces[0][::-1]
    assert solid_as_written(box.vertices, faces) is None
    assert density_volume([None], [2e-6, 4e-6]) == 6e-6  # the visual open: the collision's
    assert density_volume([1e-3], [2e-6]) == 1e-3
    assert density_volume([], [None]) is None  # no closed part in either role: not judged


def _density_findings(tmp_path, urdf):
    result = import_file(urdf, tmp_path / "recipe" / "robot.yaml")
    warned = [w.split("ankle.urdf:3: ", 1)[-1] for w in result.warnings if "implies" in w]
    out = build([result.recipe_path], tmp_path / "build")
    assert not out.errors, out.errors
    built = next((tmp_path / "build" / result.robot).rglob("*.urdf"))
    links, _, _ = read_urdf_facts(built)
    found = [f"{f.severity} {f.check} {f.subject}: {f.message} ({f.hint})"
             for link in links for f in lint_link(link) if f.check == "implied-density"]
    return warned, found


def test_an_open_visual_repaired_by_robotkit_is_judged_on_the_collision_as_check_does(tmp_path):
    urdf = _urdf(tmp_path, '<sphere radius="0.01"/>')
    assert mesh_is_closed(str(tmp_path / "ankle.stl"), (1.0, 1.0, 1.0))  # robotkit's repair closes it
    warned, found = _density_findings(tmp_path, urdf)
    assert warned == [
        "link 'ankle_roll_link': the original's mass 1 kg over its geometry's 4.189e-06 m^3 implies 2.387e+05 kg/m^3, "
        "above 25000 (the mass looks like grams written as kilograms): kept (check reports it)"]
    assert found == [
        "error implied-density link 'ankle_roll_link': implied density 2.387e+05 kg/m^3 (mass 1 kg, volume "
        "4.189e-06 m^3) is above 25000 (the mass looks like grams written as kilograms)"]


def test_no_warning_when_check_finds_none(tmp_path):
    """The same link with a collision box of the part's size: neither says anything."""
    urdf = _urdf(tmp_path, f'<box size="{SIDE} {SIDE} {SIDE}"/>')
    assert _density_findings(tmp_path, urdf) == ([], [])
