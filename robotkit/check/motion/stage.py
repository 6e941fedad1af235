"""The ``motion`` stage of ``robotkit check``: every drive an MJCF declares, stepped from its
named poses in MuJoCo (the MJCF as written) and, when there is a URDF, PyBullet and Drake.

The drives are read from the MJCF through MuJoCo itself (:func:`drives_from_mjcf`), so the stage
works on any MJCF, imported ones included.  Each drive steps by a tenth of its joint's range
(at most 0.2 rad, 2 cm for a slide joint) towards the middle of the range, from each of the
first :data:`MAX_POSES` poses; a 2 s run with no step in MuJoCo (the file's own integrator)
is the hold test.  The three simulators run at once, one worker process each.

Besides the runs, the explicit-integration criteria are evaluated at every pose from MuJoCo's
mass matrix M (joint diagonal, armature included): kv*dt/M > 2 diverges with MuJoCo's Euler
(actuator damping is explicit there; joint damping is implicit unless ``eulerdamp`` is off),
and w*dt = sqrt(kp/M)*dt > 2 diverges in any of MuJoCo's integrators (stiffness is always
explicit) unless an implicit integrator damps it (kv*dt/M >= 1)."""

from __future__ import annotations

import math
import time
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from robotkit import mj
from robotkit.check import programs
from robotkit.check.findings import Finding
from robotkit.check.motion.law import Drive, Step
from robotkit.check.motion.metrics import metrics

STAGE = "motion"
SIMULATORS = ("mujoco", "pybullet", "drake")
PACKAGES = {"mujoco": "mujoco", "pybullet": "pybullet", "drake": "drake"}  # what pip installs
PROGRAMS = {"mujoco": "MuJoCo", "pybullet": "PyBullet", "drake": "Drake"}
MAX_POSES = 3
STEP_FRACTION = 0.1  # of the joint's range
MAX_STEP = {"hinge": 0.2, "slide": 0.02}  # rad, m
STEP_SECONDS = 1.0  # at least; a slow drive runs until it should have settled (MAX_STEP_SECONDS at most)
MAX_STEP_SECONDS = 4.0
HOLD_SECONDS = 2.0
TRACE_POINTS = 100
EXPLICIT_LIMIT = 2.0  # kv*dt/M or w*dt beyond which explicit integration diverges
REACH = 0.02  # final error beyond 2 % of the step: never reaches the target
OVERSHOOT = 0.20
SATURATED = 0.10
CHATTER = 5  # sign changes of the acceleration over the last half of a velocity step
RISE_AGREE = 0.15  # rise time within 15 % of MuJoCo's
FINAL_AGREE = 0.01  # final error within 1 % of the step of MuJoCo's
HOLD_DRIFT = 0.1  # of the step: a hold that drifts further is a warning (further than the step: an error)
INTEGRATORS = {0: "Euler", 1: "RK4", 2: "implicit", 3: "implicitfast"}


@dataclass
class Plan:
    """What the stage runs: the drives, the poses, the steps and the static figures."""
    mjcf: Path
    urdf: Path | None
    package_dirs: dict[str, Path]
    drives: list[Drive]
    poses: dict[str, dict[str, float]]
    integrator: str
    timestep: float
    kinds: dict[str, str] = field(default_factory=dict)  # joint: hinge | slide
    steps: list[tuple[str, Step, float]] = field(default_factory=list)  # (pose, step, start value)
    figures: dict[tuple[str, str], dict] = field(default_factory=dict)  # (joint, pose): M, kv*dt/M, w*dt, sag
    not_checked: list[dict] = field(default_factory=list)


def drives_from_mjcf(path: Path) -> tuple[list[Drive], dict[str, dict[str, float]], str, float]:
    """(drives, poses, integrator, time step) of an MJCF, read through MuJoCo as written."""
    plan = read_plan(path)
    return plan.drives, plan.poses, plan.integrator, plan.timestep


def read_plan(path: Path, urdf: Path | None = None, package_dirs: dict | None = None, model=None) -> Plan:
    """The plan of the stage on the MJCF ``path`` (``model``: it compiled already, if it is)."""
    mujoco = mj.load()

    model = mujoco.MjModel.from_xml_path(str(path)) if model is None else model
    kinds = {int(mujoco.mjtJoint.mjJNT_HINGE): "hinge", int(mujoco.mjtJoint.mjJNT_SLIDE): "slide"}
    drives, kind_of, not_checked = [], {}, []
    for a in range(model.nu):
        name = model.actuator(a).name or f"actuator {a}"
        drive, why = actuator_drive(model, a, kinds, mujoco)
        if drive is not None and drive.joint in kind_of:
            drive, why = None, f"joint '{drive.joint}' already has a drive"
        if drive is None:
            not_checked.append({"actuator": name, "why": why})
            continue
        drives.append(drive)
        kind_of[drive.joint] = kinds[int(model.jnt_type[model.joint(drive.joint).id])]
    integrator = INTEGRATORS.get(int(model.opt.integrator), str(int(model.opt.integrator)))
    plan = Plan(Path(path), urdf, dict(package_dirs or {}), drives, poses(model, kinds), integrator,
                float(model.opt.timestep), kind_of, not_checked=not_checked)
    plan.figures = static_figures(model, plan, mujoco)
    plan.steps = plan_steps(model, plan)
    return plan


