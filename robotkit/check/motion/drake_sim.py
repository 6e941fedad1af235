"""The step response in Drake: a discrete MultibodyPlant (SAP) stepped by a Simulator.

The plant is built without a SceneGraph, so no geometry is loaded: no contact (as in the
MuJoCo and PyBullet runs here) and the mesh formats do not matter.  Each drive's joint gets a
JointActuator if the URDF made none, with rotor inertia = armature, gear ratio 1 (reflected
inertia = armature, added to the joint's diagonal mass) and effort limit = effort.  Position
and velocity drives use Drake's implicit PD controllers (p=kp, d=kd; velocity: p=0, d=kv)
fed the desired state; Drake clamps PD + feed-forward to the effort limit, the law's clip.
Gravity compensation is the feed-forward on the actuation input: -CalcGravityGeneralizedForces
at the current state, recomputed every control step.  Effort drives get actuation 0 (+ that)."""

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


def run(plant, model, actuators: dict, drives: list[Drive], step: Step, rec: Recorder) -> None:
    from pydrake.systems.analysis import Simulator

    joints = single_dof_joints(plant, model)
    simulator = Simulator(plant)
    context = simulator.get_mutable_context()
    q0 = plant.GetPositions(context).copy()
    for name, value in step.start.items():
        if name in joints:
            q0[joints[name][0]] = value
    plant.SetPositions(context, q0)
    controlled = [plant.get_joint_actuator(i) for i in plant.GetJointActuatorIndices(model)
                  if plant.get_joint_actuator(i).has_controller()]
    desired = np.zeros(2 * len(controlled))
    for k, a in enumerate(controlled):
        d = next(d for d in drives if d.joint == a.joint().name())
        desired[k], desired[len(controlled) + k] = targets(d, step)
    if controlled:
        plant.get_desired_state_input_port(model).FixValue(context, desired)
    port = plant.get_actuation_input_port()
    port.FixValue(context, np.zeros(plant.num_actuated_dofs()))
    simulator.Initialize()
    stepped = actuators[step.joint]
    for i in range(rec.steps()):
        u = np.zeros(plant.num_actuated_dofs())
        if any(d.gravcomp for d in drives):
            gravity = -plant.CalcGravityGeneralizedForces(context)
            for d in drives:
                if d.gravcomp:
                    actuators[d.joint].set_actuation_vector([gravity[joints[d.joint][1]]], u)
        port.FixValue(context, u)
        q, v = plant.GetPositions(context), plant.GetVelocities(context)
        simulator.AdvanceTo((i + 1) * rec.timestep)
        tau = float(stepped.get_actuation_vector(plant.get_net_actuation_output_port().Eval(context))[0])
        if not rec.record(i * rec.timestep, {n: float(q[a]) for n, (a, _) in joints.items()},
                          {n: float(v[b]) for n, (_, b) in joints.items()}, tau):
            return
