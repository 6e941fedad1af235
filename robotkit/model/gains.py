"""Gains from the robot's own inertia, and the checks every drive gets (given gains too).

For each actuated joint the effective inertia J is the diagonal of the joint-space mass matrix
(armature included) over configurations: the zero pose, the named poses, each joint's own range
swept with the others at each pose, and seeded random samples within the limits.  The base is
held; a free robot is also taken standing at the zero pose and its named poses: its weight
shared by its lowest leaf bodies (the feet), which adds the weight each joint holds and the
body's mass reflected through the leg to J (:func:`stance`).  MuJoCo computes M and the gravity torques
(``mj_fullM``, ``qfrc_bias`` at rest) on a model built from the finalized robot without geometry.

``gains: auto`` takes the worst case: ``kp = J_max w^2``, ``kd = 2 zeta J_max w`` (a position
drive), ``kv = J_max w`` (a velocity drive: time constant 1/w).  The default bandwidth is the
highest that keeps a reference step (a tenth of the range, at most 0.2 rad or 2 cm) inside the
effort limit against the largest gravity torque, at most :data:`MAX_BANDWIDTH_HZ`, and with
``w dt`` at most :data:`MAX_W_DT` at every simulator's time step.  Where the sag under gravity
(largest gravity torque / kp) of an auto position drive exceeds :data:`SAG_TOLERANCE` and the
base is fixed, every drive compensates gravity (MJCF ``gravcomp`` and ``actuatorgravcomp``);
the ROS formats cannot, so the report says an integral term or feed-forward is needed there.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np

from robotkit import mj
from robotkit.geometry import rpy_quat
from robotkit.model.robot import Robot

TIMESTEPS = {"mujoco": 0.002, "pybullet": 1 / 240, "drake": 0.002}
"""Each simulator's time step as robotkit's outputs and checks use it (MuJoCo: the MJCF's default)."""
IMPLICIT_DAMPING = {"mujoco": True, "pybullet": True, "drake": True}
"""Whether the drive's damping is integrated implicitly: MuJoCo's implicitfast (the MJCF's
integrator), Drake SAP's PD controllers, and robotkit's PyBullet loop (stable PD,
:mod:`robotkit.check.motion.pybullet_sim`); a hand-written explicit torque loop is not."""
MAX_BANDWIDTH_HZ = 5.0
MAX_W_DT = 0.2  # semi-implicit Euler is stable below 2; a tenth of that keeps the response true
STABLE_W_DT = 2.0  # semi-implicit Euler on a spring: unstable from w dt = 2
MAX_KV_DT_OVER_M = 1.0  # explicit damping, as chosen (the Kinova Gen3 fix brought it to 0.99)
STABLE_KV_DT_OVER_M = 2.0  # explicit Euler on a damper: unstable from 2
REFERENCE_STEP = {"revolute": 0.2, "prismatic": 0.02}  # rad, m: at most a tenth of the range
SAG_TOLERANCE = {"revolute": math.radians(0.1), "prismatic": 1e-4}  # rad, m
DAMPING_DOMINANCE = 100.0  # a velocity drive's kv over the joint's own damping (steady state within 1 %)
SAMPLES = 64
SEED = 0
ACTUATED = ("revolute", "continuous", "prismatic")


def _free_angle_range(j) -> tuple[float, float]:
    if j.type == "continuous" or j.limit is None or j.limit.lower is None:
        return -math.pi, math.pi
    return j.limit.lower, j.limit.upper


def dynamics_model(robot: Robot):
    """A MuJoCo model of the finalized robot's bodies, inertials and joints (no geometry), its
    base held; joint names as the robot's.  Mimic joints are left free (their coupling is not in M)."""
    mujoco = mj.load()  # heavy: only a build with actuators tunes

    spec = mujoco.MjSpec()
    spec.option.gravity = [0, 0, -9.81]
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    links = {link.name: link for link in robot.links}
    children: dict[str, list] = {}
    for j in robot.joints:
        children.setdefault(j.parent, []).append(j)
    stack = [(spec.worldbody, j) for j in reversed(children.get(robot.root, []))]
    if robot.root != "world":
        top = spec.worldbody.add_body(name=robot.root)
        _inertial(top, links[robot.root])
        stack = [(top, j) for j in reversed(children.get(robot.root, []))]
    while stack:
        parent, j = stack.pop()
        b = parent.add_body(name=j.child, pos=list(j.origin.xyz), quat=list(rpy_quat(j.origin.rpy)))
        _inertial(b, links[j.child])
        _feet_geoms(b, links[j.child])
        if j.type in ACTUATED:
            kind = mujoco.mjtJoint.mjJNT_SLIDE if j.type == "prismatic" else mujoco.mjtJoint.mjJNT_HINGE
            b.add_joint(name=j.name, type=kind, axis=list(j.axis),
                        armature=j.dynamics.armature if j.dynamics is not None else 0.0)
        stack.extend((b, c) for c in reversed(children.get(j.child, [])))
    return spec.compile()


def _inertial(body, link) -> None:
    i = link.inertial
    if i is None or i.mass <= 0:  # massless frames: a negligible mass so MuJoCo accepts a moving body
        body.mass, body.inertia = 1e-9, [1e-12] * 3
        return
    ixx, ixy, ixz, iyy, iyz, izz = i.inertia
    body.ipos = list(i.com)
    body.mass = i.mass
    body.fullinertia = [ixx, iyy, izz, ixy, ixz, iyz]


PRIMITIVES = {"sphere": "mjGEOM_SPHERE", "box": "mjGEOM_BOX", "cylinder": "mjGEOM_CYLINDER",
              "capsule": "mjGEOM_CAPSULE"}


def _feet_geoms(body, link) -> None:
    """The link's primitive shapes (collision, else visual), massless and without contacts: where
    a free robot's feet touch the floor (:func:`stance`)."""
    mujoco = mj.load()

    for g in [g for g in link.collisions if g.shape.kind in PRIMITIVES] or [
            g for g in link.visuals if g.shape.kind in PRIMITIVES]:
        s = g.shape
        size = ([v / 2 for v in s.size] if s.kind == "box" else [s.radius, s.length / 2, 0] if s.length
                else [s.radius, 0, 0])
        pose = g.pose
        body.add_geom(type=getattr(mujoco.mjtGeom, PRIMITIVES[s.kind]), size=size, pos=list(pose.xyz),
                      quat=list(rpy_quat(pose.rpy)), contype=0, conaffinity=0, mass=0)


def stance(model, data) -> tuple[np.ndarray, np.ndarray]:
    """A free robot standing at the configuration in ``data`` (after mj_forward): its weight
    shared by its lowest leaf bodies (the feet, within 1 cm of the lowest), each foot's share
    pushing up at its lowest point.  Returns (the inertia of the body's share reflected at each
    dof: m |J_foot column|^2, the torque each dof holds: |J_foot^T F|)."""
    mujoco = mj.load()

    parents = set(int(p) for p in model.body_parentid[1:])
    leaves = [b for b in range(1, model.nbody) if b not in parents]
    points = {}
    for b in leaves:
        geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == b]
        if geoms:
            g = min(geoms, key=lambda g: data.geom_xpos[g][2] - model.geom_rbound[g])
            points[b] = data.geom_xpos[g] - np.array([0, 0, model.geom_rbound[g]])
        else:
            points[b] = data.xipos[b].copy()
    low = min(p[2] for p in points.values()) if points else 0.0
    feet = [b for b, p in points.items() if p[2] <= low + 0.01]
    mass = float(np.sum(model.body_mass)) / max(len(feet), 1)
    inertia, torque = np.zeros(model.nv), np.zeros(model.nv)
    jacp = np.zeros((3, model.nv))
    for b in feet:
        mujoco.mj_jac(model, data, jacp, None, points[b], b)
        inertia += mass * (jacp ** 2).sum(axis=0)
        torque += np.abs(jacp[2] * mass * 9.81)
    return inertia, torque