def actuator_drive(model, a: int, kinds: dict[int, str], mujoco) -> tuple[Drive | None, str]:
    """The drive of actuator ``a``, or None and why it is not checked."""
    if int(model.actuator_trntype[a]) != int(mujoco.mjtTrn.mjTRN_JOINT):
        return None, "not on a joint (tendon, site or body transmission)"
    if not np.allclose(model.actuator_gear[a], [1, 0, 0, 0, 0, 0]):
        return None, f"gear {model.actuator_gear[a][0]:g}, not 1"
    j = int(model.actuator_trnid[a][0])
    if int(model.jnt_type[j]) not in kinds:
        return None, "not on a hinge or slide joint"
    if int(model.actuator_dyntype[a]) != int(mujoco.mjtDyn.mjDYN_NONE):
        return None, "has activation dynamics"
    g, b = model.actuator_gainprm[a], model.actuator_biasprm[a]
    fixed = int(model.actuator_gaintype[a]) == int(mujoco.mjtGain.mjGAIN_FIXED)
    bias = int(model.actuator_biastype[a])
    if not fixed:
        return None, "its gain is not fixed"
    if bias == int(mujoco.mjtBias.mjBIAS_NONE):
        interface, kp, kd = ("effort", 0.0, 0.0) if math.isclose(g[0], 1.0) else (None, 0.0, 0.0)
    elif bias == int(mujoco.mjtBias.mjBIAS_AFFINE) and b[0] == 0 and g[0] > 0 and math.isclose(b[1], -g[0]):
        interface, kp, kd = "position", float(g[0]), float(-b[2])
    elif bias == int(mujoco.mjtBias.mjBIAS_AFFINE) and b[0] == 0 and b[1] == 0 and math.isclose(b[2], -g[0]):
        interface, kp, kd = "velocity", float(g[0]), 0.0
    else:
        interface = None
    if interface is None:
        return None, "neither a position, a velocity nor a motor actuator"
    return Drive(model.joint(j).name, interface, kp, kd, armature=float(model.dof_armature[model.jnt_dofadr[j]]),
                 effort=effort(model, a, j), gravcomp=gravity_compensated(model, j)), ""


def effort(model, a: int, j: int) -> float | None:
    """The smallest force limit on the joint's actuator: the joint's actuatorfrcrange, the actuator's forcerange."""
    limits = [max(abs(x) for x in model.jnt_actfrcrange[j])] if model.jnt_actfrclimited[j] else []
    if model.actuator_forcelimited[a]:
        limits.append(max(abs(x) for x in model.actuator_forcerange[a]))
    return float(min(limits)) if limits else None


def gravity_compensated(model, j: int) -> bool:
    """The joint's actuator carries gravity compensation: actuatorgravcomp and gravcomp bodies below it."""
    if not model.jnt_actgravcomp[j]:
        return False
    body = int(model.jnt_bodyid[j])
    below = [b for b in range(model.nbody) if is_below(model, b, body)]
    return any(model.body_gravcomp[b] > 0 for b in below)


def is_below(model, b: int, ancestor: int) -> bool:
    while b > 0:
        if b == ancestor:
            return True
        b = int(model.body_parentid[b])
    return ancestor == 0


def poses(model, kinds: dict[int, str]) -> dict[str, dict[str, float]]:
    """{keyframe name: {hinge or slide joint: value}}; {"zero": {}} without keyframes."""
    out = {}
    for k in range(model.nkey):
        name = model.key(k).name or f"key {k}"
        out[name] = {model.joint(j).name: float(model.key_qpos[k][model.jnt_qposadr[j]])
                     for j in range(model.njnt) if int(model.jnt_type[j]) in kinds}
    return out or {"zero": {}}


