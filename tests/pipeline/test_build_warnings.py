"""Build-time warnings: what the cheap lints see (units, implied density, unused materials,
actuators with no force range) and what a format cannot express, one line each on stderr,
``file:line: key: warning: ...``, word for word; progress and timings never among them."""

from __future__ import annotations

import json

import pytest

import trimesh

from robotkit.pipeline.buildwarn import ROBOTS, SUBJECT, collapse

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
        "careless.yaml:6: materials.blue: warning: material 'blue': used by no geometry",
        "careless.yaml:23: actuators.wheel_joint: warning: joint 'wheel_joint': the velocity actuator has no force "
        "range in MuJoCo (unbounded torque) without an effort limit (give the joint limit: {effort: ...})"]
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
    assert [line for line in proc.stderr.splitlines() if not line.startswith("collision ")] == []
    # what MJCF cannot hold by its nature is recorded once, in report.json, and never printed
    report = json.loads((tmp_path / "out" / "careless" / "report.json").read_text())
    assert report["limits"] == {"mjcf": ["joint 'wheel_joint': MJCF has no velocity limit (10 not enforced)"]}


VARIANTS = """\
robot: twins
args:
  size: {default: 10 cm}
variants:
  small: {size: 10 cm}
  large: {size: 20 cm}
links:
  base: {visual: {box: {size: ["${size}", "${size}", "${size}"]}}, inertial: {mass: 1}}
  left: {visual: {sphere: {radius: 0.05}}, inertial: {mass: 0.1}}
  right: {visual: {sphere: {radius: 0.05}}, inertial: {mass: 0.1}}
joints:
  left_joint: {type: continuous, parent: base, child: left, axis: [0, 1, 0]}
  right_joint: {type: continuous, parent: base, child: right, axis: [0, 1, 0]}
actuators:
  left_joint: {interface: velocity, p: 2}
  right_joint: {interface: velocity, p: 2}
"""


@pytest.mark.slow
def test_a_repeated_warning_prints_once_with_its_count_and_items(tmp_path):
    """The same warning on both variants' robots, and on two actuators, is one line each."""
    write_recipe(tmp_path, VARIANTS, "twins.yaml")
    proc = run_cli("build", "twins.yaml", "--out", "out", "--no-report", "-j", "1", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert [line for line in proc.stderr.splitlines() if "warning" in line] == [
        "twins.yaml:1: metadata.maintainers: warning: twins_small, twins_large: ROS package: no maintainer: "
        "package.xml names none, and catkin and colcon refuse a package without one (give metadata.maintainers, or "
        "an author with an email)",
        "twins.yaml:15: actuators.left_joint: warning: joint 'left_joint' and 1 more ('right_joint'): the velocity "
        "actuator has no force range in MuJoCo (unbounded torque) without an effort limit (give the joint limit: "
        "{effort: ...})"]


def test_collapse_names_the_count_and_the_items():
    lines = [("r: MJCF: sensor 'a': noise is not written", "f.yaml:3: sensors.a: warning: r: MJCF: sensor 'a': "
              "noise is not written"),
             ("r: SDF: joint 'j': mimic", "f.yaml:4: joints.j: warning: r: SDF: joint 'j': mimic"),
             ("r: MJCF: sensor 'b': noise is not written", "f.yaml:5: sensors.b: warning: r: MJCF: sensor 'b': "
              "noise is not written"),
             ("r: MJCF: joint 'x' and 1 more ('y'): slow", "f.yaml:6: joints.x: warning: r: MJCF: joint 'x' and 1 "
              "more ('y'): slow"),
             ("r: MJCF: joint 'z': slow", "f.yaml:7: joints.z: warning: r: MJCF: joint 'z': slow"),
             ("mesh 'm.stl' is open", "f.yaml:8: links.a.visual.mesh: warning: mesh 'm.stl' is open"),
             ("mesh 'm.stl' is open", "f.yaml:9: links.b.visual.mesh: warning: mesh 'm.stl' is open")]
    assert collapse(lines, SUBJECT) == [
        ("r: MJCF: sensor 'a' and 1 more ('b'): noise is not written",
         "f.yaml:3: sensors.a: warning: r: MJCF: sensor 'a' and 1 more ('b'): noise is not written"),
        ("r: SDF: joint 'j': mimic", "f.yaml:4: joints.j: warning: r: SDF: joint 'j': mimic"),
        ("r: MJCF: joint 'x' and 2 more ('y', 'z'): slow",
         "f.yaml:6: joints.x: warning: r: MJCF: joint 'x' and 2 more ('y', 'z'): slow"),
        lines[5], lines[6]]  # no item named as the form wants: each where it is
    # the robots of a recipe's variants: one line when the place is the same, else apart
    twins = [("a_1: SDF: lost", "f.yaml:1: robot: warning: a_1: SDF: lost"),
             ("a_2: SDF: lost", "f.yaml:1: robot: warning: a_2: SDF: lost"),
             ("b: SDF: lost", "g.yaml:1: robot: warning: b: SDF: lost")]
    assert collapse(twins, ROBOTS) == [("a_1, a_2: SDF: lost", "f.yaml:1: robot: warning: a_1, a_2: SDF: lost"),
                                       twins[2]]
