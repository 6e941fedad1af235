"""Interference: the robot's own links, at its named poses and over its joints' ranges.

On a build folder, the collision geometry is the MJCF's (the same the matrix was sampled on,
:mod:`robotkit.model.selfcollision`), the disabled pairs are the SRDF's (their reasons with them),
the named poses are the MJCF's keyframes:

- at every named pose, a pair that is not disabled and interpenetrates deeper than
  :data:`~robotkit.model.selfcollision.TOUCH` is an error, naming the pair and the depth;
- each joint swept from each named pose towards both limits (the others held): the first angle at
  which a pair that is not disabled starts to collide, when that is inside the limits, is a warning
  (the limit is wider than the mechanism allows);
- in a fresh sample (another seed): a pair disabled as Never that collides, and a pair the recipe
  allows (User) that never comes near, are warnings.
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from robotkit.check.findings import Finding
from robotkit.emit.layout import robot_layout
from robotkit.model.selfcollision import CLEARANCE, TOUCH, Sampler

STEPS = 240
"""Steps over a joint's whole range when sweeping it (1.5 degrees over a full turn), then bisected."""
FRESH = 10000
"""Configurations of the fresh sample."""


def disabled_pairs(srdf: Path) -> dict[frozenset, str]:
    """The SRDF's disabled pairs and their reasons."""
    root = ET.parse(srdf).getroot()
    return {frozenset((e.get("link1"), e.get("link2"))): e.get("reason", "")
            for e in root.iter("disable_collisions")}


def interference(robot_dir: Path) -> list[Finding]:
    """The findings of the module docstring for one build folder."""
    layout = robot_layout(robot_dir)
    srdf = layout.path("srdf/{name}.srdf")
    where = f"srdf/{layout.name}.srdf"
    sampler = Sampler(path=str(layout.mjcf))
    disabled = disabled_pairs(srdf) if srdf.is_file() else {p: "MJCF exclude" for p in sampler.file_excludes}
    findings = at_poses(sampler, disabled, where) + sweeps(sampler, disabled)
    seed = 0
    if layout.report_json.is_file():
        seed = json.loads(layout.report_json.read_text(encoding="utf-8")).get("self_collision", {}).get("seed", 0)
    return findings + fresh_sample(sampler, disabled, seed + 1, where)


def mjcf_interference(path: Path) -> list[Finding]:
    """Interference of a foreign MJCF: its own filter (contype/conaffinity, excludes, explicit
    pairs, MuJoCo's parent filter) says which pairs are disabled; its keyframes are the poses."""
    sampler = Sampler(path=str(path))
    disabled = {p: "MJCF filter" for p in own_filter(path, sampler)}
    return at_poses(sampler, disabled, str(path)) + sweeps(sampler, disabled)


def own_filter(path: Path, sampler: Sampler) -> set[frozenset]:
    """The link pairs (of bodies with colliding geoms) MuJoCo never collides in the file as written."""
    from robotkit.mj import load

    mujoco = load()
    m = mujoco.MjModel.from_xml_path(str(path))
    weld, parent = m.body_weldid, m.body_parentid
    excluded = {int(s) for s in m.exclude_signature}
    paired = {frozenset((int(m.geom_bodyid[a]), int(m.geom_bodyid[b]))) for a, b in zip(m.pair_geom1, m.pair_geom2)}
    filterparent = not m.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_FILTERPARENT)

    def collides(a: int, b: int) -> bool:
        if frozenset((a, b)) in paired:
            return True
        wa, wb = int(weld[a]), int(weld[b])
        if wa == wb or ((min(a, b) << 16) + max(a, b)) in excluded:
            return False
        if filterparent and wa and wb and (wa == weld[parent[wb]] or wb == weld[parent[wa]]):
            return False
        ga, gb = np.flatnonzero(m.geom_bodyid == a), np.flatnonzero(m.geom_bodyid == b)
        return any((m.geom_contype[g] & m.geom_conaffinity[h]) or (m.geom_contype[h] & m.geom_conaffinity[g])
                   for g in ga for h in gb)

    bodies = sorted(sampler.has_geoms)
    return {frozenset((sampler.names[a], sampler.names[b])) for i, a in enumerate(bodies) for b in bodies[i + 1:]
            if not collides(a, b)}


def _mm(depth: float) -> str:
    return f"{depth * 1000:.3g} mm"


def at_poses(sampler: Sampler, disabled: dict, where: str) -> list[Finding]:
    out = []
    for name, q in sorted(sampler.space.poses.items()):
        for (a, b), depth in sorted(sampler.colliding(sampler.space.held(q), TOUCH).items()):
            if frozenset((a, b)) not in disabled:
                out.append(Finding("error", "self-collision", f"pose '{name}'",
                                   f"links '{a}' and '{b}' interpenetrate by {_mm(depth)}",
                                   "change the pose, or allow the pair in self_collision.allow with its reason",
                                   file=where))
    return out