def plan_steps(model, plan: Plan) -> list[tuple[str, Step, float]]:
    """(pose, step, start) for every stepped drive from each of the first MAX_POSES poses."""
    out = []
    for pose in list(plan.poses)[:MAX_POSES]:
        start = plan.poses[pose]
        for d in plan.drives:
            if d.interface == "effort":
                continue
            j = model.joint(d.joint).id
            q0 = start.get(d.joint, float(model.qpos0[model.jnt_qposadr[j]]))
            size = MAX_STEP[plan.kinds[d.joint]]
            direction = 1.0
            if model.jnt_limited[j]:
                lo, hi = (float(x) for x in model.jnt_range[j])
                size = min(size, STEP_FRACTION * (hi - lo))
                direction = 1.0 if q0 <= (lo + hi) / 2 else -1.0
            full = {**start, d.joint: q0}
            seconds = step_seconds(plan.figures[(d.joint, pose)], d.interface)
            if d.interface == "velocity":  # travels about one step in STEP_SECONDS
                out.append((pose, Step(d.joint, full, direction * size / STEP_SECONDS, seconds), 0.0))
            else:
                out.append((pose, Step(d.joint, full, q0 + direction * size, seconds), q0))
    return out


def step_seconds(figure: dict, interface: str) -> float:
    """How long a step runs: 1.5 x the time its slowest mode takes to decay to 1 % (4.6 time
    constants), from M, kp and kv at the pose, within [STEP_SECONDS, MAX_STEP_SECONDS]."""
    M, kp, kv = figure["M"], figure["kp"], figure["kv"]
    if interface == "velocity":
        rate = kv / M if M > 0 else 0.0
    elif kp > 0 and M > 0:
        w, zeta = math.sqrt(kp / M), kv / (2 * math.sqrt(kp * M))
        rate = zeta * w if zeta <= 1 else w * (zeta - math.sqrt(zeta * zeta - 1))
    else:
        rate = 0.0
    if rate <= 0:
        return STEP_SECONDS
    return min(max(1.5 * 4.6 / rate, STEP_SECONDS), MAX_STEP_SECONDS)


def static_figures(model, plan: Plan, mujoco) -> dict[tuple[str, str], dict]:
    """Per (joint, pose): M (the joint's diagonal of the mass matrix, armature included), kv
    (the actuator's, plus the joint's damping where MuJoCo integrates it explicitly), kv*dt/M
    and w*dt at the MJCF's time step, and the gravity torque at the pose."""
    data = mujoco.MjData(model)
    full = np.zeros((model.nv, model.nv))
    explicit_joint_damping = plan.integrator in ("RK4",) or (
        plan.integrator == "Euler" and model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP))
    out = {}
    for pose in list(plan.poses)[:MAX_POSES]:
        mujoco.mj_resetData(model, data)
        for name, value in plan.poses[pose].items():
            data.qpos[model.jnt_qposadr[model.joint(name).id]] = value
        mujoco.mj_forward(model, data)
        mujoco.mj_fullM(model, data, full)
        data.qvel[:] = 0.0
        mujoco.mj_forward(model, data)
        for d in plan.drives:
            j = model.joint(d.joint).id
            dof = int(model.jnt_dofadr[j])
            M = float(full[dof, dof])
            kv = d.kd if d.interface == "position" else d.kp if d.interface == "velocity" else 0.0
            if explicit_joint_damping:
                kv += float(model.dof_damping[dof])
            kp = d.kp if d.interface == "position" else 0.0
            out[(d.joint, pose)] = {"M": M, "kv": kv, "kp": kp, "dt": plan.timestep,
                                    "kv_dt_M": kv * plan.timestep / M, "w_dt": math.sqrt(kp / M) * plan.timestep,
                                    "gravity": float(data.qfrc_bias[dof])}
    return out


# ---- the runs (one worker process per simulator) ----

def run_simulator(simulator: str, plan: Plan) -> dict:
    """Every step of ``plan`` in one simulator: {"runs": [...], "wall": s, "error": str | None}."""
    t0 = time.perf_counter()
    out = {"runs": [], "error": None, "hold": {}}
    try:
        simulate = load_simulator(simulator)
    except ImportError as exc:
        out["error"] = f"not installed: {exc}"
        return out
    drives = [replace(d, gravcomp=False) for d in plan.drives] if simulator == "mujoco" else plan.drives
    for pose, step, start in plan.steps:
        t = time.perf_counter()
        try:
            if simulator == "mujoco":  # the file compensates gravity itself (body gravcomp), as written
                trace = simulate(plan.mjcf, drives, step)
            else:
                trace = simulate(plan.urdf, drives, step, plan.package_dirs)
        except Exception as exc:  # the simulator refused this robot: reported, the others still run
            out["runs"].append({"pose": pose, "joint": step.joint, "refused": f"{type(exc).__name__}: {exc}"})
            continue
        out["runs"].append(summarize(trace, pose, step, start, plan, time.perf_counter() - t))
    if simulator == "mujoco":
        out["hold"] = {pose: hold(plan, pose) for pose in list(plan.poses)[:MAX_POSES]}
    out["wall"] = time.perf_counter() - t0
    return out


