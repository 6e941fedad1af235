"""The self-collision matrix holds up outside the sampler that made it.

- An independent sampler (Pinocchio + coal on the URDF, another seed, twice the build's sample
  count) finds no collision of a pair the SRDF calls Never; every pair of links joined by a joint
  is disabled as Adjacent; the MJCF excludes exactly the SRDF's disabled pairs; no checked pair
  is in collision at a named pose (SRDF group_state).
- The 1 cm clearance, replayed at the build's own samples with coal's distances: a Never pair never
  comes within it, a checked pair no sample put in contact does (in a sample, or where the build's
  closest-approach search put it).
- Pinocchio (URDF + SRDF) and MuJoCo (the built MJCF, its excludes) report the same colliding
  link pairs at 1000 random configurations, but for pairs less than :data:`DEPTH_TOLERANCE` deep.
- Gazebo reads model.sdf (``self_collide``, ``collide_bitmask``), and the masks robotkit solves
  make exactly the checked pairs share a bit.

The convex collision pieces are given to coal as convex shapes (GJK/EPA, as MuJoCo collides a mesh
as its convex hull); Pinocchio's URDF reader loads them as BVH triangle meshes otherwise.
Measured (2 cores, load 2, 2026-11-26): 20,000 configurations over the quadrupeds' 50 Never pairs
take 0.5-0.6 s each; ur5 has one Never pair (wrist_1_link-wrist_3_link, 13.9 mm apart at the
closest; 14 of its 15 pairs of links that are not adjacent collide in some sample).  At 1000
configurations Pinocchio and MuJoCo agree exactly on every one (ur5: 259 with a collision,
quadruped_compact 17, quadruped_explorer 120); depths differ by at most 3 mm."""

from __future__ import annotations

import json
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from validators import IN_CI, ign_sdf_check

pytestmark = pytest.mark.consumers

ROBOTS = ["ur5", "quadruped_compact", "quadruped_explorer"]
EXAMPLES = ROBOTS + ["turret_bot", "rover", "turtlebot3_burger", "lidar_mast"]
SAMPLES = 20000
"""Independent samples: twice MoveIt's (and the build's) 10,000."""
SEED = 20261126
AGREEMENT_SAMPLES = 1000
DEPTH_TOLERANCE = 1e-3
"""m: a pair in contact less deep than this in one program and not at all in the other is numerical
tolerance (GJK/EPA against MuJoCo's own box and mesh colliders), not a disagreement."""


def need(module: str):
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        if IN_CI:
            pytest.fail(f"{module} is not installed (scripts/test.sh installs it)")
        pytest.skip(f"{module} is not installed")


@pytest.fixture(scope="module")
def built(examples) -> Path:
    """The examples, built once per session (folders OUT/<robot>)."""
    return examples


# ---------------------------------------------------------------------------------------- readers


def pair(a: str, b: str) -> tuple[str, str]:
    return (a, b) if a <= b else (b, a)


def srdf_disabled(out: Path, robot: str) -> dict[tuple[str, str], str]:
    """The SRDF's disabled pairs -> reason."""
    root = ET.parse(out / robot / "srdf" / f"{robot}.srdf").getroot()
    return {pair(e.get("link1"), e.get("link2")): e.get("reason") for e in root.iter("disable_collisions")}


def srdf_poses(out: Path, robot: str) -> dict[str, dict[str, float]]:
    root = ET.parse(out / robot / "srdf" / f"{robot}.srdf").getroot()
    return {s.get("name"): {j.get("name"): float(j.get("value")) for j in s.iter("joint")}
            for s in root.iter("group_state")}


def mjcf_excludes(out: Path, robot: str) -> set[tuple[str, str]]:
    root = ET.parse(out / robot / "mjcf" / f"{robot}.xml").getroot()
    return {pair(e.get("body1"), e.get("body2")) for e in root.iter("exclude")}