def configurations(robot: Robot, model, samples: int = SAMPLES, seed: int = SEED) -> np.ndarray:
    """The configurations the tuner looks at (rows of qpos): zero, the named poses, each actuated
    joint's range swept (9 points) with the others at each pose, and seeded random samples."""
    mujoco = mj.load()

    joints = {j.name: j for j in robot.joints if j.type in ACTUATED}
    adr = {name: int(model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)])
           for name in joints}
    bases = [np.zeros(model.nq)]
    for pose in robot.poses:
        q = np.zeros(model.nq)
        for name, value in pose.values:
            q[adr[name]] = value
        bases.append(q)
    rows = list(bases)
    for name, j in joints.items():
        lo, hi = _free_angle_range(j)
        for q0 in bases:
            for v in np.linspace(lo, hi, 9):
                q = q0.copy()
                q[adr[name]] = v
                rows.append(q)
    rng = np.random.default_rng(seed)
    for _ in range(samples):
        q = np.zeros(model.nq)
        for name, j in joints.items():
            q[adr[name]] = rng.uniform(*_free_angle_range(j))
        rows.append(q)
    return np.array(rows)


def inertia_and_gravity(model, qs: np.ndarray, standing: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(min of diag M, max of diag M, max |gravity torque|) per dof over the configurations ``qs``;
    the first ``standing`` of them are also taken standing on the feet (:func:`stance`)."""
    mujoco = mj.load()

    data = mujoco.MjData(model)
    full = np.zeros((model.nv, model.nv))
    diag = np.empty((len(qs) + standing, model.nv))
    grav = np.empty((len(qs) + standing, model.nv))
    for k, q in enumerate(qs):
        data.qpos[:] = q
        data.qvel[:] = 0
        mujoco.mj_forward(model, data)
        mujoco.mj_fullM(model, data, full)
        diag[k] = np.diag(full)
        grav[k] = data.qfrc_bias
        if k < standing:
            extra, torque = stance(model, data)
            diag[len(qs) + k] = diag[k] + extra
            grav[len(qs) + k] = torque
    return diag.min(axis=0), diag.max(axis=0), np.abs(grav).max(axis=0)


def tune(robot: Robot, timesteps: dict[str, float] | None = None) -> dict:
    """report.json's ``actuators``: per drive its inertia, gains and their reasons, and the
    stability, saturation and sag checks at each simulator's time step."""
    mujoco = mj.load()

    timesteps = timesteps or TIMESTEPS
    model = dynamics_model(robot)
    qs = configurations(robot, model)
    fixed = robot.root == "world" or robot.base == "fixed"
    # a free robot also stands on its feet at the zero pose and the named poses
    j_min, j_max, g_max = inertia_and_gravity(model, qs, 0 if fixed else 1 + len(robot.poses))
    joints = {j.name: j for j in robot.joints}
    drives = {}
    for a in robot.actuators:
        dof = int(model.jnt_dofadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, a.joint)])
        drives[a.joint] = drive_entry(a, joints[a.joint], float(j_min[dof]), float(j_max[dof]),
                                      float(g_max[dof]), timesteps)
    gravcomp = fixed and any(d.get("needs_gravcomp") and d["source"] == "auto" for d in drives.values())
    for d in drives.values():
        d["gravcomp"] = gravcomp
        _sag_notes(d, gravcomp, fixed)
    return {"method": ("diagonal of MuJoCo's joint-space mass matrix (armature included) and gravity torques "
                       f"over {len(qs)} configurations ({SAMPLES} seeded random samples, seed {SEED}, the zero "
                       "pose, the named poses, each joint's range swept), the base held"
                       + ("" if fixed else "; and standing: the robot's weight shared by its lowest leaf bodies "
                          "at the zero pose and the named poses, its share reflected at each joint")),
            "timesteps": timesteps, "gravcomp": gravcomp, "drives": drives}


