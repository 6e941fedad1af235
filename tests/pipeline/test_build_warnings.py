"""Build-time warnings: what the cheap lints see (units, implied density, unused materials,
actuators with no force range) and what a format cannot express, one line each on stderr,
``file:line: key: warning: ...``, word for word; progress and timings never among them."""

from __future__ import annotations

import pytest

import trimesh

from conftest import run_cli, write_recipe

RECIPE = """\
robot: careless
density: 1250
metadata: {maintainers: [{name: A, email: a@example.org}]}
materials:
  red: {rgba: [0.8, 0, 0, 1]}
  blue: {rgba: [0, 0, 0.8, 1]}
links:
  base:
    visual: {box: {size: [0.3, 0.3, 0.1]}, material: red}
  wheel:
    visual: {mesh: wheel.stl}
  payload:
    visual: {box: {size: [0.1, 0.1, 0.1]}}
    inertial: {mass: 2000}
joints:
  wheel_joint:
    type: continuous
    parent: base
    child: wheel
    axis: [0, 1, 0]
  payload_joint: {type: fixed, parent: base, child: payload, origin: {xyz: [0, 0, 0.1]}}
actuators:
  wheel_joint: {interface: velocity, p: 2}
"""


@pytest.mark.slow
def test_build_warns_with_file_line_and_key(tmp_path):
    wheel = trimesh.creation.cylinder(radius=66.0, height=26.0, sections=64)  # millimetres, declared as metres
    write_recipe(tmp_path, RECIPE, "careless.yaml", {"wheel.stl": wheel})
    proc = run_cli("build", "careless.yaml", "--out", "out", "--no-report", "-j", "1", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    warnings = [line for line in proc.stderr.splitlines() if not line.startswith("collision ")]
    assert warnings == [
        "careless.yaml:11: links.wheel.visual.mesh: warning: mesh 'wheel.stl' is 132 m across as declared (scale 1): "
        "a mesh in millimetres declared as metres? (units: mm)",
        "careless.yaml:14: links.payload.inertial: warning: link 'payload': mass 2000 kg in 0.001 m^3 of visual "
        "geometry implies 2e+06 kg/m^3, outside 10..25000 (grams written as kilograms, or a mesh in millimetres "
        "declared as metres?)",
        "careless.yaml:6: materials.blue: warning: material 'blue' is used by no geometry",
        "careless.yaml:23: actuators.wheel_joint: warning: the velocity actuator of continuous joint 'wheel_joint' "
        "has no force range in MuJoCo (unbounded torque): the joint has no effort limit (give it limit: {effort: "
        "...})"]
    # a no-op rebuild keeps them (counted; -v shows them again)
    again = run_cli("build", "careless.yaml", "--out", "out", "--no-report", "-j", "1", "-v", cwd=tmp_path)
    assert [line for line in again.stderr.splitlines() if "warning:" in line] == warnings


@pytest.mark.slow
def test_a_clean_recipe_builds_without_warnings(tmp_path):
    write_recipe(tmp_path, RECIPE.replace("  blue: {rgba: [0, 0, 0.8, 1]}\n", "")
                 .replace("{mesh: wheel.stl}", "{mesh: wheel.stl, units: mm}")
                 .replace("inertial: {mass: 2000}", "inertial: {mass: 2}")
                 .replace("axis: [0, 1, 0]", "axis: [0, 1, 0]\n    limit: {effort: 3, velocity: 10}"),
                 "clean.yaml", {"wheel.stl": trimesh.creation.cylinder(radius=66.0, height=26.0, sections=64)})
    proc = run_cli("build", "clean.yaml", "--out", "out", "--no-report", "-j", "1", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert [line for line in proc.stderr.splitlines() if not line.startswith("collision ")] == [
        "clean.yaml:15: joints.wheel_joint: warning: careless: MJCF: joint 'wheel_joint': MJCF has no velocity "
        "limit (10 not enforced)"]
