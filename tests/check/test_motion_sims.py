"""The motion check's simulators against known answers: a critically damped PD step on a
hinge (rise time 3.358 / w, no overshoot), a velocity step (first order, rise time ln 9 tau),
a pendulum held by gravity compensation or sagging by m g l sin(q) / kp, an explicit-damping
explosion in a plain PyBullet torque loop that the implicit integrators survive, and the metrics on synthetic curves.
The fixtures are written by hand here, as URDF (PyBullet, Drake) and MJCF (MuJoCo)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from robotkit.check.motion.pybullet_sim import simulate_pybullet
from robotkit.check.motion import SIMULATORS, Drive, Step, Trace, metrics, simulate_mujoco

RISE = 3.358  # x 1/w: the 10-90 % rise time of y = 1 - (1 + w t) exp(-w t)
G = 9.81

URDF = """<?xml version="1.0"?>
<robot name="{name}">
  <link name="base_link">
    <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <link name="arm">
    <inertial><origin xyz="0 0 {com}"/><mass value="{mass}"/>
      <inertia ixx="{i}" ixy="0" ixz="0" iyy="{i}" iyz="0" izz="{i}"/></inertial>
  </link>
  <joint name="hinge" type="revolute">
    <parent link="base_link"/><child link="arm"/><origin xyz="0 0 0.5"/><axis xyz="{axis}"/>
    <limit lower="-10" upper="10" effort="1000" velocity="1000"/>
  </joint>
</robot>
"""

MJCF = """<mujoco model="{name}">
  <option integrator="implicitfast" timestep="0.002"/>
  <worldbody>
    <body name="base_link">
      <inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>
      <body name="arm" pos="0 0 0.5">
        <joint name="hinge" type="hinge" axis="{axis}" armature="{armature}"/>
        <inertial pos="0 0 {com}" mass="{mass}" diaginertia="{i} {i} {i}"/>
      </body>
    </body>
  </worldbody>
  {actuator}
</mujoco>
"""


def fixture(folder: Path, name: str, axis="0 0 1", com=0.0, mass=1.0, i=0.02, armature=0.0, actuator=""):
    """(urdf, mjcf) of one hinge: ``i`` about the COM, which sits ``com`` along the arm's z."""
    urdf, mjcf = folder / f"{name}.urdf", folder / f"{name}.xml"
    urdf.write_text(URDF.format(name=name, axis=axis, com=com, mass=mass, i=i))
    mjcf.write_text(MJCF.format(name=name, axis=axis, com=com, mass=mass, i=i, armature=armature, actuator=actuator))
    return urdf, mjcf


def run(simulator: str, urdf: Path, mjcf: Path, drives, step) -> Trace:
    if simulator == "mujoco":
        return simulate_mujoco(mjcf, drives, step)
    return SIMULATORS[simulator](urdf, drives, step, package_dirs={})


J, A, W = 0.02, 0.01, 10.0  # the hinge: inertia about its axis, armature, natural frequency (rad/s)
CRITICAL = Drive("hinge", "position", kp=(J + A) * W**2, kd=2 * (J + A) * W, armature=A, effort=100.0)
# measured (rise time / analytic): mujoco 0.9953, pybullet 1.0100, drake 1.0050 (velocity step:
# 1.0050, 0.9896, 1.0025)
RISE_TOL = 0.02
SIMS = [pytest.param("mujoco"), pytest.param("pybullet", marks=pytest.mark.consumers),
        pytest.param("drake", marks=pytest.mark.consumers)]


@pytest.mark.parametrize("simulator", SIMS)
def test_critically_damped_step(tmp_path, simulator):
    urdf, mjcf = fixture(tmp_path, "hinge", i=J, armature=A)
    trace = run(simulator, urdf, mjcf, [CRITICAL], Step("hinge", {"hinge": 0.0}, 0.5))
    m = metrics(trace, 0.0, 0.5, "position", effort=CRITICAL.effort)
    assert trace.diverged is None and trace.simulator == simulator
    assert m["rise_time"] == pytest.approx(RISE / W, rel=RISE_TOL)
    assert m["overshoot"] < 0.01
    assert m["final_error"] < 1e-3
    assert m["saturated"] == 0.0


