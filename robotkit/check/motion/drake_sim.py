"""The step response in Drake: a discrete MultibodyPlant (SAP) stepped by a Simulator.

The plant is built without a SceneGraph, so no geometry is loaded: no contact (as in the
MuJoCo and PyBullet runs here) and the mesh formats do not matter.  Each drive's joint gets a
JointActuator if the URDF made none, with rotor inertia = armature, gear ratio 1 (reflected
inertia = armature, added to the joint's diagonal mass) and effort limit = effort.  Position
and velocity drives use Drake's implicit PD controllers (p=kp, d=kd; velocity: p=0, d=kv)
fed the desired state; Drake clamps PD + feed-forward to the effort limit, the law's clip.
Gravity compensation is the feed-forward on the actuation input: -CalcGravityGeneralizedForces
at the current state (Drake's InverseDynamics in gravity mode, in the diagram), recomputed every
control step.  Effort drives get actuation 0 (+ that).  The state and the net actuation are logged
inside Drake, so a run is a few AdvanceTo calls, not a Python call per step."""

from __future__ import annotations

import logging
import math
import tempfile
from pathlib import Path

import numpy as np

from robotkit.check.motion.files import resolved_urdf, root_link
from robotkit.check.motion.law import Drive, Recorder, Step, Trace, check_drives, targets


def simulate_drake(urdf: Path, drives: list[Drive], step: Step, package_dirs: dict[str, Path],
                   hold_base: bool = True, timestep: float = 2e-3) -> Trace:
    from pydrake.multibody.plant import DiscreteContactApproximation, MultibodyPlant
    from pydrake.multibody.parsing import Parser

    check_drives(drives, step)
    logging.getLogger("drake").setLevel(logging.ERROR)  # joint friction, ros2_control tags: not failures
    plant = MultibodyPlant(time_step=timestep)
    plant.set_discrete_contact_approximation(DiscreteContactApproximation.kSap)
    parser = Parser(plant)
    for name, folder in package_dirs.items():
        parser.package_map().Add(name, str(Path(folder).resolve()))
    with tempfile.TemporaryDirectory() as tmp:
        path = resolved_urdf(urdf, package_dirs, Path(tmp), strip_visuals=True)
        (model,) = parser.AddModels(str(path))
        root = root_link(path)
    if hold_base and root != "world" and root is not None:
        plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(root, model))
    actuators = add_actuators(plant, model, drives)
    plant.Finalize()
    rec = Recorder("drake", timestep, step, drives)
    run(plant, model, actuators, drives, step, rec)
    return rec.trace()


def add_actuators(plant, model, drives: list[Drive]) -> dict[str, object]:
    """{joint: its JointActuator}, added where the URDF made none, set up as the drive says."""
    from pydrake.multibody.tree import PdControllerGains

    from pydrake.multibody.tree import JointActuatorIndex

    # before Finalize, GetJointActuatorIndices(model) lists none: the URDF's transmissions are looked up one by one
    every = (plant.get_joint_actuator(JointActuatorIndex(i)) for i in range(plant.num_actuators()))
    existing = {a.joint().name(): a for a in every if a.model_instance() == model}
    out = {}
    for d in drives:
        if not plant.HasJointNamed(d.joint, model):
            raise ValueError(f"joint '{d.joint}' is not in the URDF")
        effort = math.inf if d.effort is None else d.effort
        actuator = existing.get(d.joint)
        if actuator is None:
            actuator = plant.AddJointActuator(f"{d.joint}_actuator", plant.GetJointByName(d.joint, model), effort)
        else:
            actuator.set_effort_limit(effort)
        actuator.set_default_rotor_inertia(d.armature)
        actuator.set_default_gear_ratio(1.0)
        if d.interface == "position":
            actuator.set_controller_gains(PdControllerGains(p=d.kp, d=d.kd))
        elif d.interface == "velocity":
            actuator.set_controller_gains(PdControllerGains(p=0.0, d=d.kp))
        out[d.joint] = actuator
    return out


def single_dof_joints(plant, model) -> dict[str, tuple[int, int]]:
    """{name: (position index, velocity index)} of the one-degree-of-freedom joints."""
    joints = (plant.get_joint(i) for i in plant.GetJointIndices(model))
    return {j.name(): (j.position_start(), j.velocity_start()) for j in joints if j.num_positions() == 1}


CHUNK = 100
"""Control steps per AdvanceTo: the state is logged inside Drake, and looked at between chunks."""


