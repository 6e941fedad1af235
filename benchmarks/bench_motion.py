"""What the motion check's simulators cost and measure on the UR5 example: each of its six
joints stepped by 0.2 rad from a pose with the elbow bent, in MuJoCo, PyBullet and Drake.

    python benchmarks/bench_motion.py [OUT]

Builds recipes/ur5.yaml into OUT (default: a temporary folder).  Gains: J = the largest
diagonal entry of MuJoCo's mass matrix for the joint over a few poses, armature A = 0.1,
w = 2 pi 4 rad/s, kp = (J + A) w^2, kd = 2 (J + A) w (critically damped for J + A: rise time
3.358 / w = 0.134 s when unsaturated), effort from the MJCF's actuatorfrcrange, gravity
compensation on.  Prints one row per joint per simulator and the totals; no timed assertions."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
          "wrist_3_joint"]
POSE = {"shoulder_lift_joint": -1.0, "elbow_joint": 1.5, "wrist_1_joint": -0.5}
W = 2 * math.pi * 4
ARMATURE = 0.1
STEP = 0.2


def gains(mjcf: Path):
    """Drives for the six joints from MuJoCo's mass matrix at a few poses."""
    import mujoco

    from robotkit.check.motion import Drive

    model = mujoco.MjModel.from_xml_path(str(mjcf))
    data = mujoco.MjData(model)
    M = np.zeros((model.nv, model.nv))
    rng = np.random.default_rng(0)
    inertia = np.zeros(model.nv)
    for k in range(8):
        data.qpos[:] = 0.0 if k == 0 else rng.uniform(-math.pi, math.pi, model.nq)
        mujoco.mj_forward(model, data)
        mujoco.mj_fullM(model, data, M)
        inertia = np.maximum(inertia, np.diag(M) - model.dof_armature)
    drives = []
    for name in JOINTS:
        j = model.joint(name).id
        J = inertia[model.jnt_dofadr[j]] + ARMATURE
        effort = float(model.jnt_actfrcrange[j][1]) if model.jnt_actfrclimited[j] else None
        drives.append(Drive(name, "position", kp=J * W**2, kd=2 * J * W, armature=ARMATURE, effort=effort,
                            gravcomp=True))
    return drives


def main() -> None:
    from robotkit.check.motion import SIMULATORS, Step, metrics

    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp())
    robotkit = Path(sys.executable).parent / "robotkit"
    t = time.perf_counter()
    subprocess.run([str(robotkit), "build", str(REPO / "recipes" / "ur5.yaml"), "--out", str(out), "--no-report"],
                   check=True, capture_output=True, cwd=REPO)
    print(f"build of ur5: {time.perf_counter() - t:.2f} s")
    d = out / "ur5"
    urdf, mjcf, packages = d / "urdf" / "ur5.urdf", d / "mjcf" / "ur5.xml", {"ur5": d}
    drives = gains(mjcf)
    print(f"w = {W:.2f} rad/s, analytic rise time (unsaturated, diagonal) {3.358 / W:.4f} s")
    print("| joint | J+A (kg m^2) | kp | kd | effort | simulator | dt (s) | wall (s) | rise (s) | overshoot "
          "| settling (s) | final error (rad) | saturated | others dev (rad) | diverged |")
    print("|" + "---|" * 15)
    totals = {s: 0.0 for s in SIMULATORS}
    for drive in drives:
        q0 = POSE.get(drive.joint, 0.0)
        step = Step(drive.joint, POSE, q0 + STEP, seconds=1.5)
        for name, simulate in SIMULATORS.items():
            t = time.perf_counter()
            # the MJCF compensates gravity itself (body gravcomp, actuatorgravcomp): MuJoCo gets no second one
            trace = (simulate(mjcf, [replace(d, gravcomp=False) for d in drives], step) if name == "mujoco"
                     else simulate(urdf, drives, step, packages))
            wall = time.perf_counter() - t
            totals[name] += wall
            m = metrics(trace, q0, q0 + STEP, "position", effort=drive.effort)
            print(f"| {drive.joint} | {drive.kp / W**2:.4f} | {drive.kp:.1f} | {drive.kd:.2f} | {drive.effort} | {name} "
                  f"| {trace.timestep:.4g} | {wall:.3f} | {fmt(m['rise_time'])} | {fmt(m['overshoot'])} "
                  f"| {fmt(m['settling_time'])} | {m['final_error']:.2e} | {m['saturated']:.3f} "
                  f"| {trace.others_max_dev:.2e} | {trace.diverged or ''} |")
    print("totals (wall, s): " + ", ".join(f"{s} {v:.2f}" for s, v in totals.items())
          + f"; all {sum(totals.values()):.2f}")
    whole_check(robotkit, d)


def whole_check(robotkit: Path, robot_dir: Path) -> None:
    """``robotkit check`` on the build, side by side with its motion stage (the build's own gains,
    the three simulators in parallel beside the other stages)."""
    t = time.perf_counter()
    proc = subprocess.run([str(robotkit), "check", str(robot_dir), "--format", "json"], capture_output=True,
                          text=True, cwd=REPO)
    wall = time.perf_counter() - t
    motion = json.loads(proc.stdout)["motion"][robot_dir.name]
    sims = ", ".join(f"{s} {v['wall']:.2f} s" for s, v in motion["simulators"].items())
    print(f"robotkit check {robot_dir.name}: {wall:.2f} s wall (exit {proc.returncode}); its motion stage "
          f"{motion['wall']:.2f} s ({sims}) running beside the other stages")


def fmt(x) -> str:
    return "never" if x is None else f"{x:.4f}"


if __name__ == "__main__":
    main()