@pytest.mark.parametrize("simulator", SIMS)
def test_velocity_step(tmp_path, simulator):
    """A velocity drive on J + A: qd = v (1 - exp(-t kv / (J + A))), rise time ln(9) (J + A) / kv."""
    urdf, mjcf = fixture(tmp_path, "wheel", i=J, armature=A)
    kv = 0.15
    drive = Drive("hinge", "velocity", kp=kv, kd=0.0, armature=A)
    trace = run(simulator, urdf, mjcf, [drive], Step("hinge", {}, 2.0, seconds=2.0))
    m = metrics(trace, 0.0, 2.0, "velocity")
    assert trace.diverged is None
    assert m["rise_time"] == pytest.approx(math.log(9) * (J + A) / kv, rel=RISE_TOL)
    assert m["overshoot"] < 0.01 and m["final_error"] < 1e-3 and m["chatter"] <= 1


M, L, I_COM = 1.0, 0.25, 0.001  # the pendulum: mass, COM below the joint, inertia about the COM
PENDULUM_J = I_COM + M * L**2


def pendulum_drive(gravcomp: bool, w: float = 20.0) -> Drive:
    return Drive("hinge", "position", kp=PENDULUM_J * w**2, kd=2 * PENDULUM_J * w, gravcomp=gravcomp)


@pytest.mark.parametrize("simulator", SIMS)
def test_pendulum_gravity_compensation(tmp_path, simulator):
    urdf, mjcf = fixture(tmp_path, "pendulum", axis="0 1 0", com=-L, mass=M, i=I_COM)
    for q in (0.6, -1.2):
        held = run(simulator, urdf, mjcf, [pendulum_drive(True)], Step("hinge", {"hinge": q}, q, seconds=1.0))
        assert held.diverged is None
        assert metrics(held, q, q, "position")["final_error"] < 1e-3  # measured: 0 (it never moves)
    stepped = run(simulator, urdf, mjcf, [pendulum_drive(True)], Step("hinge", {"hinge": -0.3}, 0.9, seconds=1.0))
    assert metrics(stepped, -0.3, 0.9, "position")["final_error"] < 1e-3


@pytest.mark.parametrize("simulator", SIMS)
def test_pendulum_sags_without_gravity_compensation(tmp_path, simulator):
    """kp (q_target - q) = m g l sin(q) at rest: measured to 1e-6 in all three; the small-sag
    estimate m g l sin(q_target) / kp is 2 % off here (7.5 % at w = 20)."""
    urdf, mjcf = fixture(tmp_path, "pendulum", axis="0 1 0", com=-L, mass=M, i=I_COM)
    drive = pendulum_drive(False, w=40.0)
    sagged = run(simulator, urdf, mjcf, [drive], Step("hinge", {"hinge": 0.6}, 0.6, seconds=1.0))
    sag = 0.6 - sagged.q[-1]
    assert sag == pytest.approx(M * G * L * math.sin(sagged.q[-1]) / drive.kp, rel=1e-3)  # the equilibrium
    assert sag == pytest.approx(M * G * L * math.sin(0.6) / drive.kp, rel=0.05)  # the small-sag estimate


# kd dt / J = 10 at PyBullet's 1/240 s (4.8 at MuJoCo's 0.002 s): explicit damping diverges.
# Measured: PyBullet "exploded at t=0.02083 s (|qd| 1.85e+03)" (the 5th step); MuJoCo (implicitfast)
# and Drake (implicit PD) creep to q = 0.0153 in 0.5 s with max |qd| 0.031 rad/s.
STIFF = Drive("hinge", "position", kp=3.0, kd=10 * J * 240, armature=0.0)


