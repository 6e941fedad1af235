"""What the self-collision matrix costs: robotkit's Sampler + classify (MuJoCo on the MJCF's
collision geometry) against the straightforward ways of doing the same classification work.

    python benchmarks/bench_selfcollision.py [OUT] [--samples 10000 100000] [--baseline-samples 10000]
                                             [--quick] [--json out.json]

Builds recipes/ur5.yaml and recipes/quadruped.yaml into OUT (default: a temporary folder), then on
ur5, quadruped_compact and quadruped_explorer times:

- **robotkit**: ``Sampler(path=MJCF)`` (compiled once, not timed) and ``classify`` at each sample
  count: every non-adjacent pair in contact per sample, then a 1 cm clearance sweep of the pairs
  never touched, the zero pose and the named poses;
- the same work on the same samples (robotkit's own ``JointSpace.random``, seed 0) with:
  (a) Pinocchio + coal ``computeCollisions`` over every non-adjacent geometry pair, the URDF's
  meshes as Pinocchio loads them (BVH triangle meshes) and as convex shapes; (b) one coal
  ``collide`` call per pair in a Python loop (convex shapes, placements from Pinocchio);
  (c) trimesh's ``CollisionManager`` (python-fcl; primitives tessellated), ``in_collision_internal``
  with names, its hits on adjacent pairs dropped.  (a) and (b) then sweep the untouched pairs again
  with a 1 cm security margin, as robotkit does; trimesh has no margin query: its column is the
  collision pass alone (a lower bound of its cost).

The baselines run on the first ``--baseline-samples`` of the samples (the Python loops would take
minutes at 100,000); times are per configuration, and the ratio is baseline / robotkit per
configuration.  "verdicts" counts the pairs whose Never / not-Never verdict differs from
robotkit's at the same samples (a BVH mesh collides surfaces only: a piece inside another is not in
collision).  One run, no timed assertions.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

ROBOTS = ["ur5", "quadruped_compact", "quadruped_explorer"]
ALWAYS = 0.95


def pair(a: str, b: str) -> tuple[str, str]:
    return (a, b) if a <= b else (b, a)


class Setup:
    """One built robot in Pinocchio (its URDF) and robotkit's Sampler (its MJCF)."""

    def __init__(self, out: Path, robot: str):
        import coal
        import pinocchio as pin

        from robotkit.model.selfcollision import Sampler

        self.pin, self.coal = pin, coal
        d = out / robot
        self.urdf, self.mjcf = str(d / "urdf" / f"{robot}.urdf"), str(d / "mjcf" / f"{robot}.xml")
        self.out = out
        self.sampler = Sampler(path=self.mjcf)
        names = self.sampler.names
        self.adjacent = {pair(names[a], names[b]) for a, b in self.sampler.adjacent}
        self.model = pin.buildModelFromUrdf(self.urdf)
        self.data = self.model.createData()

    def geometry(self, convex: bool):
        pin, coal = self.pin, self.coal
        geom = pin.buildGeomFromUrdf(self.model, self.urdf, pin.COLLISION, package_dirs=[str(self.out)])
        if convex:
            for g in geom.geometryObjects:
                if isinstance(g.geometry, coal.BVHModelBase):
                    g.geometry.buildConvexRepresentation(False)
                    g.geometry = g.geometry.convex
        link = [self.model.frames[g.parentFrame].name for g in geom.geometryObjects]
        return geom, link

    def pairs(self, geom, link, links: set | None = None) -> list[tuple[int, int]]:
        """Geometry pairs on different joints between non-adjacent links (or only ``links`` pairs)."""
        objs = geom.geometryObjects
        out = []
        for i in range(len(objs)):
            for j in range(i + 1, len(objs)):
                key = pair(link[i], link[j])
                if (objs[i].parentJoint != objs[j].parentJoint and key not in self.adjacent
                        and link[i] != link[j] and (links is None or key in links)):
                    out.append((i, j))
        return out

    def to_pinocchio(self, samples: np.ndarray) -> np.ndarray:
        """robotkit's samples (MuJoCo qpos) as Pinocchio configurations, joint by joint."""
        m, mj = self.model, self.sampler.model
        q = np.tile(self.pin.neutral(m), (len(samples), 1))
        for j in range(1, m.njoints):
            a = samples[:, mj.jnt_qposadr[mj.joint(m.names[j]).id]]
            iq = m.idx_qs[j]
            if m.nqs[j] == 2:
                q[:, iq], q[:, iq + 1] = np.cos(a), np.sin(a)
            else:
                q[:, iq] = a
        return q