def drive_entry(a, j, j_min: float, j_max: float, g_max: float, timesteps: dict[str, float]) -> dict:
    """One drive's numbers: inertia, gains (auto or given), and the checks."""
    kind = "prismatic" if j.type == "prismatic" else "revolute"
    effort = j.limit.effort if j.limit is not None and j.limit.effort else None
    rng = (j.limit.upper - j.limit.lower) if j.limit is not None and j.limit.lower is not None else None
    step = min(rng / 10, REFERENCE_STEP[kind]) if rng else REFERENCE_STEP[kind]
    entry = {"interface": a.interface, "inertia": {"min": j_min, "max": j_max}, "armature": a.armature,
             "gravity_torque_max": g_max, "effort": effort, "reference_step": step, "notes": []}
    zeta = a.damping_ratio
    if a.interface == "effort":
        entry.update(source="none", p=0.0, i=0.0, d=0.0)
        return entry
    w, why = _bandwidth(a, j_min, j_max, g_max, effort, step, timesteps)
    auto = _auto_gains(a.interface, j_max, w, zeta)
    damping = j.dynamics.damping if j.dynamics is not None else 0.0
    if a.interface == "velocity" and auto[0] < DAMPING_DOMINANCE * damping:  # else it never reaches its speed
        auto = (_sig(DAMPING_DOMINANCE * damping), 0.0)
        why += (f"; kv raised to {DAMPING_DOMINANCE:g}x the joint's damping, so the drive reaches 99 % of its "
                "target speed against it")
    if a.auto:
        entry.update(source="auto", bandwidth_hz=w / (2 * math.pi), bandwidth_reason=why, damping_ratio=zeta,
                     p=auto[0], i=a.i, d=auto[1])
    else:
        entry.update(source="recipe", p=a.p, i=a.i, d=a.d,
                     auto_would_give={"p": auto[0], "d": auto[1], "bandwidth_hz": w / (2 * math.pi)})
    entry.update(_checks(entry, j_min, timesteps, kind))
    return entry


