"""The step response in MuJoCo: the MJCF the build writes (or the scene that includes it),
with its own integrator and time step.

The base is held by deleting the root body's free joint.  The MJCF's own actuators are used
as written when every drive has one with the Drive's gains and the joint's armature equals the
Drive's; otherwise they are removed and each drive gets a ``position`` (kp, kv=kd) or
``velocity`` (kv) actuator, its joint's armature is *set* to ``Drive.armature`` (never added)
and the clip is the joint's ``actuatorfrcrange`` = +-effort (it bounds the joint's total
actuator force, as the law clips PD + gravity together).  Gravity compensation: a ``motor``
actuator on the joint whose control is, every step, the joint's gravity torque (``qfrc_bias``
at the current positions and zero velocity), i.e. the same explicit feed-forward PyBullet and
Drake add; body ``gravcomp`` is not used (it would compensate every joint above the body).
Contacts are disabled (the scene's floor too): the PyBullet and Drake runs load the robot
alone, without self-collision, and an actuator test is not a contact test."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robotkit import mj
from robotkit.check.motion.law import Drive, Recorder, Step, Trace, check_drives, isclose, targets

TOL = 1e-9


def simulate_mujoco(mjcf: Path, drives: list[Drive], step: Step, hold_base: bool = True) -> Trace:
    mujoco = mj.load()  # heavy: imported when a robot is stepped

    check_drives(drives, step)
    spec = mujoco.MjSpec.from_file(str(mjcf))
    if hold_base:
        hold(spec, mujoco)
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)  # as in PyBullet and Drake here
    controls = written_actuators(spec, drives, mujoco)
    if controls is None:
        controls = own_actuators(spec, drives, mujoco)
    gravcomp = {d.joint: gravity_motor(spec, d.joint, mujoco) for d in drives if d.gravcomp}
    model = spec.compile()
    data = mujoco.MjData(model)
    joints = {model.joint(j).name: j for j in range(model.njnt)
              if int(model.jnt_type[j]) in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))}
    for name, value in step.start.items():
        if name in joints:
            data.qpos[model.jnt_qposadr[joints[name]]] = value
    mujoco.mj_forward(model, data)
    for d in drives:
        if d.joint in controls:
            q_target, qd_target = targets(d, step)
            data.ctrl[model.actuator(controls[d.joint]).id] = qd_target if d.interface == "velocity" else q_target
    rec = Recorder("mujoco", float(model.opt.timestep), step, drives)
    run(model, data, rec, joints, step.joint, gravcomp, mujoco)
    rec.warnings.extend(f"MuJoCo warned {mujoco.mjtWarning(w).name} ({data.warning[w].number} times)"
                        for w in range(len(data.warning)) if data.warning[w].number)
    return rec.trace()


def run(model, data, rec: Recorder, joints: dict[str, int], stepped: str, gravcomp: dict[str, str], mujoco) -> None:
    """Step ``rec.steps()`` times, recording each state with the actuator torque applied from it."""
    qadr = {n: int(model.jnt_qposadr[j]) for n, j in joints.items()}
    vadr = {n: int(model.jnt_dofadr[j]) for n, j in joints.items()}
    scratch = mujoco.MjData(model) if gravcomp else None
    bias = np.zeros(model.nv)
    motors = {n: model.actuator(a).id for n, a in gravcomp.items()}
    for i in range(rec.steps()):
        if scratch is not None:  # the gravity torque at the current positions, zero velocity
            scratch.qpos[:] = data.qpos
            scratch.qvel[:] = 0.0
            mujoco.mj_fwdPosition(model, scratch)
            mujoco.mj_rne(model, scratch, 0, bias)
            for n, a in motors.items():
                data.ctrl[a] = bias[vadr[n]]
        q = {n: float(data.qpos[a]) for n, a in qadr.items()}
        qd = {n: float(data.qvel[a]) for n, a in vadr.items()}
        mujoco.mj_step(model, data)  # qfrc_actuator is what was applied from the state before
        if not rec.record(i * model.opt.timestep, q, qd, float(data.qfrc_actuator[vadr[stepped]])):
            return


def hold(spec, mujoco) -> None:
    """Delete the free joint of each root body (the base is held where the file puts it), and
    the keyframes, whose qpos counted it (the step sets its own start)."""
    held = False
    for body in spec.worldbody.bodies:
        for joint in list(body.joints):
            if joint.type == mujoco.mjtJoint.mjJNT_FREE:
                spec.delete(joint)
                held = True
    for key in list(spec.keys) if held else []:
        spec.delete(key)


def matches(actuator, drive: Drive) -> bool:
    """The actuator is the drive's, with the drive's gains."""
    g, b = actuator.gainprm, actuator.biasprm
    if drive.interface == "position":
        return isclose(g[0], drive.kp) and isclose(b[1], -drive.kp) and isclose(b[2], -drive.kd)
    if drive.interface == "velocity":
        return isclose(g[0], drive.kp) and isclose(b[1], 0.0) and isclose(b[2], -drive.kp)
    return isclose(g[0], 1.0) and isclose(b[1], 0.0) and isclose(b[2], 0.0)


def written_actuators(spec, drives: list[Drive], mujoco) -> dict[str, str] | None:
    """{joint: actuator name} when the file's actuators are the drives as given, else None."""
    by_joint: dict[str, list] = {}
    for a in spec.actuators:
        if a.trntype == mujoco.mjtTrn.mjTRN_JOINT:
            by_joint.setdefault(a.target, []).append(a)
    out = {}
    for d in drives:
        found = [a for a in by_joint.get(d.joint, []) if matches(a, d)]
        joint = spec.joint(d.joint)
        if joint is None:
            raise ValueError(f"joint '{d.joint}' is not in the MJCF")
        if not found or abs(joint.armature - d.armature) > TOL:
            return None
        out[d.joint] = found[0].name
    return out if out else None


def own_actuators(spec, drives: list[Drive], mujoco) -> dict[str, str]:
    """Replace the file's actuators by the drives' own; {joint: actuator name} (effort drives: none)."""
    for a in list(spec.actuators):
        spec.delete(a)
    out = {}
    for d in drives:
        joint = spec.joint(d.joint)
        if joint is None:
            raise ValueError(f"joint '{d.joint}' is not in the MJCF")
        joint.armature = d.armature
        if d.effort is None:
            joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_FALSE
        else:
            joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_TRUE
            joint.actfrcrange = [-d.effort, d.effort]
        if d.interface == "effort":
            continue
        a = spec.add_actuator(name=f"{d.joint}_{d.interface}", target=d.joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        if d.interface == "position":
            a.set_to_position(kp=d.kp, kv=d.kd)
        else:
            a.set_to_velocity(kv=d.kp)
        a.ctrllimited = a.forcelimited = mujoco.mjtLimited.mjLIMITED_FALSE
        out[d.joint] = a.name
    return out


def gravity_motor(spec, joint: str, mujoco) -> str:
    a = spec.add_actuator(name=f"{joint}_gravcomp", target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    a.set_to_motor()
    a.ctrllimited = a.forcelimited = mujoco.mjtLimited.mjLIMITED_FALSE
    return a.name
