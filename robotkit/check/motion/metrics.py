"""Step-response numbers of a Trace.

All are measured on the normalized response y = (x - start) / (target - start), x being the
joint position (position and effort drives) or velocity (velocity drives):
- rise_time: from y = 0.1 to y = 0.9, crossings linearly interpolated between samples (s);
  None when y never reaches 0.9;
- overshoot: max(y) - 1 as a fraction of the step, 0 when y stays below 1;
- settling_time: the time after which |y - 1| stays within 2 % (s); None when the last
  sample is outside the band;
- final_error: |target - x| at the last sample (rad, m, or rad/s, m/s);
- saturated: the fraction of samples where |tau| >= 0.999 effort (None without an effort);
- chatter: the number of sign changes of d(qd)/dt over the last half of the run, counting only
  changes of qd larger than CHATTER_BAND x |step| per sample (so round-off at rest is not counted);
  a smooth step response has 0 or 1, a drive that rings against its clip or limit cycles many.
With a zero step (target = start, a hold test) the times and overshoot are None."""

from __future__ import annotations

import numpy as np

from robotkit.check.motion.law import Trace

SETTLE_BAND = 0.02
CHATTER_BAND = 1e-6


def crossing(t: np.ndarray, y: np.ndarray, level: float) -> float | None:
    """The first time y reaches ``level`` (interpolated), None if never."""
    above = np.nonzero(y >= level)[0]
    if not len(above):
        return None
    k = int(above[0])
    if k == 0:
        return float(t[0])
    return float(t[k - 1] + (level - y[k - 1]) / (y[k] - y[k - 1]) * (t[k] - t[k - 1]))


def settling(t: np.ndarray, y: np.ndarray) -> float | None:
    outside = np.nonzero(np.abs(y - 1.0) > SETTLE_BAND)[0]
    if not len(outside):
        return float(t[0])
    k = int(outside[-1])
    return None if k == len(y) - 1 else float(t[k + 1])


def chatter(qd: np.ndarray, step: float) -> int:
    change = np.diff(qd[len(qd) // 2:])
    change = change[np.abs(change) > CHATTER_BAND * max(abs(step), 1e-12)]
    return int(np.count_nonzero(np.diff(np.sign(change))))


def metrics(trace: Trace, start: float, target: float, interface: str, effort: float | None = None) -> dict:
    """rise_time, overshoot, settling_time, final_error, saturated, chatter (see the module)."""
    x = trace.qd if interface == "velocity" else trace.q
    size = target - start
    out = {"rise_time": None, "overshoot": None, "settling_time": None,
           "final_error": float(abs(target - x[-1])) if len(x) else None,
           "saturated": None, "chatter": chatter(trace.qd, size) if len(x) else None}
    if effort is not None and len(x):
        out["saturated"] = float(np.mean(np.abs(trace.tau) >= effort * 0.999))
    if not len(x) or size == 0:
        return out
    y = (x - start) / size
    low, high = crossing(trace.t, y, 0.1), crossing(trace.t, y, 0.9)
    out["rise_time"] = None if low is None or high is None else high - low
    out["overshoot"] = float(max(0.0, y.max() - 1.0))
    out["settling_time"] = settling(trace.t, y)
    return out