def run(plant, model, actuators: dict, drives: list[Drive], step: Step, rec: Recorder) -> None:
    """The whole run in one diagram: the gravity compensation is Drake's InverseDynamics (gravity
    mode) through a gain that routes each gravcomp drive's joint torque to its actuator, and the
    state and net actuation are logged every control step, so no Python runs per step."""
    from pydrake.systems.analysis import Simulator
    from pydrake.systems.framework import DiagramBuilder

    joints = single_dof_joints(plant, model)
    builder = DiagramBuilder()
    builder.AddSystem(plant)
    gravity = gravity_feedforward(builder, plant, actuators, drives, joints)
    state_log, tau_log = (log_every(builder, port, rec.timestep)
                          for port in (plant.get_state_output_port(), plant.get_net_actuation_output_port()))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = plant.GetMyMutableContextFromRoot(simulator.get_mutable_context())
    q0 = plant.GetPositions(context).copy()
    for name, value in step.start.items():
        if name in joints:
            q0[joints[name][0]] = value
    plant.SetPositions(context, q0)
    fix_desired(plant, model, context, drives, step)
    if not gravity:
        plant.get_actuation_input_port().FixValue(context, np.zeros(plant.num_actuated_dofs()))
    simulator.Initialize()
    root = simulator.get_context()
    nq, steps, done = plant.num_positions(), rec.steps(), 0
    stepped = actuators[step.joint].input_start()
    while done < steps:
        end = min(done + CHUNK, steps)
        try:
            simulator.AdvanceTo(end * rec.timestep)
        except RuntimeError:
            if record(rec, joints, nq, stepped, state_log.FindLog(root), tau_log.FindLog(root), done, steps):
                raise  # not a divergence the samples show: Drake's own failure
            return
        if not record(rec, joints, nq, stepped, state_log.FindLog(root), tau_log.FindLog(root), done, end):
            return
        done = end


def gravity_feedforward(builder, plant, actuators: dict, drives: list[Drive], joints: dict) -> bool:
    """-CalcGravityGeneralizedForces of the current state on each gravcomp drive's actuator."""
    from pydrake.systems.controllers import InverseDynamics
    from pydrake.systems.primitives import MatrixGain

    routed = [d for d in drives if d.gravcomp]
    if not routed:
        return False
    compensation = builder.AddSystem(InverseDynamics(plant, InverseDynamics.InverseDynamicsMode.kGravityCompensation))
    select = np.zeros((plant.num_actuated_dofs(), plant.num_velocities()))
    for d in routed:
        select[actuators[d.joint].input_start(), joints[d.joint][1]] = 1.0
    gain = builder.AddSystem(MatrixGain(select))
    builder.Connect(plant.get_state_output_port(), compensation.get_input_port_estimated_state())
    builder.Connect(compensation.get_output_port_generalized_force(), gain.get_input_port())
    builder.Connect(gain.get_output_port(), plant.get_actuation_input_port())
    return True


def log_every(builder, port, period: float):
    from pydrake.systems.primitives import LogVectorOutput

    return LogVectorOutput(port, builder, period)


def fix_desired(plant, model, context, drives: list[Drive], step: Step) -> None:
    """The PD controllers' desired state: the step's targets.  The port has a position and a
    velocity for every actuator of the model, controlled or not (Drake ignores the others':
    effort drives beside position drives, Menagerie's TIAGo with motor actuators)."""
    every = [plant.get_joint_actuator(i) for i in plant.GetJointActuatorIndices(model)]
    desired = np.zeros(2 * len(every))
    for k, a in enumerate(every):
        if a.has_controller():
            d = next(d for d in drives if d.joint == a.joint().name())
            desired[k], desired[len(every) + k] = targets(d, step)
    if any(a.has_controller() for a in every):
        plant.get_desired_state_input_port(model).FixValue(context, desired)


def record(rec: Recorder, joints: dict, nq: int, stepped: int, states, taus, start: int, end: int) -> bool:
    """Steps ``start`` to ``end`` from the logs into ``rec``: the state at step i's start, the net
    actuation of the stepped joint at its end.  False when the recorder saw a divergence."""
    x, u = states.data(), taus.data()
    i = np.arange(start, min(end, x.shape[1], u.shape[1] - 1))
    names = list(joints)
    q = x[[joints[n][0] for n in names]][:, i].T
    v = x[[nq + joints[n][1] for n in names]][:, i].T
    return rec.record_many(i * rec.timestep, names, q, v, u[stepped, i + 1])
