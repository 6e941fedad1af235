"""The step response in PyBullet (DIRECT mode, the URDF's own inertia, TORQUE_CONTROL).

PyBullet integrates explicitly (semi-implicit Euler).  By default (``implicit``) the drive's
damping is integrated implicitly, as MuJoCo's implicitfast and Drake's PD controllers do: with
M from ``calculateMassMatrix`` and the bias h = ``calculateInverseDynamics(q, qd, 0)``, the
accelerations are qdd = (M + A + dt Kd)^-1 (tau_law - h) (A: the armature, Kd: kd of a position
drive, kv of a velocity drive) and the motor gives tau = tau_law - dt Kd qdd, clipped ("stable
PD", Tan, Liu and Turk 2011).  With ``implicit=False`` the law's torque is applied as it is, as a
hand-written torque loop would: then a large kd dt / inertia diverges here.

PyBullet has no armature.  It is put inside the control loop, exactly (computed torque): a
robot with armature A accelerates at qdd = (M + A)^-1 (tau - h); PyBullet is given
tau - A qdd, which makes its (armature-free) robot accelerate the same.  The recorded torque
is the motor's (tau, after the clip).  Gravity compensation is the same feed-forward:
``calculateInverseDynamics(q, 0, 0)`` at the current positions, inside the clip.  All three need a
held base: PyBullet's inverse dynamics of a free base raises (or gives zeros with flags=1), so
a free base with armature, gravity compensation or the implicit loop is refused with a ValueError."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from robotkit.check.motion.files import resolved_urdf
from robotkit.ioutil import quiet
from robotkit.check.motion.law import Drive, Recorder, Step, Trace, check_drives, clip, law, targets

NO_SPEED_CAP = 1e6


def simulate_pybullet(urdf: Path, drives: list[Drive], step: Step, package_dirs: dict[str, Path],
                      hold_base: bool = True, timestep: float = 1 / 240, implicit: bool = True) -> Trace:
    with quiet():  # heavy, and it prints its build banner
        import pybullet as p

    check_drives(drives, step)
    with tempfile.TemporaryDirectory() as tmp:
        path = resolved_urdf(urdf, package_dirs, Path(tmp))
        client = p.connect(p.DIRECT)
        try:
            with quiet():
                body = p.loadURDF(str(path), useFixedBase=hold_base, flags=p.URDF_USE_INERTIA_FROM_FILE,
                                  physicsClientId=client)
            rec = Recorder("pybullet", timestep, step, drives)
            run(p, client, body, drives, step, rec, hold_base, implicit and hold_base)
            return rec.trace()
        finally:
            p.disconnect(client)


def movable_joints(p, client: int, body: int) -> dict[str, int]:
    """{name: PyBullet joint index} of the revolute and prismatic joints, in index order."""
    out = {}
    for i in range(p.getNumJoints(body, physicsClientId=client)):
        info = p.getJointInfo(body, i, physicsClientId=client)
        if info[2] in (p.JOINT_REVOLUTE, p.JOINT_PRISMATIC):
            out[info[1].decode()] = i
    return out


def prepare(p, client: int, body: int, joints: dict[str, int], step: Step) -> None:
    """The start pose, no link damping, no speed cap, the default velocity motors off."""
    for link in range(-1, p.getNumJoints(body, physicsClientId=client)):
        p.changeDynamics(body, link, linearDamping=0.0, angularDamping=0.0, maxJointVelocity=NO_SPEED_CAP,
                         physicsClientId=client)
    for name, i in joints.items():
        p.resetJointState(body, i, step.start.get(name, 0.0), 0.0, physicsClientId=client)
    p.setJointMotorControlArray(body, list(joints.values()), p.VELOCITY_CONTROL,
                                forces=[0.0] * len(joints), physicsClientId=client)


def run(p, client: int, body: int, drives: list[Drive], step: Step, rec: Recorder, hold_base: bool,
        implicit: bool = True) -> None:
    joints = movable_joints(p, client, body)
    missing = [d.joint for d in drives if d.joint not in joints]
    if missing:
        raise ValueError(f"joints not movable in the URDF: {', '.join(missing)}")
    p.setGravity(0, 0, -9.81, physicsClientId=client)
    p.setTimeStep(timestep := rec.timestep, physicsClientId=client)
    prepare(p, client, body, joints, step)
    names = list(joints)
    column = {n: k for k, n in enumerate(names)}
    armature = np.array([next((d.armature for d in drives if d.joint == n), 0.0) for n in names])
    wanted = {d.joint: targets(d, step) for d in drives}
    kd = np.zeros(len(names))  # the velocity gain of each drive: integrated implicitly
    for d in drives:
        kd[column[d.joint]] = d.kd if d.interface == "position" else d.kp if d.interface == "velocity" else 0.0
    if not hold_base and (armature.any() or any(d.gravcomp for d in drives)):
        raise ValueError("PyBullet cannot give the armature or gravity compensation of a free base: its "
                         "calculateInverseDynamics raises on one (and returns zeros with flags=1); hold the base")
    damping = joint_damping(p, client, body, joints) if implicit else np.zeros(len(names))
    for i in range(rec.steps()):
        states = p.getJointStates(body, list(joints.values()), physicsClientId=client)
        q = [s[0] for s in states]
        qd = [s[1] for s in states]
        gravity = (p.calculateInverseDynamics(body, q, [0.0] * len(q), [0.0] * len(q), physicsClientId=client)
                   if any(d.gravcomp for d in drives) else [0.0] * len(q))
        tau = np.zeros(len(names))
        for d in drives:
            k = column[d.joint]
            tau[k] = law(d, *wanted[d.joint], q[k], qd[k], gravity[k])
        total = tau
        mh = dynamics(p, client, body, q, qd) if implicit or armature.any() else None
        if implicit:
            tau, total = implicit_damping(mh, np.asarray(qd), tau, (armature, kd, damping, timestep), drives, column)
        if not rec.record(i * timestep, dict(zip(names, q)), dict(zip(names, qd)), float(tau[column[step.joint]])):
            return
        applied = total - armature * accelerations(mh, total, armature) if armature.any() else total
        p.setJointMotorControlArray(body, list(joints.values()), p.TORQUE_CONTROL, forces=applied.tolist(),
                                    physicsClientId=client)
        p.stepSimulation(physicsClientId=client)


def joint_damping(p, client: int, body: int, joints: dict[str, int]) -> np.ndarray:
    """The URDF's joint damping, taken out of PyBullet (which applies it explicitly) to be
    integrated implicitly with the drives', as MuJoCo and Drake do."""
    out = np.array([p.getJointInfo(body, i, physicsClientId=client)[6] for i in joints.values()])
    for i in joints.values():
        p.changeDynamics(body, i, jointDamping=0.0, physicsClientId=client)
    return out


