"""report.html: the pictures of a robot and a table per link and per joint (mass, centre of
mass, principal moments, equivalent inertia box, implied density, collision fidelity, the
lints that fired on it, what each format lost), rendered through the one Jinja environment.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robotkit import urdfxml
from robotkit.check.findings import Finding
from robotkit.check.lints import equivalent_box, link_volume
from robotkit.emit.env import environment

FORMATS = {"urdf": "URDF", "sdf": "SDF", "mjcf": "MJCF"}
TEMPLATE = "report/report.html.j2"


@dataclass
class LinkRow:
    name: str
    mass: float | None = None
    com: list[float] | None = None
    moments: list[float] | None = None  # principal moments about the COM, ascending
    box: list[float] | None = None  # equivalent inertia box sides
    volume: float | None = None
    density: float | None = None
    collision: list[str] = field(default_factory=list)
    findings: list[Finding] = field(default_factory=list)
    losses: list[str] = field(default_factory=list)


@dataclass
class JointRow:
    name: str
    type: str
    parent: str = ""
    child: str = ""
    axis: list[float] | None = None
    lower: float | None = None
    upper: float | None = None
    mimic: str | None = None
    findings: list[Finding] = field(default_factory=list)
    losses: list[str] = field(default_factory=list)


def link_rows(links, findings: list[Finding], losses: dict[str, list[str]], collision: dict) -> list[LinkRow]:
    """One row per link from the check package's LinkFacts."""
    rows = []
    for link in links:
        row = LinkRow(link.name)
        if link.mass is not None and link.inertia is not None:
            row.mass = float(link.mass)
            row.com = [float(v) for v in link.com]
            moments = np.linalg.eigvalsh(np.asarray(link.inertia, dtype=float))
            row.moments = [float(v) for v in moments]
            if link.mass > 0:
                row.box = [float(v) for v in equivalent_box(link.mass, moments)]
        row.volume = link_volume(link)
        if row.volume and row.mass:
            row.density = row.mass / row.volume
        subject = f"link '{link.name}'"
        row.findings = [f for f in findings if f.subject == subject]
        row.losses = [f"{FORMATS.get(fmt, fmt)}: {item}" for fmt, items in sorted(losses.items())
                      for item in items if subject in item]
        names = [g.name for g in link.role("collision")]
        for entry in collision.values():
            stem = Path(entry["source"]).stem
            if any(n.startswith(stem) for n in names):
                row.collision.append(_fidelity(entry))
        rows.append(row)
    return rows


def _fidelity(entry: dict) -> str:
    f = entry["fidelity"]
    text = f"{entry['strategy']}, {f['pieces']} piece{'s' * (f['pieces'] != 1)}"
    if f.get("volume_ratio"):
        text += f", {f['volume_ratio']:.3g}x the visual volume"
    dist = f.get("distance") or {}
    if dist.get("max") is not None:
        text += f", surface within {dist['max'] * 1000:.3g} mm"
    return text


def joint_rows(urdf_text: str | None, joints, findings: list[Finding], losses: dict[str, list[str]]) -> list[JointRow]:
    structure = {}
    if urdf_text:
        for el in urdfxml.parse_text(urdf_text).getroot().findall("joint"):
            axis = el.find("axis")
            structure[el.get("name")] = (
                (el.find("parent").get("link") if el.find("parent") is not None else ""),
                (el.find("child").get("link") if el.find("child") is not None else ""),
                [float(v) for v in (axis.get("xyz", "1 0 0") if axis is not None else "1 0 0").split()])
    rows = []
    for j in joints:
        parent, child, axis = structure.get(j.name, ("", "", None))
        if j.type in ("fixed", "floating"):
            axis = None
        subject = f"joint '{j.name}'"
        rows.append(JointRow(j.name, j.type, parent, child, axis, j.lower, j.upper, j.mimic,
                             [f for f in findings if f.subject == subject],
                             [f"{FORMATS.get(fmt, fmt)}: {item}" for fmt, items in sorted(losses.items())
                              for item in items if names_joint(item, j.name)]))
    return rows


def names_joint(item: str, name: str) -> bool:
    """A loss line about joint ``name``: ``joint 'name'``, or one of the joints after ``joint 'a' and
    2 more ('b', 'c')`` (robotkit.emit.controllers.joints_phrase)."""
    if f"joint '{name}'" in item:
        return True
    m = re.match(r"joint '[^']+' and \d+ more \(([^)]*)\)", item)
    return bool(m) and f"'{name}'" in m.group(1)


def flagged_links(findings: list[Finding]) -> set[str]:
    """The links a lint fired on: drawn red in the report's pictures and in the viewer."""
    return {f.subject[6:-1] for f in findings if f.subject.startswith("link '")}


def other_findings(findings: list[Finding], rows: list[LinkRow], joints: list[JointRow]) -> list[Finding]:
    named = {f"link '{r.name}'" for r in rows} | {f"joint '{j.name}'" for j in joints}
    return [f for f in findings if f.subject not in named]


def other_losses(losses: dict[str, list[str]], rows: list[LinkRow], joints: list[JointRow]) -> list[str]:
    placed = {item for r in [*rows, *joints] for item in r.losses}
    return [f"{FORMATS.get(fmt, fmt)}: {item}" for fmt, items in sorted(losses.items()) for item in items
            if f"{FORMATS.get(fmt, fmt)}: {item}" not in placed]


def _num(x, digits: int = 4) -> str:
    if x is None:
        return "–"
    return f"{x:.{digits}g}"


def _vec(v, digits: int = 4) -> str:
    return "–" if v is None else "(" + ", ".join(_num(x, digits) for x in v) + ")"


def render_page(robot: str, source: str, pictures, links: list[LinkRow], joints: list[JointRow],
                findings: list[Finding], losses: list[str], notes: list[str] = (), plots=()) -> str:
    """The page; ``plots``: the drives' step responses (robotkit.picture.plots), when measured."""
    env = environment().overlay()
    env.filters["num"] = _num
    env.filters["v"] = _vec
    errors = sum(f.severity == "error" for f in findings) + sum(
        f.severity == "error" for r in [*links, *joints] for f in r.findings)
    warnings = sum(f.severity == "warning" for f in findings) + sum(
        f.severity == "warning" for r in [*links, *joints] for f in r.findings)
    return env.get_template(TEMPLATE).render(
        robot=robot, source=source, pictures=list(pictures), links=links, joints=joints, findings=findings,
        losses=losses, notes=list(notes), errors=errors, warnings=warnings,
        total_mass=sum(r.mass or 0.0 for r in links), plots=list(plots))


def read_losses(report_json: Path) -> tuple[dict[str, list[str]], dict]:
    """(losses per format, collision fidelity entries) of a build's report.json."""
    try:
        data = json.loads(report_json.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}, {}
    return data.get("losses", {}), data.get("collision", {})