def load_simulator(simulator: str):
    """The simulator's function; ImportError when its program is not installed."""
    if simulator == "mujoco":
        mj.load()  # ImportError when it is not installed
        from robotkit.check.motion.mujoco_sim import simulate_mujoco
        return simulate_mujoco
    if simulator == "pybullet":
        from robotkit.ioutil import quiet

        with quiet():  # it prints its build banner
            import pybullet  # noqa: F401

        from robotkit.check.motion.pybullet_sim import simulate_pybullet
        return simulate_pybullet
    import pydrake  # noqa: F401

    from robotkit.check.motion.drake_sim import simulate_drake
    return simulate_drake


def summarize(trace, pose: str, step: Step, start: float, plan: Plan, wall: float) -> dict:
    drive = next(d for d in plan.drives if d.joint == step.joint)
    m = metrics(trace, start, step.target, drive.interface, effort=drive.effort)
    keep = np.linspace(0, len(trace.t) - 1, min(TRACE_POINTS, len(trace.t))).round().astype(int) \
        if len(trace.t) else np.zeros(0, dtype=int)
    x = trace.qd if drive.interface == "velocity" else trace.q
    return {"pose": pose, "joint": step.joint, "start": start, "target": step.target, "timestep": trace.timestep,
            **m, "others_max_dev": trace.others_max_dev, "diverged": trace.diverged, "warnings": trace.warnings,
            "wall": wall, "trace": {"t": trace.t[keep].tolist(), "q": x[keep].tolist()}}


def hold(plan: Plan, pose: str) -> dict:
    """The MJCF as written, base held and contacts off, from ``pose`` with every position target
    at the pose, stepped HOLD_SECONDS with its own integrator: {joint: max |q - q0|}, divergence."""
    mujoco = mj.load()

    from robotkit.check.motion.mujoco_sim import hold as hold_base

    spec = mujoco.MjSpec.from_file(str(plan.mjcf))
    hold_base(spec, mujoco)
    for key in list(spec.keys):
        spec.delete(key)
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    model = spec.compile()
    data = mujoco.MjData(model)
    values = plan.poses[pose]
    for name, value in values.items():
        data.qpos[model.jnt_qposadr[model.joint(name).id]] = value
    for a in range(model.nu):
        j = int(model.actuator_trnid[a][0])
        if int(model.actuator_biastype[a]) == int(mujoco.mjtBias.mjBIAS_AFFINE) and model.actuator_biasprm[a][1] != 0:
            data.ctrl[a] = float(data.qpos[model.jnt_qposadr[j]])
    adr = {d.joint: int(model.jnt_qposadr[model.joint(d.joint).id]) for d in plan.drives}
    q0 = {n: float(data.qpos[a]) for n, a in adr.items()}
    drift = dict.fromkeys(adr, 0.0)
    diverged = None
    for i in range(int(round(HOLD_SECONDS / model.opt.timestep))):
        mujoco.mj_step(model, data)
        if not np.isfinite(data.qvel).all() or np.abs(data.qvel).max(initial=0.0) > 1e3:
            diverged = f"diverged at t={(i + 1) * model.opt.timestep:.4g} s"
            break
        for n, a in adr.items():
            drift[n] = max(drift[n], abs(float(data.qpos[a]) - q0[n]))
    return {"drift": drift, "diverged": diverged}


# ---- the stage ----

class MotionRun:
    """The stage started: the simulators run in worker processes while the caller does other
    work; :meth:`finish` waits for them and gives (findings, results)."""

    def __init__(self, mjcf: Path, urdf: Path | None, package_dirs: dict[str, Path],
                 simulators: tuple[str, ...] = SIMULATORS, cached=None, model=None):
        """``cached``: a :class:`robotkit.check.cache.StageCache` of the build folder the files are
        in (each simulator's runs taken from it when there, stored in it when computed);
        ``model``: the MJCF compiled already, if it is."""
        import multiprocessing

        self.t0 = time.perf_counter()
        self.plan = read_plan(Path(mjcf), urdf, package_dirs, model)
        self.simulators = [s for s in simulators if s == "mujoco" or urdf is not None]
        self.skipped = [s for s in simulators if s not in self.simulators]
        self.futures: dict[str, Future] = {}
        self.cached, self.pool, self.missed = cached, None, {}
        if not self.plan.steps:
            return
        hits = {s: cached.get(f"{STAGE} {s}") if cached else None for s in self.simulators}
        for s, hit in hits.items():
            if hit is not None:
                self.futures[s] = Future()
                self.futures[s].set_result(hit)
        missed = [s for s in self.simulators if hits[s] is None]
        if missed:
            context = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else None)
            self.pool = ProcessPoolExecutor(max_workers=len(missed), mp_context=context)
            with programs.SPAWN:  # forked while no program is being started (robotkit.check.programs.SPAWN)
                self.missed = {s: self.pool.submit(run_simulator, s, self.plan) for s in missed}
            self.futures.update(self.missed)
            self.futures = {s: self.futures[s] for s in self.simulators}  # in the simulators' order

    def finish(self) -> tuple[list[Finding], dict]:
        runs = {}
        for s, future in self.futures.items():
            try:
                runs[s] = future.result()
            except Exception as exc:  # the worker itself failed (a crash in the program)
                runs[s] = {"runs": [], "hold": {}, "error": f"{type(exc).__name__}: {exc}"}
            else:
                if self.cached and s in self.missed and not runs[s].get("error"):
                    self.cached.put(f"{STAGE} {s}", runs[s])  # computed and whole: kept for the same files
        if self.pool is not None:
            self.pool.shutdown()
        results = assemble(self.plan, runs, self.skipped)
        results["wall"] = time.perf_counter() - self.t0
        return findings(self.plan, runs, results), results


