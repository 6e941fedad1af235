"""The import proved by behaviour: the rebuilt model.sdf against the original, both read through
libsdformat (``ign sdf -p``; the original as the import read it).

At the zero configuration and :data:`SAMPLES` seeded random ones (each revolute, continuous and
prismatic joint kept one to one set to the same value in both; the joints an approximation
replaced at zero): every original link's pose in the model frame, mass, centre of mass and
inertia tensor (model axes); and each kept joint's kind (turning, sliding, fixed) and axis.  The
links whose inertial the import recomputed (on the ledger) are compared by mass only."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from robotkit.errors import Problem, RobotkitError
from robotkit.importer.sdf.model import read_model
from robotkit.importer.sdf.source import printed
from robotkit.urdfxml import parse_text

SAMPLES = 10
SEED = 0
TOL = {"mass": 1e-9, "pose": 1e-9, "inertia": 1e-9, "axis": 1e-9}
"""Relative tolerances (pose: metres and rotation-matrix entries, absolute)."""
KIND = {"revolute": "turning", "continuous": "turning", "prismatic": "sliding", "fixed": "fixed", "screw": "turning"}


@dataclass
class Verdict:
    configurations: int = 0
    worst: dict = field(default_factory=dict)
    failures: list = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.failures

    def lines(self) -> list[str]:
        head = (f"verified through libsdformat against the original at {self.configurations} configurations: "
                + ("every quantity agrees" if self.ok else f"{len(self.failures)} disagreements"))
        worst = ", ".join(f"{k} {v[0]:.1e} (tol {TOL[k]:g})" for k, v in self.worst.items())
        return [head, "  largest differences: " + worst] + [f"  DIFFERS: {f}" for f in self.failures[:20]]


def rebuilt_model(path):
    result = printed(path, None)
    if result.returncode != 0:
        raise RobotkitError(Problem(f"libsdformat refuses the rebuilt model.sdf: {result.stderr.strip()[:300]}",
                                    file=str(path)))
    root = parse_text(result.stdout).getroot()
    return read_model(root.find("model"), str(path))


def verify(original, tree, repaired: set, rebuilt_path) -> Verdict:
    rebuilt = rebuilt_model(rebuilt_path)
    verdict = Verdict(worst={k: (0.0, "") for k in TOL})
    pairs = [(j, names[0]) for j, names in tree.joint_map.items() if len(names) == 1
             and original.joints[j].type in ("revolute", "continuous", "prismatic") and names[0] in rebuilt.joints]
    root = _root(original, tree.used.values())
    _joints(verdict, original, rebuilt, tree, (original.links[root].T @ tree.offset(root, original.links[root].T),
                                                rebuilt.links[root].T))
    rng = np.random.default_rng(SEED)
    configs = [("the zero configuration", {})]
    for i in range(SAMPLES if pairs else 0):
        q = {j: float(rng.uniform(-1.5, 1.5) if original.joints[j].type != "prismatic" else rng.uniform(-0.2, 0.2))
             for j, _ in pairs}
        configs.append((f"random configuration {i + 1}", q))
    names = dict(pairs)
    for label, q in configs:
        po = _relative(poses(original, q, tree.used.values()), root, tree.offset(root, original.links[root].T))
        pr = _relative(_framed(rebuilt, poses(rebuilt, {names[j]: v for j, v in q.items()})), root, np.eye(4))
        _links(verdict, original, rebuilt, tree, repaired, po, pr, label)
    verdict.configurations = len(configs)
    return verdict


def _root(model, joints) -> str:
    """The first link no joint from another link moves (a link jointed to the world counts)."""
    inner = {j.child for j in joints if j.parent in model.links}
    return next((n for n in model.links if n not in inner), next(iter(model.links)))


def _relative(poses: dict, root: str, offset) -> dict:
    """Poses in the root link's recipe frame: the rebuild may stand the robot elsewhere (a free
    robot on the floor)."""
    base = np.linalg.inv(poses[root] @ offset)
    return {name: base @ T for name, T in poses.items()}


def _check(verdict: Verdict, kind: str, err: float, where: str) -> None:
    if err > verdict.worst[kind][0]:
        verdict.worst[kind] = (err, where)
    if err > TOL[kind]:
        verdict.failures.append(f"{where}: {kind} off by {err:.2e} (tolerance {TOL[kind]:g})")


def _joints(verdict: Verdict, original, rebuilt, tree, roots) -> None:
    """Each kept joint's kind, and its axis in its model's root link frame."""
    Ro, Rr = (T[:3, :3] for T in roots)
    for j, names in tree.joint_map.items():
        oj = original.joints[j]
        if len(names) != 1 or oj.type not in KIND:
            continue
        rj = rebuilt.joints.get(names[0])
        if rj is None and oj.type == "fixed" and _massless_frame(oj.child, original, rebuilt):
            continue  # the child is a <frame> of the rebuild: its pose is compared
        if rj is None or KIND.get(rj.type) != KIND[oj.type]:
            verdict.failures.append(f"joint '{j}': {oj.type} in the original, "
                                    f"{rj.type if rj else 'missing'} in the rebuild")
            continue
        if oj.axes and rj.axes:
            _check(verdict, "axis", float(np.abs(Ro.T @ oj.axes[0] - Rr.T @ rj.axes[0]).max()), f"joint '{j}' axis")


def poses(model, q: dict, joints=None) -> dict:
    """Every link's pose in the model frame with joint values ``q`` (others at zero), along
    ``joints`` (the original's: those the import's tree follows, not the loops it drops)."""
    parent_of = {j.child: j for j in (model.joints.values() if joints is None else joints) if j.type != "gearbox"}
    done: dict = {}

    def pose(link, seen=()):
        if link in done:
            return done[link]
        j = parent_of.get(link)
        if j is None or j.parent not in model.links or link in seen:
            done[link] = model.links[link].T
            return done[link]
        P = pose(j.parent, seen + (link,))
        delta = P @ np.linalg.inv(model.links[j.parent].T)
        done[link] = delta @ _motion(j, q.get(j.name, 0.0)) @ model.links[link].T
        return done[link]

    for name in model.links:
        pose(name)
    return done


def _motion(j, v: float) -> np.ndarray:
    """The move of joint ``j`` by ``v`` in the model frame at the zero configuration."""
    M = np.eye(4)
    if not v or not j.axes:
        return M
    a, p = j.axes[0], j.T[:3, 3]
    if j.type == "prismatic":
        M[:3, 3] = a * v
        return M
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    R = np.eye(3) + np.sin(v) * K + (1 - np.cos(v)) * K @ K
    M[:3, :3], M[:3, 3] = R, p - R @ p
    return M


def _framed(model, done: dict) -> dict:
    """Link poses ``done`` with the model's <frame>s added where their links are (model.sdf
    writes a massless link fixed to another as a frame)."""
    for name, (attached, T) in model.frames.items():
        if attached in done and attached in model.links and name not in done:
            done[name] = done[attached] @ np.linalg.inv(model.links[attached].T) @ T
    return done


def _massless_frame(name: str, original, rebuilt) -> bool:
    """Whether the original's link ``name`` is massless and the rebuild has it as a <frame>."""
    return name in original.links and original.links[name].mass == 0 and name in rebuilt.frames


