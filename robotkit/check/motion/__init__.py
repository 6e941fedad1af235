"""The motion check's simulators: the same control law run at each program's own time step in
MuJoCo, PyBullet and Drake, and the step-response metrics of what each did.  The simulators
import their program when called (heavy imports stay off the CLI start-up path)."""

from __future__ import annotations

from robotkit.check.motion.drake_sim import simulate_drake
from robotkit.check.motion.law import Drive, Step, Trace
from robotkit.check.motion.metrics import metrics
from robotkit.check.motion.mujoco_sim import simulate_mujoco
from robotkit.check.motion.pybullet_sim import simulate_pybullet

SIMULATORS = {"mujoco": simulate_mujoco, "pybullet": simulate_pybullet, "drake": simulate_drake}

__all__ = ["Drive", "Step", "Trace", "SIMULATORS", "metrics", "simulate_drake", "simulate_mujoco", "simulate_pybullet"]
