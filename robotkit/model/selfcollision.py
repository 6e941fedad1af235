"""The self-collision matrix: which link pairs a consumer should check, from sampled configurations.

MoveIt Setup Assistant's classification, computed on the collision geometry MuJoCo gets (the
MJCF's hulls, pieces and primitives; MuJoCo collides a mesh as its convex hull, and every
collision piece robotkit writes is convex):

- **Adjacent**: the links are welded together (a chain of fixed joints), or joined by one moving
  joint between their welded groups, or through a group without collision geometry between them
  (MoveIt's rule: a link without geometry passes adjacency on);
- **User**: the recipe allows them to touch (``self_collision: {allow: [[a, b, reason]]}``);
- **Default**: in contact at the zero pose (each joint at 0, clamped into its limits);
- **Always**: in contact in at least 95 % of the samples (MoveIt's threshold);
- **Never**: never within :data:`CLEARANCE` of each other in any sample.  MoveIt asks for no
  contact only; the clearance keeps a pair whose collisions are too rare for the sample count to
  find checked (a pair that comes within 1 cm is one a denser sampler may see collide).

Every other pair is checked (reason ``""``), and so is every pair the recipe names in ``check``.
Samples are uniform within the joint limits (a continuous joint over one turn, a mimic joint
following its leader, a floating base held); the zero pose and the named poses (MJCF keyframes)
are evaluated too, and the contacts at the named poses recorded for ``robotkit check``.

The same :class:`Sampler` reads the MJCF robotkit renders (the build's ``<robot>:self-collision``
task) and a built or foreign MJCF file (``robotkit check``): limits, mimic couplings (joint
equalities), named poses (keyframes) and the body tree all come from the compiled model.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field

import numpy as np

from robotkit.mj import load as load_mujoco

CLEARANCE = 0.01
"""m: a pair that comes closer than this in a sample is not classified Never."""
ALWAYS = 0.95
"""Fraction of the samples in contact above which a pair is Always in collision (MoveIt's)."""
DEFAULT_SAMPLES = 10000
"""MoveIt Setup Assistant's default sampling density; ur5's and the quadruped's matrices are the
same at 10,000 and 100,000 samples and for seeds 0 to 4 (docs/selfcollision.md)."""
TOUCH = 1e-4
"""m: the penetration below which two geoms resting on each other count as touching, not in
collision (the interference check's tolerance)."""
SEARCH_ONLY = 20
"""Up to this many pairs never in contact, each is searched (:class:`Approach`) without a second sweep."""
REASONS = ("Adjacent", "User", "Default", "Always", "Never")


@dataclass(frozen=True)
class Pair:
    """One link pair's verdict: ``reason`` is a MoveIt reason (disabled) or "" (checked)."""

    a: str
    b: str
    reason: str
    hits: int = 0  # samples in contact
    closest: float | None = None  # m, the smallest distance seen within CLEARANCE (negative: depth)
    note: str = ""  # the recipe's reason for a User pair

    @property
    def disabled(self) -> bool:
        return bool(self.reason)


@dataclass(frozen=True)
class Matrix:
    """The classified pairs of links that have collision geometry, and how they were found."""

    samples: int
    seed: int
    pairs: tuple[Pair, ...] = ()
    poses: dict = field(default_factory=dict)  # pose -> [[a, b, depth m], ...]: every pair in contact there

    def disabled(self) -> list[Pair]:
        return [p for p in self.pairs if p.disabled]

    def disabled_set(self) -> set[frozenset]:
        return {frozenset((p.a, p.b)) for p in self.pairs if p.disabled}

    def to_json(self) -> dict:
        return {"samples": self.samples, "seed": self.seed, "clearance": CLEARANCE, "always": ALWAYS,
                "poses": self.poses,
                "pairs": [{k: v for k, v in asdict(p).items() if v not in (None, "") or k == "reason"}
                          for p in self.pairs]}

    @classmethod
    def from_json(cls, data: dict) -> "Matrix":
        pairs = tuple(Pair(p["a"], p["b"], p["reason"], p.get("hits", 0), p.get("closest"), p.get("note", ""))
                      for p in data["pairs"])
        return cls(data["samples"], data["seed"], pairs, data.get("poses", {}))

    def dumps(self) -> str:
        return json.dumps(self.to_json(), sort_keys=True)


@dataclass(frozen=True)
class Settings:
    """What the recipe says (``self_collision:``): sample count, seed, pairs forced out and in."""

    samples: int = DEFAULT_SAMPLES
    seed: int = 0
    allow: tuple[tuple[str, str, str], ...] = ()  # (a, b, reason): never checked
    check: tuple[tuple[str, str], ...] = ()  # always checked


class Sampler:
    """A compiled MuJoCo model of the robot's collision geometry with every pair enabled (but the
    adjacent ones), and the joint space to sample.  ``xml`` is MJCF text whose mesh files are
    below ``meshdir``; or ``path``, an MJCF file."""

    def __init__(self, xml: str | None = None, meshdir: str | None = None, path: str | None = None):
        mujoco = load_mujoco()
        spec = mujoco.MjSpec.from_file(path) if path else mujoco.MjSpec.from_string(xml)
        if meshdir:
            spec.meshdir = meshdir
        self.file_excludes = {frozenset((e.bodyname1, e.bodyname2)) for e in spec.excludes}
        for e in list(spec.excludes):
            spec.delete(e)
        for g in spec.geoms:
            on = bool(g.contype or g.conaffinity)
            g.contype, g.conaffinity, g.margin, g.gap = int(on), int(on), 0.0, 0.0
        for b in spec.bodies[1:]:  # geometry only: any positive mass compiles
            b.explicitinertial, b.mass, b.ipos = True, 1.0, [0, 0, 0]
            if np.isnan(b.fullinertia[0]):  # the file's own form: a diagonal, or a full tensor
                b.inertia = [1e-3] * 3
            else:
                b.fullinertia = [1e-3, 1e-3, 1e-3, 0, 0, 0]
        model = spec.compile()
        self.names = [model.body(i).name for i in range(model.nbody)]
        self.has_geoms = {int(b) for b in model.geom_bodyid[(model.geom_contype | model.geom_conaffinity) > 0]}
        self.adjacent = adjacent_bodies(model, self.has_geoms)
        for a, b in sorted(self.adjacent):  # never sampled: their reason is known
            e = spec.add_exclude()
            e.bodyname1, e.bodyname2 = self.names[a], self.names[b]
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self._mujoco = mujoco
        self.space = JointSpace(self.model)

    def contacts(self, q: np.ndarray) -> list[tuple[int, int, float]]:
        """(body a, body b, distance) of every geom contact within the clearance at ``q``."""
        m, d = self.model, self.data
        d.qpos[:] = q
        self._mujoco.mj_kinematics(m, d)
        self._mujoco.mj_collision(m, d)
        n = d.ncon
        if not n:
            return []
        bodies = m.geom_bodyid[d.contact.geom[:n]]
        return [(int(a), int(b), float(dist)) for (a, b), dist in zip(np.sort(bodies, axis=1), d.contact.dist[:n])]

    def colliding(self, q: np.ndarray, tolerance: float = 0.0) -> dict[tuple[str, str], float]:
        """Link pair (names, sorted) -> penetration depth, for the pairs in contact at ``q``
        deeper than ``tolerance``."""
        out: dict = {}
        for a, b, dist in self.contacts(q):
            if dist < -tolerance:
                key = tuple(sorted((self.names[a], self.names[b])))
                out[key] = max(out.get(key, 0.0), -dist)
        return out

    def near(self, samples: np.ndarray, pairs: set[tuple[int, int]]) -> set[tuple[int, int]]:
        """Which of ``pairs`` (body ids, sorted) come within :data:`CLEARANCE` in any of ``samples``:
        the other bodies' geoms switched off and a margin set for this sweep only.  MuJoCo's
        midphase keeps the bounding boxes compiled without the margin (it is switched off here), and
        reports contacts up to the two geoms' margins added (those farther than CLEARANCE are dropped)."""
        m = self.model
        keep = np.isin(m.geom_bodyid, sorted({b for p in pairs for b in p})) & (m.geom_contype > 0)
        saved = m.geom_contype.copy(), m.geom_conaffinity.copy(), m.geom_margin.copy(), m.opt.disableflags
        m.geom_contype[:], m.geom_conaffinity[:] = keep, keep
        m.geom_margin[keep] = CLEARANCE
        m.opt.disableflags |= int(self._mujoco.mjtDisableBit.mjDSBL_MIDPHASE)
        try:
            rows, dist = self.sweep(samples)
        finally:
            m.geom_contype[:], m.geom_conaffinity[:], m.geom_margin[:], m.opt.disableflags = saved
        rows = rows[dist < CLEARANCE]
        return {(int(a), int(b)) for a, b in np.unique(rows[:, 1:], axis=0)} & pairs

    def sweep(self, samples: np.ndarray):
        """Contacts over many configurations: (sample index, body a, body b) rows and distances,
        in sample order.  (Two threads sharing the model were measured no faster: the Python
        bookkeeping between MuJoCo's calls holds the GIL.)"""
        return self._sweep(samples, np.arange(len(samples)), self.data)

    def _sweep(self, samples: np.ndarray, idx: np.ndarray, d):
        m, mj = self.model, self._mujoco
        geoms, dists, which, counts = [], [], [], []
        kinematics, collision, qpos = mj.mj_kinematics, mj.mj_collision, d.qpos
        for i in idx:
            qpos[:] = samples[i]
            kinematics(m, d)
            collision(m, d)
            n = d.ncon
            if n:
                con = d.contact
                geoms.append(con.geom[:n].copy())
                dists.append(con.dist[:n].copy())
                which.append(i)
                counts.append(n)
        if not geoms:
            return np.zeros((0, 3), dtype=int), np.zeros(0)
        bodies = np.sort(m.geom_bodyid[np.concatenate(geoms)], axis=1)
        return np.column_stack([np.repeat(which, counts), bodies]), np.concatenate(dists)


class Approach:
    """The closest approach of one link pair, searched: the distance between their collision
    geoms (``mj_geomDistance``) minimised over the joints on the tree path between them, by a
    pattern search from the closest of the first samples.  Sampling alone misses collisions that
    need several joints just so (two diagonal legs' shins); this finds them."""

    STARTS, FIRST, ROUNDS = 2, 128, 40

    def __init__(self, sampler: Sampler, a: int, b: int):
        m = sampler.model
        self.sampler = sampler
        solid = (m.geom_contype > 0)
        self.pairs = [(int(g1), int(g2)) for g1 in np.flatnonzero((m.geom_bodyid == a) & solid)
                      for g2 in np.flatnonzero((m.geom_bodyid == b) & solid)]
        path = _path_bodies(m, a) ^ _path_bodies(m, b)
        space = sampler.space
        self.cols = [i for i, addr in enumerate(space.addr)
                     if int(m.jnt_bodyid[_joint_at(m, addr)]) in path]

    def distance(self, q: np.ndarray) -> float:
        s = self.sampler
        s.data.qpos[:] = s.space.follow(q.copy())
        s._mujoco.mj_kinematics(s.model, s.data)
        return min(s._mujoco.mj_geomDistance(s.model, s.data, g1, g2, 10.0, None) for g1, g2 in self.pairs)

    def closest(self, samples: np.ndarray) -> float:
        """The smallest distance found (negative: a collision exists); ``self.at`` is where."""
        self.at = None
        if not self.pairs or not self.cols:
            return float("inf")
        first = samples[: self.FIRST]
        ranked = sorted(range(len(first)), key=lambda i: self.distance(first[i]))
        found = [self._descend(first[i].copy()) for i in ranked[: self.STARTS]]
        best, self.at = min(found, key=lambda f: f[0])
        return best

    def _descend(self, q: np.ndarray) -> tuple[float, np.ndarray]:
        space = self.sampler.space
        best = self.distance(q)
        step = 0.1 * (space.hi - space.lo)
        for _ in range(self.ROUNDS):
            if best < 0:
                break
            moved = False
            for i in self.cols:
                for sign in (1.0, -1.0):
                    trial = q.copy()
                    trial[space.addr[i]] = np.clip(q[space.addr[i]] + sign * step[i], space.lo[i], space.hi[i])
                    d = self.distance(trial)
                    if d < best:
                        q, best, moved = trial, d, True
                        break
            if not moved:
                step = step / 2
        return best, self.sampler.space.follow(q)


def _path_bodies(model, body: int) -> set[int]:
    """``body`` and its ancestors (the world excluded)."""
    out = set()
    while body > 0:
        out.add(body)
        body = int(model.body_parentid[body])
    return out


def _joint_at(model, qposadr: int) -> int:
    return int(np.flatnonzero(model.jnt_qposadr == qposadr)[0])


class JointSpace:
    """The sampled joints of a compiled model: their qpos addresses and ranges (a continuous
    hinge over one turn), the mimic couplings (joint equalities), the named poses (keyframes)."""

    def __init__(self, model):
        mujoco = load_mujoco()
        self.qpos0 = model.qpos0.copy()
        self.names, self.addr, self.lo, self.hi = [], [], [], []
        for j in range(model.njnt):
            kind = int(model.jnt_type[j])
            if kind not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
                continue
            if model.jnt_limited[j]:
                lo, hi = model.jnt_range[j]
            elif kind == int(mujoco.mjtJoint.mjJNT_HINGE):
                lo, hi = -np.pi, np.pi
            else:
                continue  # an unlimited slide (a planar base): held
            self.names.append(model.joint(j).name)
            self.addr.append(int(model.jnt_qposadr[j]))
            self.lo.append(float(lo))
            self.hi.append(float(hi))
        self.lo, self.hi = np.array(self.lo), np.array(self.hi)
        self.mimic = []  # (follower qpos address, leader qpos address, offset, multiplier)
        for e in range(model.neq):
            if int(model.eq_type[e]) == int(mujoco.mjtEq.mjEQ_JOINT) and model.eq_obj2id[e] >= 0:
                c = model.eq_data[e]
                self.mimic.append((int(model.jnt_qposadr[model.eq_obj1id[e]]),
                                   int(model.jnt_qposadr[model.eq_obj2id[e]]), float(c[0]), float(c[1])))
        followers = {f for f, *_ in self.mimic}
        keep = [i for i, a in enumerate(self.addr) if a not in followers]
        self.names = [self.names[i] for i in keep]
        self.addr, self.lo, self.hi = np.array([self.addr[i] for i in keep], dtype=int), self.lo[keep], self.hi[keep]
        self.poses = {model.key(k).name or f"key{k}": self.follow(model.key_qpos[k].copy()) for k in range(model.nkey)}

    def follow(self, q: np.ndarray) -> np.ndarray:
        for f, leader, offset, mult in self.mimic:
            q[..., f] = offset + mult * q[..., leader]
        return q

    def zero(self) -> np.ndarray:
        q = self.qpos0.copy()
        q[self.addr] = np.clip(0.0, self.lo, self.hi)
        return self.follow(q)

    def random(self, n: int, seed: int) -> np.ndarray:
        rng = np.random.default_rng(seed)
        q = np.tile(self.qpos0, (n, 1))
        q[:, self.addr] = self.lo + (self.hi - self.lo) * rng.random((n, len(self.addr)))
        return self.follow(q)

    def held(self, pose: np.ndarray) -> np.ndarray:
        """A named pose's configuration with the base at the model's reference (self-collision
        depends on the joints only)."""
        q = self.qpos0.copy()
        q[self.addr] = pose[self.addr]
        return self.follow(q)


def adjacent_bodies(model, has_geoms: set[int]) -> set[tuple[int, int]]:
    """Body pairs (a < b, both with collision geometry) MoveIt calls Adjacent: welded together,
    or with one moving joint between their welded groups, passing through groups without
    collision geometry."""
    weld = [int(w) for w in model.body_weldid]
    parent = [int(p) for p in model.body_parentid]
    groups: dict[int, list[int]] = {}
    for b in range(model.nbody):
        groups.setdefault(weld[b], []).append(b)
    edges: dict[int, set[int]] = {g: set() for g in groups}
    for g in groups:
        if g != 0:
            up = weld[parent[g]]
            edges[g].add(up)
            edges[up].add(g)
    solid = {g for g, bodies in groups.items() if any(b in has_geoms for b in bodies)}

    def neighbours(g: int) -> set[int]:
        """The solid groups one joint away, walking on through empty ones."""
        seen, todo, out = {g}, list(edges[g]), set()
        while todo:
            h = todo.pop()
            if h in seen:
                continue
            seen.add(h)
            if h in solid:
                out.add(h)
            else:
                todo.extend(edges[h])
        return out

    near = {g: neighbours(g) | {g} for g in solid}
    out = set()
    bodies = sorted(has_geoms)
    for i, a in enumerate(bodies):
        for b in bodies[i + 1:]:
            if weld[b] in near[weld[a]]:
                out.add((a, b))
    return out


def classify(sampler: Sampler, settings: Settings) -> Matrix:
    """Sample ``settings.samples`` configurations and classify every pair of links with collision
    geometry (module docstring)."""
    space, names = sampler.space, sampler.names
    samples = space.random(settings.samples, settings.seed) if len(space.addr) else space.zero()[None, :]
    rows, dist = sampler.sweep(samples)
    nb = len(names)
    key = rows[:, 1] * nb + rows[:, 2]
    hit = dist < 0
    hits = np.bincount(np.unique(rows[hit, 0] * nb * nb + key[hit]) % (nb * nb), minlength=nb * nb)
    closest = np.full(nb * nb, np.inf)
    np.minimum.at(closest, key, dist)
    untouched = {(a, b) for a, b in _pairs(sampler) if not np.isfinite(closest[a * nb + b])}
    # pairs never in contact: near in a sample (a second sweep with the clearance as margin, worth
    # its cost when many pairs would otherwise each be searched), else by a searched closest approach
    near = sampler.near(samples, untouched) if len(untouched) > SEARCH_ONLY else set()
    for a, b in sorted(untouched - near):
        if Approach(sampler, a, b).closest(samples) < CLEARANCE:
            near.add((a, b))
    at_zero = sampler.colliding(space.zero())
    allow = {frozenset(p[:2]): p[2] for p in settings.allow}
    check = {frozenset(p) for p in settings.check}
    pairs = []
    bodies = sorted(sampler.has_geoms, key=lambda b: names[b])
    for i, a in enumerate(bodies):
        for b in bodies[i + 1:]:
            lo, hi = min(a, b), max(a, b)
            k = lo * nb + hi
            ab = tuple(sorted((names[a], names[b])))
            reason = _reason((lo, hi) in sampler.adjacent, allow.get(frozenset(ab)), ab in at_zero,
                             hits[k] / len(samples), np.isfinite(closest[k]) or (lo, hi) in near)
            if frozenset(ab) in check:
                reason = ""
            pairs.append(Pair(ab[0], ab[1], reason, int(hits[k]),
                              round(float(closest[k]), 6) if np.isfinite(closest[k]) else None,
                              allow.get(frozenset(ab)) or ""))
    poses = {name: [[a, b, round(depth, 6)] for (a, b), depth in sorted(sampler.colliding(space.held(q)).items())]
             for name, q in sorted(space.poses.items())}
    return Matrix(len(samples), settings.seed, tuple(pairs), poses)


def _pairs(sampler: Sampler) -> list[tuple[int, int]]:
    bodies = sorted(sampler.has_geoms)
    return [(a, b) for i, a in enumerate(bodies) for b in bodies[i + 1:] if (a, b) not in sampler.adjacent]


def _reason(adjacent: bool, allowed: str | None, at_zero: bool, fraction: float, near: bool) -> str:
    if adjacent:
        return "Adjacent"
    if allowed is not None:
        return "User"
    if at_zero:
        return "Default"
    if fraction >= ALWAYS:
        return "Always"
    return "" if near else "Never"


def apply(robot, matrix: Matrix):
    """The robot carrying its matrix (the emitters write it)."""
    from dataclasses import replace

    return replace(robot, collision_matrix=matrix)


def solve_masks(nodes: list[str], enabled: set[frozenset], free: set[frozenset], bits: int = 16) -> dict | None:
    """Collide bit masks (Gazebo's ``collide_bitmask``: two collisions touch when their masks share
    a bit) that make exactly the ``enabled`` pairs of ``nodes`` collide; pairs in ``free`` may do
    either (Gazebo filters them itself); every node gets a bit (the ground collides with any).
    Greedy clique cover of the enabled-or-free graph; None when it needs more than ``bits`` bits."""
    ok = enabled | free

    def fits(v: str, clique: list[str]) -> bool:
        return all(frozenset((v, u)) in ok for u in clique)

    cliques: list[list[str]] = []
    covered: set[frozenset] = set()
    for pair in sorted(enabled, key=sorted):
        if pair in covered:
            continue
        clique = sorted(pair)
        for v in nodes:  # grow it with the nodes that have enabled pairs into it first
            if v not in clique and fits(v, clique) and any(frozenset((v, u)) in enabled for u in clique):
                clique.append(v)
        cliques.append(clique)
        covered |= {frozenset((u, v)) for u in clique for v in clique if u != v}
    for v in nodes:
        if not any(v in c for c in cliques):
            home = next((c for c in cliques if fits(v, c) and not any(frozenset((v, u)) in enabled for u in c)
                         and all(frozenset((v, u)) in free for u in c)), None)
            if home is not None:
                home.append(v)
            else:
                cliques.append([v])
    if len(cliques) > bits:
        return None
    return {v: sum(1 << i for i, c in enumerate(cliques) if v in c) for v in nodes}