def urdf_adjacent(out: Path, robot: str) -> set[tuple[str, str]]:
    """Pairs of links with collision geometry joined by a joint, or through links without any
    (MoveIt's adjacency), read from the URDF alone."""
    root = ET.parse(out / robot / "urdf" / f"{robot}.urdf").getroot()
    solid = {link.get("name") for link in root.findall("link") if link.find("collision") is not None}
    edges: dict[str, set[str]] = {}
    for j in root.findall("joint"):  # the robot's joints (not a transmission's)
        a, b = j.find("parent").get("link"), j.find("child").get("link")
        edges.setdefault(a, set()).add(b)
        edges.setdefault(b, set()).add(a)
    out_pairs = set()
    for start in solid:
        seen, todo = {start}, list(edges.get(start, ()))
        while todo:
            v = todo.pop()
            if v in seen:
                continue
            seen.add(v)
            if v in solid:
                out_pairs.add(pair(start, v))
            else:
                todo.extend(edges.get(v, ()))
    return out_pairs


# ------------------------------------------------------------------------------------- Pinocchio


class Pin:
    """The URDF in Pinocchio with its collision geometry in coal (convex pieces as convex shapes)."""

    def __init__(self, out: Path, robot: str):
        self.pin = pin = need("pinocchio")
        coal = need("coal")
        urdf = str(out / robot / "urdf" / f"{robot}.urdf")
        self.srdf = str(out / robot / "srdf" / f"{robot}.srdf")
        self.model = pin.buildModelFromUrdf(urdf)
        self.geom = pin.buildGeomFromUrdf(self.model, urdf, pin.COLLISION, package_dirs=[str(out)])
        for g in self.geom.geometryObjects:
            if isinstance(g.geometry, coal.BVHModelBase):
                g.geometry.buildConvexRepresentation(False)
                g.geometry = g.geometry.convex
        self.link = [self.model.frames[g.parentFrame].name for g in self.geom.geometryObjects]
        self.data = self.model.createData()
        self.joints = [self.model.names[j] for j in range(1, self.model.njoints)]

    def keep(self, pairs: set[tuple[str, str]] | None = None):
        """Collision pairs: every pair of geometries on different joints minus the SRDF's disabled
        ones (``pairs`` None), or only those between ``pairs`` of links."""
        pin = self.pin
        self.geom.removeAllCollisionPairs()
        if pairs is None:
            self.geom.addAllCollisionPairs()
            pin.removeCollisionPairs(self.model, self.geom, self.srdf)
        else:
            objects = self.geom.geometryObjects
            for i in range(len(objects)):
                for j in range(i + 1, len(objects)):
                    if (objects[i].parentJoint != objects[j].parentJoint
                            and pair(self.link[i], self.link[j]) in pairs):
                        self.geom.addCollisionPair(pin.CollisionPair(i, j))
        self.gdata = pin.GeometryData(self.geom)
        for r in self.gdata.collisionRequests:
            r.enable_contact = True

    def random(self, n: int, seed: int) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """``n`` configurations uniform within the URDF's limits (a continuous joint over one turn):
        Pinocchio's q and each joint's angle by name."""
        m, rng = self.model, np.random.default_rng(seed)
        qs = np.tile(self.pin.neutral(m), (n, 1))
        angles = {}
        for j, name in enumerate(self.joints, start=1):
            iq, nq = m.idx_qs[j], m.nqs[j]
            lo, hi = m.lowerPositionLimit[iq], m.upperPositionLimit[iq]
            if nq == 2 or not (np.isfinite(lo) and np.isfinite(hi)):
                lo, hi = -np.pi, np.pi
            a = lo + (hi - lo) * rng.random(n)
            if nq == 2:
                qs[:, iq], qs[:, iq + 1] = np.cos(a), np.sin(a)
            else:
                qs[:, iq] = a
            angles[name] = a
        return qs, angles

    def at(self, values: dict[str, float]) -> np.ndarray:
        q = self.pin.neutral(self.model)
        for name, v in values.items():
            j = self.model.getJointId(name)
            iq = self.model.idx_qs[j]
            if self.model.nqs[j] == 2:
                q[iq], q[iq + 1] = np.cos(v), np.sin(v)
            else:
                q[iq] = v
        return q

    def colliding(self, q: np.ndarray) -> dict[tuple[str, str], float]:
        """Link pair -> penetration depth (m) of the kept pairs in collision at ``q``."""
        if not self.pin.computeCollisions(self.model, self.data, self.geom, self.gdata, q, False):
            return {}
        out: dict = {}
        for k, cp in enumerate(self.geom.collisionPairs):
            res = self.gdata.collisionResults[k]
            if res.isCollision():
                key = pair(self.link[cp.first], self.link[cp.second])
                depth = max((-c.penetration_depth for c in res.getContacts()), default=0.0)
                out[key] = max(out.get(key, 0.0), depth)
        return out