def motion_stage(mjcf: Path, urdf: Path | None, package_dirs: dict[str, Path],
                 simulators: tuple[str, ...] = SIMULATORS) -> tuple[list[Finding], dict]:
    """The stage's (findings, results) on an MJCF (and the URDF of the same robot, if any)."""
    return MotionRun(mjcf, urdf, package_dirs, simulators).finish()


def has_actuators(mjcf: Path) -> bool:
    """Whether the MJCF declares an actuator (the stage runs only then)."""
    return compiled(mjcf).nu > 0


def compiled(mjcf: Path):
    """The MJCF compiled by MuJoCo (its MjModel)."""
    return mj.load().MjModel.from_xml_path(str(mjcf))


def assemble(plan: Plan, runs: dict[str, dict], skipped: list[str]) -> dict:
    """The results: per joint, per pose, per simulator; per simulator totals."""
    joints: dict[str, dict] = {}
    for d in plan.drives:
        joints[d.joint] = {"interface": d.interface, "kp": d.kp, "kv": d.kd if d.interface == "position" else
                           d.kp if d.interface == "velocity" else 0.0, "armature": d.armature, "effort": d.effort,
                           "gravcomp": d.gravcomp, "poses": {}}
        for pose in list(plan.poses)[:MAX_POSES]:
            f = plan.figures[(d.joint, pose)]
            hold_run = runs.get("mujoco", {}).get("hold", {}).get(pose, {})
            joints[d.joint]["poses"][pose] = {
                "M": f["M"], "kv_dt_M": f["kv_dt_M"], "w_dt": f["w_dt"], "gravity_torque": f["gravity"],
                "hold_drift": hold_run.get("drift", {}).get(d.joint), "hold_diverged": hold_run.get("diverged"),
                "simulators": {}}
    for s, r in runs.items():
        for run in r["runs"]:
            joints[run["joint"]]["poses"][run["pose"]]["simulators"][s] = {k: v for k, v in run.items()
                                                                            if k not in ("pose", "joint")}
    simulators = {s: {"status": "error" if r.get("error") else "ok", "error": r.get("error"),
                      "wall": r.get("wall"), "runs": len(r["runs"]),
                      "timestep": next((x["timestep"] for x in r["runs"] if "timestep" in x), None),
                      "wall_per_joint": {d.joint: sum(x.get("wall", 0.0) for x in r["runs"] if x["joint"] == d.joint)
                                         for d in plan.drives}}
                  for s, r in runs.items()}
    for s in skipped:
        simulators[s] = {"status": "not run", "error": "no URDF beside the MJCF: MuJoCo only"}
    return {"mjcf": str(plan.mjcf), "urdf": str(plan.urdf) if plan.urdf else None, "integrator": plan.integrator,
            "timestep": plan.timestep, "poses": list(plan.poses)[:MAX_POSES], "step_seconds": STEP_SECONDS,
            "simulators": simulators, "joints": joints, "not_checked": plan.not_checked}


# ---- findings ----

def units(plan: Plan, joint: str) -> tuple[str, str, str]:
    """(position, inertia, stiffness) units of ``joint``."""
    return ("m", "kg", "N/m") if plan.kinds.get(joint) == "slide" else ("rad", "kg m^2", "N m/rad")


def worst_pose(plan: Plan, joint: str, key: str) -> tuple[str, dict]:
    pose = max(list(plan.poses)[:MAX_POSES], key=lambda p: plan.figures[(joint, p)][key])
    return pose, plan.figures[(joint, pose)]