def _bandwidth(a, j_min: float, j_max: float, g_max: float, effort: float | None, step: float,
               timesteps: dict[str, float]) -> tuple[float, str]:
    if a.bandwidth is not None:
        return 2 * math.pi * a.bandwidth, "the recipe's bandwidth"
    limits = {f"at most {MAX_BANDWIDTH_HZ:g} Hz": 2 * math.pi * MAX_BANDWIDTH_HZ,
              f"w dt <= {MAX_W_DT:g} at the largest time step ({max(timesteps.values()):.4g} s)":
                  MAX_W_DT / max(timesteps.values())}
    explicit = [dt for sim, dt in timesteps.items() if not IMPLICIT_DAMPING[sim]]
    if explicit and j_min > 0:  # explicit damping: kd dt / J_min (kv for a velocity drive) within the bound
        per_w = 2 * a.damping_ratio * j_max if a.interface == "position" else j_max  # kd / w, kv / w
        limits[f"kv dt / J_min <= {MAX_KV_DT_OVER_M:g} at the explicit time step ({max(explicit):.4g} s)"] = (
            MAX_KV_DT_OVER_M * j_min / (per_w * max(explicit)))
    if effort:
        spare = max(effort - g_max, 0.1 * effort)
        if a.interface == "position":
            limits["a reference step of %.3g within the effort limit against gravity" % step] = math.sqrt(
                spare / (j_max * step))
    why = min(limits, key=limits.get)
    return limits[why], why


def _auto_gains(interface: str, j: float, w: float, zeta: float) -> tuple[float, float]:
    """(p, d), to four significant digits (the same numbers in every file)."""
    if interface == "velocity":
        return _sig(j * w), 0.0
    return _sig(j * w * w), _sig(2 * zeta * j * w)


def _sig(x: float) -> float:
    return float(f"{x:.4g}")


def _checks(entry: dict, j_min: float, timesteps: dict[str, float], kind: str) -> dict:
    """Stability at each simulator's time step, saturation, sag under gravity."""
    p, d = entry["p"], entry["d"]
    kv = d if entry["interface"] == "position" else p
    w_max = math.sqrt(p / j_min) if entry["interface"] == "position" and j_min > 0 else 0.0
    stability = {}
    for sim, dt in timesteps.items():
        kv_dt_m = kv * dt / j_min if j_min > 0 else math.inf
        ok = w_max * dt < STABLE_W_DT and (IMPLICIT_DAMPING[sim] or kv_dt_m < STABLE_KV_DT_OVER_M)
        stability[sim] = {"timestep": dt, "w_dt": w_max * dt, "kv_dt_over_m": kv_dt_m, "stable": ok}
    out = {"stability": stability}
    g, effort = entry["gravity_torque_max"], entry["effort"]
    if entry["interface"] == "position":
        peak = p * entry["reference_step"] + g
        out["peak_effort"] = peak
        out["saturates"] = bool(effort and peak > effort * (1 + 1e-3))  # 1e-3: the gains' four digits
        out["sag"] = g / p if p > 0 else math.inf
        out["needs_gravcomp"] = out["sag"] > SAG_TOLERANCE[kind]
    return out


def _sag_notes(d: dict, gravcomp: bool, fixed: bool) -> None:
    if not d.get("needs_gravcomp"):
        return
    if d["source"] == "recipe" and not gravcomp:
        d["notes"].append("sag under gravity above tolerance with the recipe's gains: raise p, add i, or use "
                          "gains: auto (which compensates gravity in the MJCF)")
        return
    if gravcomp:
        d["notes"].append("sag under gravity above tolerance: MJCF compensates gravity (gravcomp); the ROS "
                          "controllers need an integral term or a gravity feed-forward to hold the pose")
    elif not fixed:
        d["notes"].append("sag under gravity above tolerance with a free base: no gravity compensation is "
                          "written (it would lift the base); an integral term or feed-forward is needed")


def apply(robot: Robot, report: dict) -> Robot:
    """The robot with the tuner's gains (``gains: auto``) and gravity compensation, and the report
    kept as JSON for report.json."""
    drives = report["drives"]
    acts = tuple(replace(a, p=drives[a.joint]["p"], d=drives[a.joint]["d"],
                         gravcomp=bool(drives[a.joint].get("gravcomp"))) if a.joint in drives else a
                 for a in robot.actuators)
    return replace(robot, actuators=acts, drive_report=json.dumps(report, sort_keys=True))