def _links(verdict, original, rebuilt, tree, repaired, po, pr, label: str) -> None:
    """Each original link against its rebuilt link with the point masses its joint's chain links
    took from it (robotkit.importer.sdf.tree.take_chain_masses), all in model axes."""
    carried: dict[str, list[str]] = {}
    for link, child in tree.moved.items():
        carried.setdefault(child, []).append(link)
    for name, lo in original.links.items():
        lr = rebuilt.links.get(name)
        where = f"link '{name}' at {label}"
        if lr is None and _massless_frame(name, original, rebuilt):
            _check(verdict, "pose", float(np.abs(po[name] @ tree.offset(name, lo.T) - pr[name]).max()), where)
            continue
        if lr is None:
            verdict.failures.append(f"link '{name}' missing in the rebuild")
            continue
        To, Tr = po[name] @ tree.offset(name, lo.T), pr[name]
        _check(verdict, "pose", float(np.abs(To - Tr).max()), where)
        mo, co, Io = _composite([(po[name], lo)])
        mr, cr, Ir = _composite([(pr[n], rebuilt.links[n]) for n in [name, *carried.get(name, [])] if n in rebuilt.links])
        if name in tree.scaled:  # its mass and moments written at the recipe's bound (on the ledger)
            continue
        _check(verdict, "mass", abs(mo - mr) / max(mo, 1e-300), where)
        if name in repaired:
            continue
        _check(verdict, "pose", float(np.abs(co - cr).max()), where + " centre of mass")
        _check(verdict, "inertia", float(np.abs(Io - Ir).max() / max(np.abs(Io).max(), 1e-300)), where)


def _composite(parts) -> tuple[float, np.ndarray, np.ndarray]:
    """(mass, centre of mass, inertia about it in model axes) of links (pose, link) together."""
    mass = sum(lk.mass for _, lk in parts)
    coms = [T[:3, :3] @ lk.com + T[:3, 3] for T, lk in parts]
    com = sum(lk.mass * c for (_, lk), c in zip(parts, coms)) / mass if len(parts) > 1 else coms[0]
    inertia = np.zeros((3, 3))
    for (T, lk), c in zip(parts, coms):
        d = c - com
        inertia += T[:3, :3] @ lk.inertia @ T[:3, :3].T + lk.mass * (float(d @ d) * np.eye(3) - np.outer(d, d))
    return mass, com, inertia