def instability(plan: Plan, joint: str, dt: float, implicit: bool) -> tuple[str, str] | None:
    """(figure, fix) when ``joint``'s drive is past the explicit limit at time step ``dt`` (None if
    not): w*dt when the stiffness is, kv*dt/M when the damping is (not counted with ``implicit``)."""
    pose = max(list(plan.poses)[:MAX_POSES], key=lambda p: max(plan.figures[(joint, p)]["kv_dt_M"],
                                                                plan.figures[(joint, p)]["w_dt"]))
    f = plan.figures[(joint, pose)]
    M, kv, kp = f["M"], f["kv"], f["kp"]
    kv_dt_m, w_dt = kv * dt / M, math.sqrt(kp / M) * dt
    _, inertia, stiffness = units(plan, joint)
    armature = next(d.armature for d in plan.drives if d.joint == joint)
    where = f"at pose '{pose}' (M {M:.3g} {inertia} incl. armature {armature:.3g}, dt {dt:.3g} s)"
    if w_dt > EXPLICIT_LIMIT and (kv_dt_m < 1 or not implicit):
        return (f"w*dt = sqrt(kp/M)*dt = {w_dt:.3g} > {EXPLICIT_LIMIT:g} {where}, kp {kp:.4g} {stiffness}",
                f"add armature (about {kp * dt * dt - M:.3g} {inertia} brings w*dt to 1) or lower kp to "
                f"{M / dt / dt:.3g} {stiffness}, or shorten the time step to {math.sqrt(M / kp):.3g} s")
    if kv_dt_m > EXPLICIT_LIMIT and not implicit:
        return (f"kv*dt/M = {kv_dt_m:.3g} > {EXPLICIT_LIMIT:g} {where}, kv {kv:.4g}",
                f"add armature (about {kv * dt - M:.3g} {inertia} brings kv*dt/M to 1) or lower kv to "
                f"{M / dt:.3g}, or use integrator implicitfast")
    return None


def static_findings(plan: Plan, runs: dict[str, dict]) -> list[Finding]:
    """The explicit-integration criteria at the MJCF's own integrator and time step.  An implicit
    integrator takes a drive's damping implicitly only while its force is within the force range:
    a saturated step is explicit again, so kv*dt/M > 2 with a saturated, overshooting MuJoCo step
    is an error too (a warning without that evidence)."""
    out = []
    implicit = plan.integrator in ("implicit", "implicitfast")
    for d in plan.drives:
        found = instability(plan, d.joint, plan.timestep, implicit)
        if found:
            out.append(Finding("error", STAGE, f"joint '{d.joint}'", f"unstable with integrator {plan.integrator}: "
                               f"{found[0]}: explicit integration diverges", found[1]))
            continue
        pose, f = worst_pose(plan, d.joint, "kv_dt_M")
        if not implicit or f["kv_dt_M"] <= EXPLICIT_LIMIT:
            continue
        bad = [r for r in runs.get("mujoco", {}).get("runs", []) if r["joint"] == d.joint and not r.get("refused")
               and (r.get("saturated") or 0) > 0 and (r.get("overshoot") or 0) > OVERSHOOT]
        _, inertia, _ = units(plan, d.joint)
        figure = (f"kv*dt/M = {f['kv_dt_M']:.3g} > {EXPLICIT_LIMIT:g} at pose '{pose}' (kv {f['kv']:.4g}, M "
                  f"{f['M']:.3g} {inertia} incl. armature {d.armature:.3g}, dt {plan.timestep:.3g} s)")
        fix = (f"add armature (about {f['kv'] * plan.timestep - f['M']:.3g} {inertia} brings kv*dt/M to 1) or lower "
               f"kv to {f['M'] / plan.timestep:.3g}")
        if bad:
            worst = max(bad, key=lambda r: r["overshoot"])
            out.append(Finding("error", STAGE, f"joint '{d.joint}'", f"unstable at its force limit: {figure}; "
                               f"integrator {plan.integrator} takes the damping implicitly only within the force "
                               f"range, and the step from pose '{worst['pose']}' saturates and overshoots by "
                               f"{100 * worst['overshoot']:.3g} % in MuJoCo", fix))
        elif d.interface == "position":  # a velocity drive saturating is a drive at full torque, no overshoot
            out.append(Finding("warning", STAGE, f"joint '{d.joint}'", f"{figure}: stable only because integrator "
                               f"{plan.integrator} takes damping implicitly (within the force range); Euler "
                               "diverges", fix))
    return out