def implicit_damping(mh, v, tau, gains, drives, column) -> tuple[np.ndarray, np.ndarray]:
    """(the motor torques, the motor and damping torques) with the drives' damping Kd and the
    joints' damping B integrated implicitly: qdd = (M + A + dt (Kd + B))^-1 (tau - B qd - h), the
    motor gives tau - dt Kd qdd (clipped again) and the joint's damper -B (qd + dt qdd)."""
    armature, kd, damping, dt = gains
    qdd = accelerations(mh, tau - damping * v, armature + dt * (kd + damping))
    motor = tau.copy()
    for d in drives:
        k = column[d.joint]
        motor[k] = clip(tau[k] - dt * kd[k] * qdd[k], d.effort)
    return motor, motor - damping * (v + dt * qdd)


def dynamics(p, client, body, q: list, qd: list) -> tuple[np.ndarray, np.ndarray]:
    """(M, h) of the (fixed-base) robot at (q, qd): its mass matrix and bias forces.  PyBullet
    takes lists (numpy arrays crash it)."""
    M = np.array(p.calculateMassMatrix(body, q, physicsClientId=client))
    h = np.array(p.calculateInverseDynamics(body, q, qd, [0.0] * len(q), physicsClientId=client))
    return M, h


def accelerations(mh: tuple[np.ndarray, np.ndarray], tau, armature) -> np.ndarray:
    """The joint accelerations qdd = (M + A)^-1 (tau - h) of the robot with armature A."""
    M, h = mh
    return np.linalg.solve(M + np.diag(armature), tau - h)
