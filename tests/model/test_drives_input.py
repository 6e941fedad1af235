"""Bad drives and poses in a recipe: one line each with file:line:key, all together, exit 2,
nothing written."""

from __future__ import annotations

from tests.conftest import run_cli, write_recipe

ROBOT = """
robot: arm
links:
  world: {}
  base: {inertial: {mass: 1, inertia: {ixx: 0.01, iyy: 0.01, izz: 0.01}}}
  arm: {inertial: {mass: 1, inertia: {ixx: 0.01, iyy: 0.01, izz: 0.01}}}
  finger: {inertial: {mass: 0.1, inertia: {ixx: 0.001, iyy: 0.001, izz: 0.001}}}
  wheel: {inertial: {mass: 0.1, inertia: {ixx: 0.001, iyy: 0.001, izz: 0.001}}}
joints:
  fix: {type: fixed, parent: world, child: base}
  j1: {type: revolute, parent: base, child: arm, axis: [0, 1, 0], limit: {lower: -1, upper: 1, effort: 10, velocity: 1}}
  j2: {type: revolute, parent: arm, child: finger, axis: [0, 1, 0], mimic: {joint: j1},
       limit: {lower: -1, upper: 1, effort: 10, velocity: 1}}
  spin: {type: continuous, parent: base, child: wheel, axis: [0, 1, 0], limit: {effort: 1, velocity: 10}}
"""


def line(recipe, text: str) -> int:
    """The last line of ``recipe`` starting with ``text`` (actuators and poses follow the joints)."""
    return max(n for n, row in enumerate(recipe.read_text().splitlines(), 1) if row.startswith(text))


def build(tmp_path, tail: str):
    recipe = write_recipe(tmp_path, ROBOT + tail, "arm.yaml")
    proc = run_cli("build", recipe, "--out", tmp_path / "out")
    return recipe, proc


def test_bad_poses_and_drives_are_named_together(tmp_path):
    recipe, proc = build(tmp_path, """
actuators:
  j1: {gains: auto, motor: {rotor_inertia: 1.0e-4, gear: 10}}
  spin: {gains: auto}
poses:
  home: {j1: 2, j2: 0.1, nope: 1, spin: 90 deg, fix: 0}
""")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    spin, home = line(recipe, "  spin: "), line(recipe, "  home: ")
    assert proc.stderr.splitlines() == [
        f"{recipe}:{spin}: actuators.spin.gains: gains: auto on a position drive needs joint 'spin' to have limits; "
        "a continuous joint takes a velocity interface",
        f"{recipe}:{home}: poses.home.j1: 2 is outside the limits of joint 'j1' [-1, 1]",
        f"{recipe}:{home}: poses.home.j2: joint 'j2' mimics 'j1'; set the joint it follows",
        f"{recipe}:{home}: poses.home.nope: no joint named 'nope'",
        f"{recipe}:{home}: poses.home.fix: joint 'fix' is fixed: a pose sets revolute, continuous and prismatic joints",
    ]
    assert not (tmp_path / "out" / "arm").exists()


def test_gains_that_are_not_numbers_or_contradict_each_other(tmp_path):
    recipe, proc = build(tmp_path, """
actuators:
  j1: {gains: auto, p: 5}
  spin: {interface: velocity, p: -1, motor: {rotor_inertia: .nan, gear: 10}}
poses:
  home: {spin: 5 cm}
""")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    j1, spin, home = line(recipe, "  j1: "), line(recipe, "  spin: "), line(recipe, "  home: ")
    lines = proc.stderr.splitlines()
    assert f"{recipe}:{j1}: actuators.j1: gains: auto derives p and d; remove p or gains: auto" in lines
    assert f"{recipe}:{spin}: actuators.spin.p: must be >= 0" in lines
    assert any(line.startswith(f"{recipe}:{spin}: actuators.spin.motor.rotor_inertia: ") for line in lines)
    assert f"{recipe}:{home}: poses.home.spin: expects an angle, got a length ('5 cm')" in lines
    assert len(lines) == 4


def test_effort_drives_take_no_gains_and_tuning_keys_need_auto(tmp_path):
    recipe, proc = build(tmp_path, """
actuators:
  j1: {interface: effort, gains: auto}
  spin: {interface: velocity, p: 1, bandwidth: 3, armature: 0.1, motor: {rotor_inertia: 1.0e-4, gear: 10}}
""")
    assert proc.returncode == 2
    j1, spin = line(recipe, "  j1: "), line(recipe, "  spin: ")
    assert proc.stderr.splitlines() == [
        f"{recipe}:{j1}: actuators.j1: an effort actuator takes no gains (gains: auto is for position and velocity)",
        f"{recipe}:{spin}: actuators.spin: bandwidth only apply with gains: auto",
    ]
