"""The data of a step-response run and the control law every simulator applies.

Position drive: tau = kp (q_target - q) - kd qd (+ the joint's gravity torque if gravcomp),
clipped to +-effort.  Velocity drive: tau = kp (qd_target - qd), clipped.  Effort drive:
tau = 0 (+ gravcomp).  Joints without a drive are passive.  Every actuated joint other than
the stepped one holds its start value (position drives) or stands still (velocity drives)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

EXPLODE_SPEED = 1e3  # rad/s or m/s: a joint faster than this has exploded


@dataclass(frozen=True)
class Drive:
    """One actuated joint, as the build emitted it."""
    joint: str
    interface: str  # "position" | "velocity" | "effort"
    kp: float  # position: stiffness (N m/rad); velocity: the velocity gain kv (N m s/rad)
    kd: float  # position: damping (N m s/rad); velocity: 0
    ki: float = 0.0  # not simulated (MJCF has no integral)
    armature: float = 0.0  # reflected rotor inertia (kg m^2 or kg), added to the joint's inertia
    effort: float | None = None  # torque/force limit; the control output is clipped to +-effort
    gravcomp: bool = False  # the drive adds the gravity torque of its joint (feed-forward)


@dataclass(frozen=True)
class Step:
    joint: str  # the joint that steps
    start: dict[str, float]  # every joint's value at t=0 (a named pose); joints not named = 0
    target: float  # position drives: the new position target; velocity drives: the new velocity target
    seconds: float = 1.5


@dataclass
class Trace:
    """What one simulator did: the stepped joint, one sample per control step."""
    simulator: str
    timestep: float
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    tau: np.ndarray
    others_max_dev: float  # largest |q - start| of the other actuated joints over the run
    diverged: str | None  # "NaN at t=..." / "exploded at t=... (|qd| ...)" or None
    warnings: list[str] = field(default_factory=list)


def check_drives(drives: list[Drive], step: Step) -> dict[str, Drive]:
    """The drives by joint; ValueError when the stepped joint has none or an interface is unknown."""
    by_joint = {d.joint: d for d in drives}
    for d in drives:
        if d.interface not in ("position", "velocity", "effort"):
            raise ValueError(f"joint '{d.joint}': unknown interface '{d.interface}'")
    if step.joint not in by_joint:
        raise ValueError(f"the stepped joint '{step.joint}' has no drive")
    return by_joint


def targets(drive: Drive, step: Step) -> tuple[float, float]:
    """(position target, velocity target) of ``drive`` during ``step``."""
    q0 = step.start.get(drive.joint, 0.0)
    if drive.joint != step.joint:
        return q0, 0.0
    if drive.interface == "velocity":
        return q0, step.target
    return step.target, 0.0


def law(drive: Drive, q_target: float, qd_target: float, q: float, qd: float, gravity: float = 0.0) -> float:
    """The motor torque of ``drive`` (``gravity``: the torque that holds the joint against gravity)."""
    if drive.interface == "position":
        tau = drive.kp * (q_target - q) - drive.kd * qd
    elif drive.interface == "velocity":
        tau = drive.kp * (qd_target - qd)
    else:
        tau = 0.0
    if drive.gravcomp:
        tau += gravity
    return clip(tau, drive.effort)


def clip(tau: float, effort: float | None) -> float:
    return tau if effort is None else min(max(tau, -effort), effort)


class Recorder:
    """Collects the stepped joint per control step, the hold of the other drives, and divergence."""

    def __init__(self, simulator: str, timestep: float, step: Step, drives: list[Drive]):
        self.simulator, self.timestep, self.step = simulator, timestep, step
        self.others = [d.joint for d in drives if d.joint != step.joint and d.interface == "position"]
        self.rows: list[tuple[float, float, float, float]] = []
        self.others_max_dev = 0.0
        self.diverged: str | None = None
        self.warnings: list[str] = []

    def steps(self) -> int:
        return int(round(self.step.seconds / self.timestep))

    def record(self, t: float, q: dict[str, float], qd: dict[str, float], tau: float) -> bool:
        """Store one sample; False (and ``diverged`` set) when the state is NaN or exploded."""
        values = np.array(list(q.values()) + list(qd.values()), dtype=float)
        if not np.isfinite(values).all():
            self.diverged = f"NaN at t={t:.4g} s"
            return False
        speed = max((abs(v) for v in qd.values()), default=0.0)
        if speed > EXPLODE_SPEED:
            self.diverged = f"exploded at t={t:.4g} s (|qd| {speed:.3g})"
            return False
        self.rows.append((t, q[self.step.joint], qd[self.step.joint], tau))
        for j in self.others:
            self.others_max_dev = max(self.others_max_dev, abs(q[j] - self.step.start.get(j, 0.0)))
        return True

    def record_many(self, t: np.ndarray, names: list[str], q: np.ndarray, qd: np.ndarray,
                    tau: np.ndarray) -> bool:
        """:meth:`record` of each row in turn (``q``, ``qd``: one column per name in ``names``),
        in numpy: stops at the first row that is NaN or exploded (``diverged`` set, False)."""
        bad = ~(np.isfinite(q).all(axis=1) & np.isfinite(qd).all(axis=1))
        speed = np.abs(qd).max(axis=1, initial=0.0)
        stop = bad | (speed > EXPLODE_SPEED)
        n = int(np.argmax(stop)) if stop.any() else len(t)
        col = {name: k for k, name in enumerate(names)}
        j = col[self.step.joint]
        self.rows.extend(zip(t[:n].tolist(), q[:n, j].tolist(), qd[:n, j].tolist(), tau[:n].tolist()))
        for other in self.others:
            if n:
                dev = float(np.abs(q[:n, col[other]] - self.step.start.get(other, 0.0)).max())
                self.others_max_dev = max(self.others_max_dev, dev)
        if n == len(t):
            return True
        if bad[n]:
            self.diverged = f"NaN at t={float(t[n]):.4g} s"
        else:
            self.diverged = f"exploded at t={float(t[n]):.4g} s (|qd| {float(speed[n]):.3g})"
        return False

    def trace(self) -> Trace:
        a = np.array(self.rows, dtype=float).reshape(-1, 4)
        return Trace(self.simulator, self.timestep, a[:, 0], a[:, 1], a[:, 2], a[:, 3],
                     float(self.others_max_dev), self.diverged, self.warnings)


def isclose(a: float, b: float) -> bool:
    return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12)