@pytest.mark.consumers
def test_explicit_damping_explodes_in_a_plain_pybullet_torque_loop_only(tmp_path):
    urdf, mjcf = fixture(tmp_path, "stiff", i=J)
    step = Step("hinge", {}, 0.5, seconds=0.5)
    traces = {s: run(s, urdf, mjcf, [STIFF], step) for s in SIMULATORS}
    plain = simulate_pybullet(urdf, [STIFF], step, {}, implicit=False)
    assert plain.diverged is not None and plain.diverged.startswith("exploded at t=")
    assert all(t.diverged is None for t in traces.values())  # PyBullet's loop integrates kd implicitly
    assert np.abs(traces["mujoco"].qd).max() < 1.0  # heavily overdamped: it creeps toward the target
    # the implicit loop is MuJoCo's implicitfast: the same creep
    assert traces["pybullet"].q[-1] == pytest.approx(traces["mujoco"].q[-1], rel=0.05)


def test_mujoco_uses_the_files_actuators_only_when_they_are_the_drives(tmp_path):
    _, bare = fixture(tmp_path, "bare", i=J, armature=A)
    kp, kd = CRITICAL.kp, CRITICAL.kd
    _, same = fixture(tmp_path, "same", i=J, armature=A, actuator=f'<actuator><position name="hinge_position" '
                      f'joint="hinge" kp="{kp!r}" kv="{kd!r}"/></actuator>')
    _, other = fixture(tmp_path, "other", i=J, armature=0.5, actuator='<actuator><position name="hinge_position" '
                       'joint="hinge" kp="1" kv="0.1"/></actuator>')
    step = Step("hinge", {}, 0.5, seconds=0.5)
    reference = simulate_mujoco(bare, [CRITICAL], step).q
    np.testing.assert_allclose(simulate_mujoco(same, [CRITICAL], step).q, reference, atol=1e-12)
    np.testing.assert_allclose(simulate_mujoco(other, [CRITICAL], step).q, reference, atol=1e-12)


def synthetic(t, y, start=0.0, size=1.0) -> Trace:
    q = start + size * y
    return Trace("synthetic", float(t[1] - t[0]), t, q, np.gradient(q, t), np.zeros_like(t), 0.0, None, [])


def test_metrics_on_known_curves():
    w = 5.0
    t = np.arange(0.0, 4.0, 1e-4)
    critical = metrics(synthetic(t, 1 - (1 + w * t) * np.exp(-w * t), 0.2, 0.5), 0.2, 0.7, "position")
    assert critical["rise_time"] == pytest.approx(RISE / w, rel=1e-3)
    assert critical["overshoot"] == 0.0
    assert critical["settling_time"] == pytest.approx(5.834 / w, rel=1e-3)  # (1 + x) e^-x = 0.02
    zeta = 0.3  # underdamped: overshoot exp(-pi zeta / sqrt(1 - zeta^2))
    wd = w * math.sqrt(1 - zeta**2)
    y = 1 - np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t))
    under = metrics(synthetic(t, y, 0.0, -0.4), 0.0, -0.4, "position")
    assert under["overshoot"] == pytest.approx(math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2)), rel=1e-3)
    assert under["final_error"] == pytest.approx(0.4 * abs(1 - y[-1]))
    never = metrics(synthetic(t, 0.5 * (1 - np.exp(-t))), 0.0, 1.0, "position")
    assert never["rise_time"] is None and never["settling_time"] is None


def test_metrics_saturation_and_chatter():
    t = np.arange(0.0, 1.0, 0.01)
    qd = np.where(np.arange(len(t)) % 2 == 0, 1.0, 1.1)  # a velocity ringing every sample
    trace = Trace("synthetic", 0.01, t, np.cumsum(qd) * 0.01, qd, np.where(t < 0.25, 5.0, 1.0), 0.0, None, [])
    m = metrics(trace, 0.0, 1.0, "velocity", effort=5.0)
    assert m["saturated"] == pytest.approx(0.25)
    assert m["chatter"] == len(t) // 2 - 2