class MuJoCo:
    """The built MJCF as a user loads it (its excludes, MuJoCo's own filters)."""

    def __init__(self, out: Path, robot: str):
        self.mj = mj = need("mujoco")
        self.model = mj.MjModel.from_xml_path(str(out / robot / "mjcf" / f"{robot}.xml"))
        self.data = mj.MjData(self.model)
        self.body = [self.model.body(b).name for b in range(self.model.nbody)]

    def colliding(self, angles: dict[str, float]) -> dict[tuple[str, str], float]:
        m, d, mj = self.model, self.data, self.mj
        d.qpos[:] = m.qpos0  # a free base stays where the model puts it
        for name, v in angles.items():
            d.qpos[m.jnt_qposadr[m.joint(name).id]] = v
        mj.mj_kinematics(m, d)
        mj.mj_collision(m, d)
        out: dict = {}
        for i in range(d.ncon):
            c = d.contact[i]
            if c.dist < 0:
                key = pair(self.body[m.geom_bodyid[c.geom[0]]], self.body[m.geom_bodyid[c.geom[1]]])
                out[key] = max(out.get(key, 0.0), -float(c.dist))
        return out


# ----------------------------------------------------------------------------------------- tests


@pytest.mark.slow
@pytest.mark.parametrize("robot", ROBOTS)
def test_never_pairs_never_collide_in_an_independent_sampler(built, robot):
    report = json.loads((built / robot / "report.json").read_text())["self_collision"]
    assert report["seed"] != SEED and SAMPLES >= 2 * report["samples"]
    never = {p for p, reason in srdf_disabled(built, robot).items() if reason == "Never"}
    p = Pin(built, robot)
    p.keep(never)
    qs, _ = p.random(SAMPLES, SEED)
    start, found = time.perf_counter(), {}
    for i, q in enumerate(qs):
        for key, depth in p.colliding(q).items():
            found.setdefault(key, (i, depth))
    seconds = time.perf_counter() - start
    assert not found, (f"{robot}: pairs the SRDF calls Never collide in Pinocchio/coal (pair: first sample, "
                       f"depth m): {found}; {len(never)} Never pairs, {SAMPLES} samples in {seconds:.1f} s")