def findings(plan: Plan, runs: dict[str, dict], results: dict) -> list[Finding]:
    robot = f"robot '{plan.mjcf.stem}'"
    out = static_findings(plan, runs)
    unstable = {f.subject for f in out if f.severity == "error"}
    for s, r in runs.items():
        if r.get("error"):  # not installed: not checked, as the consumers stage says (the test suite installs all)
            missing = "not installed" in r["error"]
            out.append(Finding("warning" if missing else "error", STAGE, robot,
                               f"{PROGRAMS.get(s, s)}: not checked: {r['error']}" if missing else
                               f"{s} could not run the motion check: {r['error']}",
                               f"pip install {PACKAGES.get(s, s)}" if missing else ""))
        refused = sorted({x["refused"] for x in r["runs"] if "refused" in x})
        out += [Finding("error", STAGE, robot, f"{s} could not step the robot: {why}") for why in refused]
    out += divergence_findings(plan, runs)
    out += response_findings(plan, runs)
    out += agreement_findings(plan, runs)
    out += hold_findings(plan, runs, unstable)
    return out


def divergence_findings(plan: Plan, runs: dict[str, dict]) -> list[Finding]:
    """One error per joint to blame for the runs that diverged: the joints past the explicit
    limit at the simulator's time step, else the stepped joint."""
    blamed: dict[str, list[str]] = {}
    for s, r in runs.items():
        implicit = s == "drake" or (s == "mujoco" and plan.integrator in ("implicit", "implicitfast"))
        for run in r["runs"]:
            if not run.get("diverged"):
                continue
            culprits = [d.joint for d in plan.drives if instability(plan, d.joint, run["timestep"], implicit)]
            for j in culprits or [run["joint"]]:
                text = (f"{s} ({run['diverged']} stepping {run['joint']} from pose '{run['pose']}', "
                        f"dt {run['timestep']:.3g} s)")
                if not any(t.startswith(f"{s} ") for t in blamed.get(j, [])):
                    blamed.setdefault(j, []).append(text)
    out = []
    for j, where in blamed.items():
        dt = min(x["timestep"] for r in runs.values() for x in r["runs"] if "timestep" in x)
        found = instability(plan, j, dt, False)
        figure, fix = found or ("", "")
        if not found:
            pose, f = worst_pose(plan, j, "kv_dt_M")
            figure = f"kv*dt/M = {f['kv_dt_M']:.3g}, w*dt = {f['w_dt']:.3g} at pose '{pose}'"
        out.append(Finding("error", STAGE, f"joint '{j}'", f"unstable: diverged in {'; '.join(where)}; {figure}",
                           fix or "lower kv and kp, add armature or shorten the time step"))
    return out


def completed(runs: dict[str, dict]):
    """(simulator, run) of every run that finished without diverging."""
    for s, r in runs.items():
        for run in r["runs"]:
            if "refused" not in run and not run.get("diverged"):
                yield s, run


def response_findings(plan: Plan, runs: dict[str, dict]) -> list[Finding]:
    """Never reaching the target (error), overshoot, saturation, chatter, MuJoCo warnings (warnings);
    one finding per joint and kind, on its worst run."""
    worst: dict[tuple[str, str], tuple[float, Finding]] = {}

    def keep(joint: str, kind: str, score: float, severity: str, message: str, hint: str = "") -> None:
        if (joint, kind) not in worst or score > worst[(joint, kind)][0]:
            worst[(joint, kind)] = (score, Finding(severity, STAGE, f"joint '{joint}'", message, hint))

    drives = {d.joint: d for d in plan.drives}
    for s, run in completed(runs):
        j, d = run["joint"], drives[run["joint"]]
        size = abs(run["target"] - run["start"])
        unit = units(plan, j)[0] + ("/s" if d.interface == "velocity" else "")
        where = f"in {s} from pose '{run['pose']}'"
        if run["final_error"] is not None and run["final_error"] > REACH * size:
            f = plan.figures[(j, run["pose"])]
            predicted = abs(f["gravity"]) / f["kp"] if f["kp"] and not d.gravcomp else None
            sag = (f"the sag gravity torque / kp = {abs(f['gravity']):.3g} / {f['kp']:.4g} = {predicted:.3g} {unit}"
                   if predicted is not None else "gravity is compensated")
            # the sag the gains predict is a warning (the tuner reported it); an error it does not explain is not
            explained = predicted is not None and abs(run["final_error"] - predicted) <= 0.5 * predicted + 0.005 * size
            keep(j, "reach", run["final_error"] / size, "warning" if explained else "error",
                 f"{'sags under gravity' if explained else 'never reaches the target'} {where}: final error "
                 f"{run['final_error']:.3g} {unit} ({100 * run['final_error'] / size:.3g} % of the {size:.3g} "
                 f"{unit} step; tolerance {100 * REACH:g} %); {sag}",
                 "raise kp, add an integral term, or compensate gravity (actuatorgravcomp)" if not d.gravcomp else "")

        if run["overshoot"] is not None and run["overshoot"] > OVERSHOOT:
            keep(j, "overshoot", run["overshoot"], "warning", f"overshoots by {100 * run['overshoot']:.3g} % {where} "
                 f"(more than {100 * OVERSHOOT:g} %)", "raise kv (damping ratio 1: kv = 2 sqrt(kp M))")
        if run["saturated"] is not None and run["saturated"] > SATURATED:
            keep(j, "saturated", run["saturated"], "warning", f"at its force limit {d.effort:g} "
                 f"{100 * run['saturated']:.3g} % of the time {where} (more than {100 * SATURATED:g} %)")
        if d.interface == "velocity" and run["chatter"] is not None and run["chatter"] > CHATTER:
            keep(j, "chatter", run["chatter"], "warning", f"the velocity drive chatters {where}: its acceleration "
                 f"changes sign {run['chatter']} times in the last half of the run")
        for w in run["warnings"]:
            keep(j, "warned", 1.0, "warning", f"{w} stepping it {where}")
    return [f for _, f in worst.values()]