@pytest.mark.consumers
@pytest.mark.parametrize("simulator", ["pybullet", "drake"])
def test_urdf_rooted_at_world(tmp_path, simulator):
    """A root link named ``world`` (Drake welds the robot itself) gives the same response."""
    urdf, mjcf = fixture(tmp_path, "hinge", i=J, armature=A)
    text = urdf.read_text().replace('<link name="base_link">', '<link name="world"/>\n  <joint name="fix" type="fixed">'
                                    '<parent link="world"/><child link="base_link"/></joint>\n  <link name="base_link">')
    rooted = tmp_path / "rooted.urdf"
    rooted.write_text(text)
    step = Step("hinge", {}, 0.5, seconds=0.5)
    np.testing.assert_allclose(run(simulator, rooted, mjcf, [CRITICAL], step).q,
                               run(simulator, urdf, mjcf, [CRITICAL], step).q, atol=1e-9)


@pytest.mark.consumers
def test_pybullet_refuses_a_free_base_it_cannot_compensate(tmp_path):
    urdf, _ = fixture(tmp_path, "hinge", i=J, armature=A)
    with pytest.raises(ValueError, match="PyBullet cannot give the armature or gravity compensation of a free base"):
        SIMULATORS["pybullet"](urdf, [CRITICAL], Step("hinge", {}, 0.5, seconds=0.1), {}, hold_base=False)


def test_mujoco_holds_a_free_base(tmp_path):
    _, bare = fixture(tmp_path, "bare", i=J, armature=A)
    free = tmp_path / "free.xml"
    free.write_text(bare.read_text().replace('<body name="base_link">', '<body name="base_link">\n      <freejoint/>'))
    step = Step("hinge", {}, 0.5, seconds=0.5)
    np.testing.assert_allclose(simulate_mujoco(free, [CRITICAL], step).q, simulate_mujoco(bare, [CRITICAL], step).q,
                               atol=1e-12)
    falling = simulate_mujoco(free, [CRITICAL], step, hold_base=False)
    assert falling.diverged is None  # the whole robot falls: the hinge's response is not the held one


@pytest.mark.parametrize("bad", [None, "nan", "explode"])
def test_record_many_is_record_row_by_row(bad):
    """Drake's runs are recorded from Drake's logs in numpy: the same trace, hold and divergence
    as recording each control step in turn."""
    from robotkit.check.motion.law import Recorder

    drives = [Drive("a", "position", 10.0, 1.0), Drive("b", "position", 10.0, 1.0)]
    step = Step("a", {"a": 0.1, "b": -0.2}, 0.3)
    rng = np.random.default_rng(7)
    t = np.arange(50) * 2e-3
    q, qd, tau = rng.normal(size=(50, 2)), rng.normal(size=(50, 2)), rng.normal(size=50)
    if bad == "nan":
        q[31, 1] = np.nan
    elif bad == "explode":
        qd[17, 0] = -2e3
    one, many = Recorder("drake", 2e-3, step, drives), Recorder("drake", 2e-3, step, drives)
    for k in range(50):
        if not one.record(float(t[k]), dict(zip("ab", q[k].tolist())), dict(zip("ab", qd[k].tolist())),
                          float(tau[k])):
            break
    assert many.record_many(t[:20], ["a", "b"], q[:20], qd[:20], tau[:20]) == (bad != "explode")
    if bad != "explode":
        many.record_many(t[20:], ["a", "b"], q[20:], qd[20:], tau[20:])
    a, b = one.trace(), many.trace()
    assert (a.diverged, a.others_max_dev, len(a.t)) == (b.diverged, b.others_max_dev, len(b.t))
    assert all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("t", "q", "qd", "tau"))
    assert (a.diverged is None) == (bad is None)