def verdicts(hits: dict, near: set, n: int, links: set) -> dict:
    """Never / Always / checked of each link pair, from hit counts and the clearance sweep."""
    out = {}
    for k in links:
        h = hits.get(k, 0)
        out[k] = "Always" if h >= ALWAYS * n else ("" if h or k in near else "Never")
    return out


def run_pinocchio(s: Setup, qs: np.ndarray, convex: bool):
    """(a): computeCollisions over every non-adjacent pair, then the untouched ones with a margin."""
    pin = s.pin
    geom, link = s.geometry(convex)

    def sweep(pairs, margin):
        geom.removeAllCollisionPairs()
        for i, j in pairs:
            geom.addCollisionPair(pin.CollisionPair(i, j))
        gd = pin.GeometryData(geom)
        for r in gd.collisionRequests:
            r.security_margin = margin
        keys = [pair(link[cp.first], link[cp.second]) for cp in geom.collisionPairs]
        hits: dict = {}
        results = gd.collisionResults
        for q in qs:
            if pin.computeCollisions(s.model, s.data, geom, gd, q, False):
                for k in {keys[i] for i, r in enumerate(results) if r.isCollision()}:
                    hits[k] = hits.get(k, 0) + 1
        return hits

    t = time.perf_counter()
    pairs = s.pairs(geom, link)
    links = {pair(link[i], link[j]) for i, j in pairs}
    hits = sweep(pairs, 0.0)
    untouched = links - set(hits)
    near = set(sweep(s.pairs(geom, link, untouched), 0.01)) if untouched else set()
    return time.perf_counter() - t, verdicts(hits, near, len(qs), links)


def run_loop(s: Setup, qs: np.ndarray):
    """(b): one coal.collide per geometry pair, in Python."""
    pin, coal = s.pin, s.coal
    geom, link = s.geometry(True)
    gd = pin.GeometryData(geom)
    shapes = [g.geometry for g in geom.geometryObjects]

    def sweep(pairs, margin):
        req = coal.CollisionRequest()
        req.security_margin = margin
        res = coal.CollisionResult()
        keys = [pair(link[i], link[j]) for i, j in pairs]
        hits: dict = {}
        for q in qs:
            pin.updateGeometryPlacements(s.model, s.data, geom, gd, q)
            tf = [coal.Transform3s(M.rotation, M.translation) for M in gd.oMg]
            seen = set()
            for (i, j), k in zip(pairs, keys):
                res.clear()
                if coal.collide(shapes[i], tf[i], shapes[j], tf[j], req, res):
                    seen.add(k)
            for k in seen:
                hits[k] = hits.get(k, 0) + 1
        return hits

    t = time.perf_counter()
    pairs = s.pairs(geom, link)
    links = {pair(link[i], link[j]) for i, j in pairs}
    hits = sweep(pairs, 0.0)
    untouched = links - set(hits)
    near = set(sweep(s.pairs(geom, link, untouched), 0.01)) if untouched else set()
    return time.perf_counter() - t, verdicts(hits, near, len(qs), links)