def agreement_findings(plan: Plan, runs: dict[str, dict]) -> list[Finding]:
    """PyBullet and Drake against MuJoCo: rise time within 15 % (when it spans ten time steps of both:
    a quicker rise is each program's step size), final error within 1 % of the step."""
    reference = {(run["joint"], run["pose"]): run for s, run in completed(runs) if s == "mujoco"}
    worst: dict[tuple[str, str], tuple[float, Finding]] = {}
    for s, run in completed(runs):
        ref = reference.get((run["joint"], run["pose"]))
        if s == "mujoco" or ref is None:
            continue
        j, size = run["joint"], abs(run["target"] - run["start"])
        where = f"from pose '{run['pose']}'"
        problems = []
        r, r0 = run["rise_time"], ref["rise_time"]
        resolved = 10 * max(run["timestep"], ref["timestep"])  # a rise within a few steps is each program's step
        if r is not None and r0 is not None and max(r, r0) < resolved:
            pass
        elif (r is None) != (r0 is None):
            problems.append((1.0, f"rise time {fmt(r)} in {s}, {fmt(r0)} in mujoco {where}"))
        elif r is not None and abs(r - r0) > RISE_AGREE * r0:
            problems.append((abs(r - r0) / r0, f"rise time {r:.3g} s in {s}, {r0:.3g} s in mujoco {where} "
                             f"({100 * (r - r0) / r0:+.3g} %; tolerance {100 * RISE_AGREE:g} %)"))
        e, e0 = run["final_error"], ref["final_error"]
        if abs(e - e0) > FINAL_AGREE * size:
            problems.append((abs(e - e0) / size, f"final error {e:.3g} in {s}, {e0:.3g} in mujoco {where} "
                             f"(differ by {100 * abs(e - e0) / size:.3g} % of the step; tolerance "
                             f"{100 * FINAL_AGREE:g} %)"))
        for score, text in problems:
            key = (j, s + text.split()[0])
            if key not in worst or score > worst[key][0]:
                worst[key] = (score, Finding("warning", STAGE, f"joint '{j}'", f"the simulators disagree: {text}"))
    return [f for _, f in worst.values()]


def hold_findings(plan: Plan, runs: dict[str, dict], unstable: set[str]) -> list[Finding]:
    """The 2 s hold in MuJoCo: a divergence (error, unless the joints to blame already have one),
    a drift past the step (error) or past a tenth of it (warning)."""
    out = []
    sizes = {(step.joint, pose): abs(step.target - start) if step.joint in plan.kinds else 0.0
             for pose, step, start in plan.steps}
    for pose, h in runs.get("mujoco", {}).get("hold", {}).items():
        if h.get("diverged"):
            if not unstable:
                out.append(Finding("error", STAGE, f"robot '{plan.mjcf.stem}'", f"does not hold pose '{pose}' in "
                                   f"MuJoCo with integrator {plan.integrator}: {h['diverged']}"))
            continue
        for j, drift in h["drift"].items():
            d = next(x for x in plan.drives if x.joint == j)
            size = sizes.get((j, pose)) or MAX_STEP[plan.kinds[j]]
            if d.interface != "position" or drift <= HOLD_DRIFT * size:
                continue
            severity = "error" if drift > size else "warning"
            out.append(Finding(severity, STAGE, f"joint '{j}'", f"drifts {drift:.3g} {units(plan, j)[0]} from "
                               f"pose '{pose}' in {HOLD_SECONDS:g} s with no step (MuJoCo, integrator "
                               f"{plan.integrator}; tolerance {100 * HOLD_DRIFT:g} % of its "
                               f"{size:.3g} step, an error past the step)"))
    return out


def fmt(x: float | None) -> str:
    return "never" if x is None else f"{x:.3g} s"