def sweeps(sampler: Sampler, disabled: dict) -> list[Finding]:
    """Each joint from each named pose (the zero pose without any) towards both of its limits."""
    space = sampler.space
    starts = {n: space.held(q) for n, q in sorted(space.poses.items())} or {"zero": space.zero()}
    seen, out = set(), []
    for i, joint in enumerate(space.names):
        for pose, q0 in starts.items():
            for end in (space.hi[i], space.lo[i]):
                hit = first_contact(sampler, disabled, q0, space.addr[i], end)
                if hit is None or (joint, end) in seen:
                    continue
                seen.add((joint, end))
                angle, (a, b) = hit
                out.append(Finding("warning", "self-collision", f"joint '{joint}'",
                                   f"from pose '{pose}', links '{a}' and '{b}' collide at {_value(sampler, i, angle)}, "
                                   f"inside its limit {_value(sampler, i, end)}: the limit is wider than the "
                                   "mechanism allows", "narrow the limit, or allow the pair with its reason"))
    return out


def _value(sampler: Sampler, i: int, v: float) -> str:
    name = sampler.space.names[i]
    hinge = int(sampler.model.jnt_type[sampler.model.joint(name).id]) == 3
    return f"{math.degrees(v):.1f} deg" if hinge else f"{v * 1000:.1f} mm"


def first_contact(sampler: Sampler, disabled: dict, q0: np.ndarray, addr: int, end: float):
    """(joint value, pair) where a pair that is not disabled first collides moving qpos[addr] from
    its value in ``q0`` to ``end`` (bisected to 1e-4 of the range), or None."""
    space = sampler.space
    start = q0[addr]
    width = float(np.max(space.hi - space.lo)) if len(space.hi) else 1.0
    n = max(2, int(math.ceil(abs(end - start) / width * STEPS)))

    def clash(v: float):
        q = q0.copy()
        q[addr] = v
        hits = [p for p in sampler.colliding(space.follow(q), TOUCH) if frozenset(p) not in disabled]
        return hits[0] if hits else None

    if clash(start) is not None:
        return None  # already in contact at the pose: at_poses says so
    free = start
    for v in np.linspace(start, end, n + 1)[1:]:
        pair = clash(v)
        if pair is not None:
            hit = v
            for _ in range(20):
                mid = (free + hit) / 2
                if clash(mid) is None:
                    free = mid
                else:
                    hit = mid
            return hit, clash(hit)
        free = v
    return None


def fresh_sample(sampler: Sampler, disabled: dict, seed: int, where: str) -> list[Finding]:
    """Never pairs that collide, User pairs that never come near, in FRESH new configurations."""
    if not len(sampler.space.addr):
        return []
    samples = sampler.space.random(FRESH, seed)
    rows, dist = sampler.sweep(samples)
    names = sampler.names
    ids = {n: i for i, n in enumerate(names)}
    users = {tuple(sorted(ids[n] for n in p)) for p, r in disabled.items() if r == "User" and p <= set(ids)}
    near = {frozenset((names[a], names[b])) for a, b in sampler.near(samples, users)} if users else set()
    deepest, hits = penetrations(rows, dist, names)
    out = []
    for pair, reason in sorted(disabled.items(), key=lambda kv: sorted(kv[0])):
        a, b = sorted(pair)
        if reason == "Never" and pair in hits:
            out.append(Finding("warning", "self-collision", f"links '{a}' and '{b}'",
                               f"disabled as Never, but they collide in {hits[pair]} of {FRESH} fresh "
                               f"configurations (seed {seed}; deepest {_mm(deepest[pair])})",
                               "sample more: self_collision.samples", file=where))
        if reason == "User" and pair not in near:
            out.append(Finding("warning", "self-collision", f"links '{a}' and '{b}'",
                               f"allowed to touch by the recipe, but never within {CLEARANCE * 100:g} cm of each "
                               f"other in {FRESH} configurations: the allow entry is not needed", file=where))
    return out


def penetrations(rows: np.ndarray, dist: np.ndarray, names: list[str]) -> tuple[dict[frozenset, float], dict[frozenset, int]]:
    """From a sweep's contacts (sample, body a, body b rows and their distances): per pair of link
    names that interpenetrate, the deepest penetration (m) and in how many samples they do.  In
    numpy: a fresh sample of 10,000 configurations has tens of thousands of contacts."""
    inside = dist < 0
    rows, depth = rows[inside], -dist[inside]
    if not len(rows):
        return {}, {}
    bodies, at = np.unique(rows[:, 1:], axis=0, return_inverse=True)
    index: dict[frozenset, int] = {}
    of_bodies = [index.setdefault(frozenset((names[a], names[b])), len(index)) for a, b in bodies]
    pairs = list(index)
    which = np.array(of_bodies)[at.reshape(-1)]
    deepest = np.zeros(len(pairs))
    np.maximum.at(deepest, which, depth)
    counted = np.unique(np.column_stack([which, rows[:, 0]]), axis=0)[:, 0]
    samples = np.bincount(counted, minlength=len(pairs))
    return ({p: float(deepest[k]) for k, p in enumerate(pairs)}, {p: int(samples[k]) for k, p in enumerate(pairs)})