@pytest.mark.slow
@pytest.mark.parametrize("robot", ROBOTS)
def test_the_clearance_rule_holds_at_the_builds_own_samples(built, robot):
    """Never means never within :data:`CLEARANCE`, and a checked pair no sample put in contact came
    within it, in a sample or where the build's closest-approach search put it: coal's distances at
    the build's own samples (robotkit's JointSpace replaying them) and at the searched configuration."""
    from robotkit.model.selfcollision import CLEARANCE, Approach, Sampler

    report = json.loads((built / robot / "report.json").read_text())["self_collision"]
    never = {pair(q["a"], q["b"]) for q in report["pairs"] if q["reason"] == "Never"}
    untouched = {pair(q["a"], q["b"]) for q in report["pairs"] if not q["reason"] and not q.get("hits")}
    sampler = Sampler(path=str(built / robot / "mjcf" / f"{robot}.xml"))
    space = sampler.space
    samples = space.random(report["samples"], report["seed"])
    p = Pin(built, robot)
    p.keep(never | untouched)

    def pin_q(mj_samples):
        qs = np.tile(p.pin.neutral(p.model), (len(mj_samples), 1))
        for name in p.joints:  # the examples' joints are revolute with limits: one coordinate each
            j = p.model.getJointId(name)
            qs[:, p.model.idx_qs[j]] = mj_samples[:, space.addr[space.names.index(name)]]
        return qs

    qs = pin_q(samples)
    keys = [pair(p.link[cp.first], p.link[cp.second]) for cp in p.geom.collisionPairs]
    closest = dict.fromkeys(never | untouched, np.inf)
    for q in qs:
        p.pin.computeDistances(p.model, p.data, p.geom, p.gdata, q)
        for k, r in zip(keys, p.gdata.distanceResults):
            closest[k] = min(closest[k], r.min_distance)
    tolerance = 1e-4
    ids = {n: i for i, n in enumerate(sampler.names)}
    for k in [k for k in untouched if closest[k] > CLEARANCE + tolerance]:  # the search found them near
        a, b = sorted(ids[n] for n in k)
        search = Approach(sampler, a, b)
        search.closest(samples)
        p.pin.computeDistances(p.model, p.data, p.geom, p.gdata, pin_q(search.at[None, :])[0])
        closest[k] = min(r.min_distance for key, r in zip(keys, p.gdata.distanceResults) if key == k)
    assert ({k: round(closest[k], 4) for k in never if closest[k] < CLEARANCE - tolerance},
            {k: round(closest[k], 4) for k in untouched if closest[k] > CLEARANCE + tolerance}) == ({}, {})


@pytest.mark.slow
@pytest.mark.parametrize("robot", EXAMPLES)
def test_links_joined_by_a_joint_are_disabled_as_adjacent(built, robot):
    disabled = srdf_disabled(built, robot)
    adjacent = urdf_adjacent(built, robot)
    assert adjacent
    assert {p: disabled.get(p) for p in adjacent} == {p: "Adjacent" for p in adjacent}


@pytest.mark.slow
@pytest.mark.parametrize("robot", EXAMPLES)
def test_mjcf_excludes_exactly_the_srdf_disabled_pairs(built, robot):
    disabled = set(srdf_disabled(built, robot))
    excludes = mjcf_excludes(built, robot)
    assert excludes == disabled, {"only in the MJCF": excludes - disabled, "only in the SRDF": disabled - excludes}
    report = json.loads((built / robot / "report.json").read_text())["self_collision"]
    assert {pair(q["a"], q["b"]) for q in report["pairs"] if q["reason"]} == disabled


@pytest.mark.slow
@pytest.mark.parametrize("robot", ROBOTS)
def test_no_checked_pair_collides_at_a_named_pose(built, robot):
    poses = srdf_poses(built, robot)
    assert poses
    p = Pin(built, robot)
    p.keep()
    assert {name: p.colliding(p.at(values)) for name, values in poses.items()} == {name: {} for name in poses}


