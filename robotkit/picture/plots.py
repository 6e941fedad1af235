"""Step responses as inline SVG: each joint's step in MuJoCo, PyBullet and Drake on one plot,
from the motion stage's results (robotkit.check.motion.stage: 100-point traces per simulator).

Plain SVG polylines, no plotting library: the page stays one self-contained file."""

from __future__ import annotations

from dataclasses import dataclass, field

WIDTH, HEIGHT, PAD = 360, 170, 34
COLOURS = {"mujoco": "#1f77b4", "pybullet": "#d62728", "drake": "#2ca02c"}


@dataclass
class StepPlot:
    """One joint's step from one pose: the SVG and the figures beside it."""

    joint: str
    pose: str
    svg: str
    rows: list[dict] = field(default_factory=list)  # per simulator: rise, overshoot, settling, final error


def step_plots(motion: dict | None) -> list[StepPlot]:
    """A plot per joint (its first pose), the simulators that ran it overlaid."""
    out = []
    for joint, entry in sorted((motion or {}).get("joints", {}).items()):
        poses = entry.get("poses", {})
        if not poses:
            continue
        pose, data = next(iter(poses.items()))
        sims = {s: r for s, r in data.get("simulators", {}).items() if r.get("trace", {}).get("t")}
        if not sims:
            continue
        rows = [{"simulator": s, **{k: r.get(k) for k in ("rise_time", "overshoot", "settling_time", "final_error")}}
                for s, r in sims.items()]
        out.append(StepPlot(joint, pose, svg(sims, entry.get("interface", "position")), rows))
    return out


def svg(sims: dict[str, dict], interface: str) -> str:
    """The traces of ``sims`` ({simulator: run}) with the start and target as dashed lines."""
    first = next(iter(sims.values()))
    start, target = first["start"], first["target"]
    ts = [t for r in sims.values() for t in r["trace"]["t"]]
    qs = [q for r in sims.values() for q in r["trace"]["q"]] + [start, target]
    t1 = max(ts) or 1.0
    lo, hi = min(qs), max(qs)
    span = (hi - lo) or 1.0

    def x(t: float) -> float:
        return PAD + (WIDTH - 2 * PAD) * t / t1

    def y(q: float) -> float:
        return HEIGHT - PAD + (q - lo) / span * (2 * PAD - HEIGHT)

    unit = "rad/s" if interface == "velocity" else "value"
    parts = [f'<svg class="step" xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" '
             f'viewBox="0 0 {WIDTH} {HEIGHT}">',
             f'<rect x="{PAD}" y="{PAD}" width="{WIDTH - 2 * PAD}" height="{HEIGHT - 2 * PAD}" fill="none" '
             'stroke="#ccc"/>']
    for level in (start, target):
        parts.append(f'<line x1="{PAD}" x2="{WIDTH - PAD}" y1="{y(level):.1f}" y2="{y(level):.1f}" '
                     'stroke="#999" stroke-dasharray="4 3"/>')
    for s, r in sims.items():
        points = " ".join(f"{x(t):.1f},{y(q):.1f}" for t, q in zip(r["trace"]["t"], r["trace"]["q"]))
        parts.append(f'<polyline class="{s}" fill="none" stroke="{COLOURS.get(s, "#000")}" stroke-width="1.5" '
                     f'points="{points}"/>')
    parts.append(f'<text x="{PAD}" y="{HEIGHT - 8}" font-size="11">0 s</text>'
                 f'<text x="{WIDTH - PAD}" y="{HEIGHT - 8}" font-size="11" text-anchor="end">{t1:.2g} s</text>'
                 f'<text x="4" y="{PAD - 8}" font-size="11">{unit}: {start:.3g} → {target:.3g}</text>')
    legend = " ".join(f'<tspan fill="{COLOURS.get(s, "#000")}">{s}</tspan>' for s in sims)
    parts.append(f'<text x="{WIDTH - PAD}" y="{PAD - 8}" font-size="11" text-anchor="end">{legend}</text></svg>')
    return "".join(parts)
