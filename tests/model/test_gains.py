"""Gains from the robot's own inertia (robotkit.model.gains), against known answers: a box arm
on a horizontal hinge, whose inertia about the hinge and gravity torque are known in closed form."""

from __future__ import annotations

import math

import pytest

from robotkit.model import gains
from robotkit.model.load import load_robots
from robotkit.model.resolve import finalize
from tests.conftest import write_recipe

M, L, W = 2.0, 0.5, 0.05  # kg, m: a box arm, its centre of mass L/2 from the hinge
ROTOR, GEAR = 1e-4, 10.0
ARMATURE = ROTOR * GEAR ** 2
J = M * (L ** 2 + W ** 2) / 12 + M * (L / 2) ** 2 + ARMATURE  # about the hinge, with the armature
G = M * 9.81 * L / 2  # the largest gravity torque: the arm horizontal

ARM = f"""
robot: arm
links:
  world: {{}}
  base: {{inertial: {{mass: 1, inertia: {{ixx: 0.01, iyy: 0.01, izz: 0.01}}}}}}
  arm:
    inertial:
      mass: {M}
      com: [{L / 2}, 0, 0]
      inertia: {{ixx: {M * 2 * W ** 2 / 12}, iyy: {M * (L ** 2 + W ** 2) / 12}, izz: {M * (L ** 2 + W ** 2) / 12}}}
joints:
  world_joint: {{type: fixed, parent: world, child: base}}
  hinge:
    type: revolute
    parent: base
    child: arm
    axis: [0, 1, 0]
    limit: {{lower: -90 deg, upper: 90 deg, effort: EFFORT, velocity: 5}}
actuators:
  hinge: ACTUATOR
"""


def tuned(tmp_path, actuator: str, effort: float = 20.0) -> dict:
    text = ARM.replace("EFFORT", str(effort)).replace("ACTUATOR", actuator)
    recipe = write_recipe(tmp_path, text, "arm.yaml")
    [(_, robot)] = load_robots([recipe])
    robot = finalize(robot, {}, {})
    report = gains.tune(robot)
    return report, robot


def test_the_inertia_about_the_hinge_and_the_gravity_torque_are_the_closed_form(tmp_path):
    report, _ = tuned(tmp_path, f"{{gains: auto, motor: {{rotor_inertia: {ROTOR}, gear: {GEAR}}}}}")
    d = report["drives"]["hinge"]
    assert d["armature"] == pytest.approx(ARMATURE, rel=1e-12)
    # a hinge whose outboard body is one rigid box: the same inertia at every configuration
    assert d["inertia"]["max"] == pytest.approx(J, rel=1e-9)
    assert d["inertia"]["min"] == pytest.approx(J, rel=1e-9)
    assert d["gravity_torque_max"] == pytest.approx(G, rel=1e-9)


def test_a_given_bandwidth_and_damping_ratio_give_kp_j_w2_and_kd_2_zeta_j_w(tmp_path):
    report, robot = tuned(tmp_path, f"{{gains: auto, bandwidth: 2, damping_ratio: 0.7, armature: {ARMATURE}}}")
    d = report["drives"]["hinge"]
    w = 2 * math.pi * 2
    assert (d["p"], d["d"]) == (float(f"{J * w * w:.4g}"), float(f"{2 * 0.7 * J * w:.4g}"))
    assert d["source"] == "auto" and d["bandwidth_reason"] == "the recipe's bandwidth"
    tuned_robot = gains.apply(robot, report)
    assert (tuned_robot.actuators[0].p, tuned_robot.actuators[0].d) == (d["p"], d["d"])


def test_the_default_bandwidth_keeps_a_reference_step_within_the_effort_limit(tmp_path):
    report, _ = tuned(tmp_path, f"{{gains: auto, armature: {ARMATURE}}}", effort=20.0)
    d = report["drives"]["hinge"]
    w = math.sqrt((20.0 - G) / (J * 0.2))  # kp * 0.2 rad + the largest gravity torque = the effort limit
    assert d["bandwidth_hz"] == pytest.approx(w / (2 * math.pi), rel=1e-12)
    assert d["bandwidth_reason"] == "a reference step of 0.2 within the effort limit against gravity"
    assert d["peak_effort"] == pytest.approx(20.0, rel=1e-3) and not d["saturates"]


def test_a_weak_effort_limit_leaves_the_cap_and_a_strong_one_the_5_hz_ceiling(tmp_path):
    report, _ = tuned(tmp_path, f"{{gains: auto, armature: {ARMATURE}}}", effort=1000.0)
    d = report["drives"]["hinge"]
    assert d["bandwidth_hz"] == pytest.approx(5.0) and d["bandwidth_reason"] == "at most 5 Hz"


def test_a_fixed_arm_that_sags_gets_gravity_compensation(tmp_path):
    report, robot = tuned(tmp_path, f"{{gains: auto, armature: {ARMATURE}}}")
    d = report["drives"]["hinge"]
    assert d["sag"] == pytest.approx(G / d["p"], rel=1e-12) and d["sag"] > math.radians(0.1)
    assert report["gravcomp"] and d["gravcomp"]
    assert gains.apply(robot, report).actuators[0].gravcomp


def test_given_gains_are_kept_and_checked_beside_what_auto_would_give(tmp_path):
    report, robot = tuned(tmp_path, "{p: 150, i: 0, d: 50}")
    d = report["drives"]["hinge"]
    assert (d["source"], d["p"], d["d"]) == ("recipe", 150.0, 50.0)
    assert set(d["auto_would_give"]) == {"p", "d", "bandwidth_hz"}
    assert not report["gravcomp"]  # only gains: auto asks for it
    # the time-step figures: kv dt / M at MuJoCo's 0.002 s
    assert d["stability"]["mujoco"]["kv_dt_over_m"] == pytest.approx(50 * 0.002 / (J - ARMATURE), rel=1e-9)
    assert gains.apply(robot, report).actuators[0].p == 150.0