@pytest.mark.slow
@pytest.mark.parametrize("robot", ROBOTS)
def test_pinocchio_and_mujoco_report_the_same_colliding_pairs(built, robot):
    p, m = Pin(built, robot), MuJoCo(built, robot)
    p.keep()
    qs, angles = p.random(AGREEMENT_SAMPLES, SEED + 1)
    agree, excused, differ, depth_diff, in_contact = 0, 0, [], [], 0
    for i, q in enumerate(qs):
        a = p.colliding(q)
        b = m.colliding({name: v[i] for name, v in angles.items()})
        in_contact += bool(a or b)
        depth_diff += [abs(a[k] - b[k]) for k in a.keys() & b.keys()]
        odd = {k: (a.get(k), b.get(k)) for k in a.keys() ^ b.keys()}
        if not odd:
            agree += 1
        elif all(max(d for d in depths if d is not None) < DEPTH_TOLERANCE for depths in odd.values()):
            excused += 1
        else:
            differ.append((i, odd))
    assert not differ, (
        f"{robot}: {agree} of {AGREEMENT_SAMPLES} configurations agree exactly, {excused} within "
        f"{DEPTH_TOLERANCE * 1000:g} mm of depth, {len(differ)} disagree (sample: {{pair: (Pinocchio depth, "
        f"MuJoCo depth)}}): {differ[:5]}")
    assert in_contact > 0, f"{robot}: no configuration in collision: the comparison is empty"
    # for the record (pytest -rA shows nothing for a passing test; the message above does on failure)
    print(f"{robot}: {agree} agree exactly, {excused} within tolerance, {in_contact} configurations with "
          f"collisions, depth difference max {max(depth_diff, default=0):.2e} m")


@pytest.mark.slow
@pytest.mark.parametrize("robot", ROBOTS)
def test_gazebo_accepts_model_sdf_with_self_collide_and_bitmasks(built, robot):
    path = built / robot / "model.sdf"
    text = path.read_text()
    assert "<self_collide>true</self_collide>" in text and "<collide_bitmask>" in text
    ign_sdf_check(path)


@pytest.mark.slow
@pytest.mark.parametrize("robot", ROBOTS)
def test_solved_masks_share_a_bit_exactly_for_checked_pairs(built, robot):
    from robotkit.model.selfcollision import Matrix, solve_masks

    matrix = Matrix.from_json(json.loads((built / robot / "report.json").read_text())["self_collision"])
    nodes = sorted({n for q in matrix.pairs for n in (q.a, q.b)})
    enabled = {frozenset((q.a, q.b)) for q in matrix.pairs if not q.disabled}
    free = {frozenset(p) for p in urdf_adjacent(built, robot)}  # Gazebo skips links joined by a joint
    masks = solve_masks(nodes, enabled, free)
    assert masks is not None and all(masks.values())
    assert_masks(masks, nodes, enabled, free)
    # model.sdf carries those masks: each link's collisions have its link's mask
    root = ET.parse(built / robot / "model.sdf").getroot()
    sdf = {link.get("name"): {int(b.text) for b in link.iter("collide_bitmask")} for link in root.iter("link")}
    assert {n: sdf.get(n) for n in nodes} == {n: {masks[n]} for n in nodes}


def assert_masks(masks: dict, nodes: list[str], enabled: set, free: set) -> None:
    for i, a in enumerate(nodes):
        for b in nodes[i + 1:]:
            k = frozenset((a, b))
            if k in enabled:
                assert masks[a] & masks[b], f"{a}-{b} is checked but shares no bit"
            elif k not in free:
                assert not masks[a] & masks[b], f"{a}-{b} is disabled but shares a bit"


def test_solve_masks_on_a_small_matrix():
    """A chain a-b-c-d (joined pairs free) with a-c checked and b-d, a-d disabled; and a matrix
    needing more bits than allowed."""
    from robotkit.model.selfcollision import solve_masks

    nodes = ["a", "b", "c", "d"]
    free = {frozenset(p) for p in ("ab", "bc", "cd")}
    enabled = {frozenset("ac")}
    masks = solve_masks(nodes, enabled, free)
    assert masks is not None and all(masks.values())
    assert_masks(masks, nodes, enabled, free)
    many = [f"n{i}" for i in range(6)]
    everything_but_a_matching = {frozenset((a, b)) for i, a in enumerate(many) for b in many[i + 1:]}
    everything_but_a_matching -= {frozenset(("n0", "n1")), frozenset(("n2", "n3")), frozenset(("n4", "n5"))}
    assert solve_masks(many, everything_but_a_matching, set(), bits=2) is None
    masks = solve_masks(many, everything_but_a_matching, set())
    assert masks is not None
    assert_masks(masks, many, everything_but_a_matching, set())