def run_trimesh(s: Setup, qs: np.ndarray):
    """(c): trimesh's CollisionManager (python-fcl), collision pass only."""
    import trimesh
    from trimesh.collision import CollisionManager

    pin, coal = s.pin, s.coal
    geom, link = s.geometry(False)
    gd = pin.GeometryData(geom)
    meshes = []
    for g in geom.geometryObjects:
        shape = g.geometry
        if isinstance(shape, coal.BVHModelBase):
            v = np.asarray(shape.vertices())
            f = np.array([[t[0], t[1], t[2]] for t in (shape.tri_indices(i) for i in range(shape.num_tris))])
            meshes.append(trimesh.Trimesh(v, f, process=False))
        elif isinstance(shape, coal.Box):
            meshes.append(trimesh.creation.box(extents=2 * np.asarray(shape.halfSide)))
        elif isinstance(shape, coal.Cylinder):
            meshes.append(trimesh.creation.cylinder(radius=shape.radius, height=2 * shape.halfLength))
        elif isinstance(shape, coal.Sphere):
            meshes.append(trimesh.creation.icosphere(radius=shape.radius))
        else:
            raise NotImplementedError(type(shape).__name__)
    names = [f"{i}" for i in range(len(meshes))]
    manager = CollisionManager()
    for name, mesh in zip(names, meshes):
        manager.add_object(name, mesh)
    pairs = s.pairs(geom, link)
    wanted = {(str(i), str(j)): pair(link[i], link[j]) for i, j in pairs}
    wanted.update({(b, a): k for (a, b), k in list(wanted.items())})
    links = set(wanted.values())
    t = time.perf_counter()
    hits: dict = {}
    for q in qs:
        pin.updateGeometryPlacements(s.model, s.data, geom, gd, q)
        for name, M in zip(names, gd.oMg):
            manager.set_transform(name, M.homogeneous)
        hit, found = manager.in_collision_internal(return_names=True)
        if hit:
            for k in {wanted[p] for p in found if p in wanted}:
                hits[k] = hits.get(k, 0) + 1
    return time.perf_counter() - t, verdicts(hits, set(), len(qs), links)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", nargs="?", help="build folder (default: a temporary one)")
    ap.add_argument("--samples", type=int, nargs="+", default=[10000, 100000])
    ap.add_argument("--baseline-samples", type=int, default=10000)
    ap.add_argument("--quick", action="store_true", help="1000 samples, baselines on 200, ur5 only")
    ap.add_argument("--json", help="also write the results to this JSON file")
    args = ap.parse_args(argv)
    if args.quick:
        args.samples, args.baseline_samples = [1000], 200
    robots = ROBOTS[:1] if args.quick else ROBOTS

    from robotkit.model.selfcollision import Settings, classify
    from robotkit.pipeline.runner import build

    try:
        import fcl  # noqa: F401  (trimesh's CollisionManager needs it)
        have_fcl = True
    except ImportError:
        have_fcl = False
        print("python-fcl is not installed (pip install python-fcl): the trimesh column is skipped")
    from importlib import metadata

    versions = {p: metadata.version(p) for p in ("mujoco", "pin", "coal", "trimesh", "python-fcl", "numpy")
                if p != "python-fcl" or have_fcl}
    print(f"# {time.strftime('%Y-%m-%d')}  {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, load {os.getloadavg()[0]:.1f}")
    print("# " + ", ".join(f"{k} {v}" for k, v in versions.items()))

    out = Path(args.out) if args.out else Path(tempfile.mkdtemp())
    recipes = [REPO / "recipes" / "ur5.yaml"] + ([] if args.quick else [REPO / "recipes" / "quadruped.yaml"])
    t = time.perf_counter()
    result = build(recipes, out, report=False)
    assert not result.errors, result.errors
    print(f"build: {time.perf_counter() - t:.2f} s")

    rows = []
    for robot in robots:
        s = Setup(out, robot)
        built = json.loads((out / robot / "report.json").read_text())["self_collision"]
        print(f"\n{robot}: {len(s.sampler.space.addr)} sampled joints, report.json: {built['samples']} samples "
              f"in {built['seconds']:.3f} s (seed {built['seed']})")
        for n in args.samples:
            t = time.perf_counter()
            matrix = classify(s.sampler, Settings(samples=n, seed=0))
            ours = time.perf_counter() - t
            m = min(n, args.baseline_samples)
            samples = s.sampler.space.random(n, 0)[:m]
            ref = {pair(p.a, p.b): p for p in classify(s.sampler, Settings(samples=m, seed=0)).pairs}
            qs = s.to_pinocchio(samples)
            row = {"robot": robot, "samples": n, "baseline_samples": m, "robotkit_s": ours,
                   "robotkit_us": ours / n * 1e6, "never": sum(p.reason == "Never" for p in matrix.pairs)}
            runs = {"pinocchio BVH": lambda: run_pinocchio(s, qs, False),
                    "pinocchio convex": lambda: run_pinocchio(s, qs, True),
                    "coal loop": lambda: run_loop(s, qs)}
            if have_fcl:
                runs["trimesh"] = lambda: run_trimesh(s, qs)
            for name, fn in runs.items():
                seconds, got = fn()
                differ = sum((got[k] == "Never") != (ref[k].reason == "Never") for k in got if k in ref)
                row[name] = {"s": seconds, "us": seconds / m * 1e6, "ratio": seconds / m / (ours / n),
                             "verdicts_differ": differ}
            rows.append(row)
    cols = ["pinocchio BVH", "pinocchio convex", "coal loop"] + (["trimesh"] if have_fcl else [])
    print("\nTime per configuration (µs) and ratio to robotkit's; baselines on the first N' samples; "
          "verdicts: pairs whose Never verdict differs from robotkit's at N'")
    print("| robot | N | robotkit (s) | robotkit (µs/config) | N' | " + " | ".join(cols) + " |")
    print("|---|---:|---:|---:|---:|" + "---|" * len(cols))
    for r in rows:
        cells = [f"{r[c]['us']:.0f} ({r[c]['ratio']:.1f}×, {r[c]['verdicts_differ']})" for c in cols]
        print(f"| {r['robot']} | {r['samples']:,} | {r['robotkit_s']:.2f} | {r['robotkit_us']:.1f} | "
              f"{r['baseline_samples']:,} | " + " | ".join(cells) + " |")
    if not have_fcl:
        print("trimesh: skipped (python-fcl is not installed)")
    if args.json:
        Path(args.json).write_text(json.dumps({"rows": rows, "versions": versions}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
