"""Decimation side by side: robotkit (MeshLib alone, as called plainly, since issue 33), robotkit
with its shortcuts (``shortcuts=True``: a meshoptimizer first pass or MeshLib's fast stage, and a
heuristic check) against meshlib called plainly, meshoptimizer alone, fast-simplification
(robotkit's library before MeshLib) and pymeshlab (MeshLab, the tool a user would otherwise
use), on every visual mesh of the examples (recipes/meshes), of ``tests/data/meshes`` (the
Panda's CAD meshes) and of the robots in ../shared/assets (CAD meshes of many components and
open edges among them: the Kinova, Fanuc, Motoman and Shadow hand meshes).

The side by side is fair: every tool starts from the same loaded arrays (loading is not timed
for any), gets the same target, and its time covers its own conversions in and out: robotkit's
the whole ``decimate`` call from a trimesh (edge census, volumes, MeshLib's mesh build, the
decimation, the result back in numpy); MeshLib's the mesh build, ``decimateMesh`` and the
arrays out; pymeshlab's ``MeshSet``, ``add_mesh``, the filter and the matrices out.

Per mesh and tool, in a child process of its own (pymeshlab crashes on some inputs): load it once
(robotkit.mesh.io.load_mesh: metres, coincident vertices merged), decimate it with every
tool to the same target (a fraction of its faces), take the best of ``--repeat`` runs for wall time (``time.perf_counter``) and CPU time (``time.process_time``:
every thread of the process, so a threaded library is not flattered on a shared machine),
and measure the result independently of robotkit's code.  Each tool runs in a process of its
own, so that no library's idle worker threads (MeshLib's TBB pool spins for a while after its
work) count in another tool's CPU time:

- faces: the result's face count against the target (within 2 %?);
- closed: closed before -> closed after (every edge used twice in opposite directions);
- Hausdorff: two-sided, sampled: ``--samples`` area-uniform points on each surface, their
  distance to the other surface by ``trimesh.proximity.closest_point`` (R-tree), on copies
  scaled to a 1000-unit bounding-box diagonal (trimesh's closest-point test has an absolute
  tolerance of 1e-12 on squared lengths: wrong by up to the triangle size for triangles
  under ~1e-2 units), reported over the diagonal.

Prints the load average before and after, one row per mesh (faces, wall ms, Hausdorff) and
a summary: targets reached, closed meshes kept closed, robotkit's Hausdorff over plain
meshlib's, every tool's wall and CPU time over robotkit's (median and over the sum of
times), how often robotkit's quality check sent it to MeshLib alone (issue 33), and robotkit's
Hausdorff over pymeshlab's.  ``python benchmarks/bench_decimate.py [--keep 0.1 | --faces 3000]
[--repeat 3] [--samples 5000] [--json out.json] [--only SUBSTRING,SUBSTRING]
[--pymeshlab-python PY]`` (``PY``: an interpreter with pymeshlab, where this one has none).
The meshes of ``tests/data/meshes`` (the Panda's link0 and link4) are included; ``--extra DIR,...``
adds folders (the Panda's nine visual meshes, issue 33: ``pip download example-robot-data==6.0.0
--no-deps``, unzip, and give ``.../robots/panda_description/meshes/visual``; a file with the same
bytes as one before is left out).  ``meshlib-1thread`` is MeshLib called plainly with its TBB
limited to one thread, as robotkit limits it: the same work on the same core count, where
``meshlib`` uses every core.  Each result's bytes are hashed, and the summary says on how many
meshes robotkit's result is MeshLib's, byte for byte.  Needs ``pip install pymeshlab
meshoptimizer fast-simplification`` (benchmark only).
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # this checkout's robotkit, not the one installed in the venv
ASSETS = REPO.parent / "shared" / "assets"
if not ASSETS.is_dir():
    ASSETS = Path("/work/shared/assets")


def visual_meshes(extra: list[str] = ()) -> list[str]:
    """The visual meshes of the examples, ``tests/data/meshes``, shared/assets and the ``extra``
    folders (``--extra``), each file once (a file with the same bytes as one before is left out:
    the Panda's link0 and link4 are in ``tests/data`` and in the wheel's folder)."""
    import hashlib

    out, seen = [], set()
    for root in (REPO / "recipes" / "meshes", REPO / "tests" / "data" / "meshes", ASSETS, *extra):
        for p in sorted(glob.glob(str(root) + "/**/*", recursive=True)):
            low = p.lower()
            if low.endswith((".stl", ".dae", ".obj")) and "collision" not in low and "/maps/" not in low:
                digest = hashlib.sha256(Path(p).read_bytes()).hexdigest()
                if digest not in seen:
                    seen.add(digest)
                    out.append(p)
    return out


# --- the tools: (V float64, F int64, target) -> (V, F) ---------------------------------------

def t_robotkit(V, F, target):
    import trimesh

    from robotkit.mesh.decimate import decimate

    out, _ = decimate(trimesh.Trimesh(V, F, process=False), target_faces=target, samples=0)
    return out.vertices, out.faces


def t_robotkit_shortcuts(V, F, target):
    import trimesh

    from robotkit.mesh.decimate import decimate

    out, _ = decimate(trimesh.Trimesh(V, F, process=False), target_faces=target, samples=0, shortcuts=True)
    return out.vertices, out.faces


def t_meshlib(V, F, target):
    import meshlib.mrmeshnumpy as mn
    import meshlib.mrmeshpy as mm
    import numpy as np

    m = mn.meshFromFacesVerts(F.astype(np.int32), V.astype(np.float32))
    s = mm.DecimateSettings()
    s.strategy = mm.DecimateStrategy.MinimizeError
    s.maxError = float("inf")
    s.maxDeletedFaces = max(m.topology.numValidFaces() - target, 0)
    s.packMesh = True  # MeshLib's defaults otherwise, as a user would call it
    mm.decimateMesh(m, s)
    return mn.getNumpyVerts(m).astype(np.float64), mn.getNumpyFaces(m.topology)


def t_meshlib_one_thread(V, F, target):
    """MeshLib called plainly, its TBB limited to one thread for this process as robotkit limits
    it (robotkit's builds decimate meshes in parallel processes, one per core): the same work
    as robotkit's, on one core."""
    from robotkit.mesh.decimate import _meshlib_single_threaded

    _meshlib_single_threaded()
    return t_meshlib(V, F, target)


def t_meshoptimizer(V, F, target):
    import meshoptimizer
    import numpy as np

    idx = F.astype(np.uint32).ravel()
    dest = np.zeros_like(idx)
    n = meshoptimizer.simplify(dest, idx, V.astype(np.float32), target_index_count=3 * target, target_error=1.0)
    f = dest[:n].reshape(-1, 3).astype(np.int64)
    used = np.unique(f)
    remap = np.zeros(len(V), np.int64)
    remap[used] = np.arange(len(used))
    return V[used], remap[f]


def t_fast_simplification(V, F, target):
    import fast_simplification
    import numpy as np

    c = 0.5 * (V.min(0) + V.max(0))
    k = 1000.0 / (np.linalg.norm(np.ptp(V, 0)) or 1.0)  # what robotkit did before
    v, f = fast_simplification.simplify((V - c) * k, F.astype(np.int32), target_count=target, agg=7.0)
    return v / k + c, f


PYMESHLAB_WORKER = """
import sys, time, numpy as np, pymeshlab
d = np.load(sys.argv[1]); V, F, target, repeat = d["V"], d["F"], int(d["target"]), int(d["repeat"])
def run():
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F))
    ms.meshing_decimation_quadric_edge_collapse(targetfacenum=target)
    m = ms.current_mesh()
    return m.vertex_matrix(), m.face_matrix()
run()
ts, cs = [], []
for _ in range(repeat):
    t, c = time.perf_counter(), time.process_time()
    v, f = run()
    cs.append(time.process_time() - c); ts.append(time.perf_counter() - t)
np.savez(sys.argv[2], V=v, F=f, time=min(ts), cpu=min(cs))
"""


def pymeshlab_elsewhere(python: str, V, F, target: int, repeat: int) -> dict:
    """pymeshlab in another interpreter (``--pymeshlab-python``: a venv of its own, where the
    project's venv has none): the same calls, warm-up and best-of-``repeat`` timing, in the child."""
    import tempfile

    import numpy as np

    with tempfile.TemporaryDirectory() as tmp:
        src, dst = os.path.join(tmp, "in.npz"), os.path.join(tmp, "out.npz")
        np.savez(src, V=V, F=F, target=target, repeat=repeat)
        proc = subprocess.run([python, "-c", PYMESHLAB_WORKER, src, dst], capture_output=True, timeout=900)
        if proc.returncode != 0 or not os.path.exists(dst):
            return {"error": f"crashed (exit {proc.returncode})"}
        d = np.load(dst)
        return {"V": d["V"], "F": d["F"], "time": float(d["time"]), "cpu": float(d["cpu"])}


def t_pymeshlab(V, F, target):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F))
    ms.meshing_decimation_quadric_edge_collapse(targetfacenum=target)
    m = ms.current_mesh()
    return m.vertex_matrix(), m.face_matrix()


TOOLS = {"robotkit": t_robotkit, "robotkit-shortcuts": t_robotkit_shortcuts, "meshlib": t_meshlib,
         "meshlib-1thread": t_meshlib_one_thread, "meshoptimizer": t_meshoptimizer,
         "fast-simplification": t_fast_simplification, "pymeshlab": t_pymeshlab}


def result_digest(v, f) -> str:
    """A digest of a result's bytes (float64 vertices, int64 faces), to tell the same result."""
    import hashlib

    import numpy as np

    h = hashlib.sha256(np.ascontiguousarray(v, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(f, dtype=np.int64).tobytes())
    return h.hexdigest()[:16]


def is_closed(F) -> bool:
    import numpy as np

    F = np.asarray(F, dtype=np.int64)
    if len(F) < 4:
        return False
    a, b = F.ravel(), np.roll(F, -1, axis=1).ravel()
    if (a == b).any():
        return False
    n = int(max(a.max(), b.max())) + 1
    directed = np.unique(a * n + b, return_counts=True)
    if (directed[1] > 1).any():
        return False
    und = np.unique(np.minimum(a, b) * n + np.maximum(a, b), return_counts=True)[1]
    return bool((und == 2).all())


def hausdorff(V0, F0, V1, F1, samples: int) -> float:
    """Two-sided sampled Hausdorff distance over the first mesh's bounding-box diagonal."""
    import numpy as np
    import trimesh

    lo = V0.min(0)
    d = float(np.linalg.norm(np.ptp(V0, 0))) / 1000.0
    a = trimesh.Trimesh((V0 - lo) / d, F0, process=False)
    b = trimesh.Trimesh((np.asarray(V1) - lo) / d, F1, process=False)
    pa = trimesh.sample.sample_surface(a, samples, seed=11)[0]
    pb = trimesh.sample.sample_surface(b, samples, seed=12)[0]
    return float(max(trimesh.proximity.closest_point(b, pa)[1].max(),
                     trimesh.proximity.closest_point(a, pb)[1].max())) / 1000.0


def target_for(faces: int, keep: float, fixed: int) -> int:
    """The target: ``fixed`` faces where given and below the mesh's count, else ``keep`` of them."""
    return fixed if 0 < fixed < faces else max(4, round(keep * faces))


def one(path: str, keep: float, repeat: int, samples: int, tools: list[str], fixed: int = 0,
        pymeshlab_python: str = "") -> dict:
    import numpy as np

    from robotkit.mesh.io import load_mesh

    mesh = load_mesh(path)
    V, F = np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64)
    target = target_for(len(F), keep, fixed)
    row = {"mesh": path, "faces": len(F), "target": target, "closed": is_closed(F), "tools": {}}
    if tools == ["pymeshlab"] and pymeshlab_python:
        got = pymeshlab_elsewhere(pymeshlab_python, V, F, target, repeat)
        if "error" in got:
            row["tools"]["pymeshlab"] = got
            return row
        f = np.asarray(got["F"], np.int64)
        row["tools"]["pymeshlab"] = {"faces": int(len(f)), "time": got["time"], "cpu": got["cpu"],
                                     "closed": is_closed(f),
                                     "hausdorff": hausdorff(V, F, np.asarray(got["V"], np.float64), f, samples)}
        return row
    for name in tools:  # warm-up: imports, first-call costs
        try:
            TOOLS[name](V, F, target)
        except Exception as exc:  # noqa: BLE001 - a tool's failure is a result
            row["tools"][name] = {"error": f"{type(exc).__name__}: {exc}"[:120]}
    times = {n: [] for n in tools if n not in row["tools"]}
    cpus = {n: [] for n in times}
    results = {}
    for _ in range(repeat):
        for name in times:
            t0, c0 = time.perf_counter(), time.process_time()
            results[name] = TOOLS[name](V, F, target)
            cpus[name].append(time.process_time() - c0)  # CPU of every thread of this process
            times[name].append(time.perf_counter() - t0)
    for name, (v, f) in results.items():
        f = np.asarray(f, np.int64)
        row["tools"][name] = {"faces": int(len(f)), "time": min(times[name]), "cpu": min(cpus[name]),
                              "closed": is_closed(f), "digest": result_digest(v, f),
                              "hausdorff": hausdorff(V, F, np.asarray(v, np.float64), f, samples)}
    if "robotkit-shortcuts" in results:  # whether the shortcuts' heuristic check sent it to MeshLib alone
        import trimesh

        from robotkit.mesh.decimate import decimate

        row["tools"]["robotkit-shortcuts"]["fallback"] = decimate(
            trimesh.Trimesh(V, F, process=False), target_faces=target, samples=0, shortcuts=True)[1]["fallback"]
    return row


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--keep", type=float, default=0.1, help="fraction of the faces to keep (default 0.1)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--samples", type=int, default=5000)
    ap.add_argument("--min-faces", type=int, default=1000, help="leave out meshes with fewer faces")
    ap.add_argument("--only", default="")
    ap.add_argument("--extra", default="", help="more folders of meshes, comma-separated (the unpacked "
                    "example-robot-data wheel's panda_description: the Panda's nine visual meshes)")
    ap.add_argument("--json")
    ap.add_argument("--one", help=argparse.SUPPRESS)
    ap.add_argument("--tools", default=",".join(TOOLS))
    ap.add_argument("--faces", type=int, default=0,
                    help="decimate to this many faces instead (meshes with more), as issue 33 did the Panda's")
    ap.add_argument("--pymeshlab-python", default="",
                    help="an interpreter with pymeshlab, where this one has none (a venv of its own)")
    args = ap.parse_args()
    tools = args.tools.split(",")
    if args.one:
        print(json.dumps(one(args.one, args.keep, args.repeat, args.samples, tools, args.faces,
                             args.pymeshlab_python)))
        return 0
    rows = []
    aim = f"to {args.faces} faces (meshes with more)" if args.faces > 0 else f"keep {args.keep} of the faces"
    print(f"{aim}; best of {args.repeat}; Hausdorff / diagonal from {args.samples} "
          f"samples each way; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"{'mesh':44} {'faces':>7} {'target':>6} C | " + " | ".join(f"{t[:10]:>27}" for t in tools))
    for path in visual_meshes([e for e in args.extra.split(",") if e]):
        if not any(part in path for part in args.only.split(",")):  # comma-separated substrings
            continue
        from robotkit.mesh.io import load_mesh

        try:
            n = len(load_mesh(path).faces)
        except Exception as exc:  # noqa: BLE001
            print(f"{os.path.relpath(path, REPO.parent)[-44:]:44} not loaded: {exc}"[:140])
            continue
        if n < args.min_faces:
            continue
        row = {"mesh": path, "faces": n, "target": target_for(n, args.keep, args.faces), "closed": None, "tools": {}}
        for name in tools:  # one process per tool: a crash (pymeshlab's) is that tool's result, and
            # no library's idle worker threads (MeshLib's TBB pool spins after its work) run on
            # into another tool's CPU time
            proc = subprocess.run([sys.executable, __file__, "--one", path, "--keep", str(args.keep),
                                   "--repeat", str(args.repeat), "--samples", str(args.samples),
                                   "--faces", str(args.faces), "--pymeshlab-python", args.pymeshlab_python,
                                   "--tools", name], capture_output=True, text=True, timeout=900)
            if proc.returncode == 0:
                got = json.loads(proc.stdout.strip().splitlines()[-1])
                row = {**got, "tools": {**row["tools"], **got["tools"]}}
            else:
                row["tools"][name] = {"error": f"crashed (exit {proc.returncode})"}
        row["tools"] = {t: row["tools"].get(t, {"error": "not run"}) for t in tools}
        rows.append(row)
        if args.json:  # after every mesh: a run cut short keeps what it measured
            Path(args.json).write_text(json.dumps(rows, indent=1))
        cells = []
        for t in tools:
            r = row["tools"][t]
            cells.append(f"{r['error'][:27]:>27}" if "error" in r else
                         f"{r['faces']:>6} {r['time'] * 1000:7.1f}ms {r['hausdorff']:.1e} {'C' if r['closed'] else 'o'}")
        print(f"{os.path.relpath(path, REPO.parent)[-44:]:44} {row['faces']:>7} {row['target']:>6} "
              f"{'C' if row['closed'] else 'o'} | " + " | ".join(cells), flush=True)
    print(f"load average at the end {os.getloadavg()[0]:.1f}")
    summary(rows, tools)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


def summary(rows, tools):
    import numpy as np

    print(f"\n{len(rows)} meshes")
    for t in tools:
        ok = [r for r in rows if "error" not in r["tools"][t]]
        within = sum(abs(r["tools"][t]["faces"] - r["target"]) <= 0.02 * r["target"] for r in ok)
        closed_in = [r for r in ok if r["closed"]]
        kept = sum(r["tools"][t]["closed"] for r in closed_in)
        print(f"  {t:20} ran {len(ok):3}; within 2 % of the target {within:3}; closed kept closed "
              f"{kept}/{len(closed_in)}")
    for mine in ("robotkit", "robotkit-shortcuts"):
        both = [r for r in rows if all("error" not in r["tools"].get(t, {"error": 1}) for t in (mine, "meshlib"))]
        if not both:
            continue
        h = np.array([r["tools"][mine]["hausdorff"] / max(r["tools"]["meshlib"]["hausdorff"], 1e-300)
                      for r in both])
        print(f"  Hausdorff {mine} / meshlib: median {np.median(h):.2f}, max {h.max():.2f}, "
              f"<= 1.0 on {int((h <= 1.0 + 1e-9).sum())}/{len(h)}, <= 1.05 on {int((h <= 1.05).sum())}/{len(h)}; "
              f"fell back to MeshLib alone on {sum(bool(r['tools'][mine].get('fallback')) for r in both)}/{len(both)}")
        same = sum(r["tools"][mine].get("digest") == r["tools"]["meshlib"].get("digest") for r in both)
        print(f"  {mine}: the same bytes as meshlib on {same}/{len(both)}")
    both = [r for r in rows if all("error" not in r["tools"].get(t, {"error": 1}) for t in ("robotkit", "pymeshlab"))]
    if both:
        h = np.array([r["tools"]["robotkit"]["hausdorff"] / max(r["tools"]["pymeshlab"]["hausdorff"], 1e-300)
                      for r in both])
        print(f"  Hausdorff robotkit / pymeshlab: median {np.median(h):.2f}, max {h.max():.2f}, "
              f"<= 1.05 on {int((h <= 1.05).sum())}/{len(h)}")
    for mine in ("meshlib", "meshlib-1thread"):  # the ceiling: MeshLib's own speed against pymeshlab's
        both = [r for r in rows if all("error" not in r["tools"].get(t, {"error": 1}) for t in (mine, "pymeshlab"))]
        for clock in ("time", "cpu") if both else ():
            ratio = np.array([r["tools"]["pymeshlab"][clock] / r["tools"][mine][clock] for r in both])
            print(f"  {'wall' if clock == 'time' else 'CPU '} pymeshlab / {mine}: median {np.median(ratio):.2f} "
                  f"({len(both)} meshes)")
    for other in ("pymeshlab", "meshlib", "meshlib-1thread", "robotkit-shortcuts", "meshoptimizer",
                  "fast-simplification"):
        both = [r for r in rows if "error" not in r["tools"].get("robotkit", {"error": 1})
                and "error" not in r["tools"].get(other, {"error": 1})]
        if not both or other not in tools:
            continue
        for clock in ("time", "cpu"):
            ratio = np.array([r["tools"][other][clock] / r["tools"]["robotkit"][clock] for r in both])
            total = sum(r["tools"][other][clock] for r in both) / sum(r["tools"]["robotkit"][clock] for r in both)
            print(f"  {'wall' if clock == 'time' else 'CPU '} {other} / robotkit: median {np.median(ratio):.2f}, "
                  f"over the sum {total:.2f}, min {ratio.min():.2f} ({len(both)} meshes)")


if __name__ == "__main__":
    sys.exit(main())
