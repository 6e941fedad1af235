"""Cost against size: whole builds against the number of links, mesh work against faces.

Links: the generated robots of ``bench_noop.py`` (arms of 10 links, boxes and one shared
STL) with N links, each built with ``robotkit build`` in a fresh process and a fresh cache:
a cold build, then a build after deleting the stamp (doit's own up-to-date check over the
whole task graph), then a no-op build (the stamp); without the picture report (``--no-report``: it renders
three pictures per joint, timed separately in docs/performance.md).  Faces: closed tori of F faces
(``trimesh.creation.torus``), the mesh functions a build runs on each mesh, in one process:
mass properties (``robotkit.mesh.inertia.mesh_mass_properties``), decimation to 10 %
(``robotkit.mesh.decimate.decimate``, no distance report), the exact surface distance
between the two (4,000 samples each way) and binary STL export.

For each size it prints the time and the time per link (or per 1,000 faces): linear cost
is a constant last column.  ``python benchmarks/bench_scaling.py [--links 10 100 1000]
[--faces 20000 200000 2000000] [--repeat 3]`` (best of ``--repeat`` for the mesh functions).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_noop  # noqa: E402


def timed(cmd, cwd, env) -> tuple[float, float]:
    """(wall, CPU) of one process and its workers (user + system, ``os.wait4``)."""
    with tempfile.TemporaryFile() as err:  # a file, not a pipe: a long stderr would block the build
        t0 = time.perf_counter()
        p = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(p.pid, 0)
        if status != 0:
            err.seek(0)
            raise SystemExit(f"{' '.join(map(str, cmd))} failed: {err.read().decode()}")
    return time.perf_counter() - t0, usage.ru_utime + usage.ru_stime


def links(sizes, tmp: Path):
    print(f"{'links':>6} {'cold build':>11} {'/link':>8} {'CPU':>7} {'marginal CPU/link':>18} {'doit check':>11} "
          f"{'/link':>8} {'no-op':>7} {'/link':>8}")
    previous = None
    for n in sizes:
        root = tmp / f"links{n}"
        root.mkdir()
        (root / "robot.yaml").write_text(bench_noop.recipe(n))
        (root / "slider.stl").write_bytes(bench_noop.MESH.read_bytes())
        env = {**os.environ, "ROBOTKIT_CACHE": str(root / "cache")}
        cmd = [str(bench_noop.BIN / "robotkit"), "build", "robot.yaml", "--out", "build", "--no-report"]
        cold, cpu = timed(cmd, root, env)
        for s in (root / "build" / ".robotkit").glob("stamp-*.json"):
            s.unlink()
        check = bench_noop.run(cmd, root, env)
        noop = bench_noop.run(cmd, root, env)
        marginal = "" if previous is None else f"{(cpu - previous[1]) / (n - previous[0]) * 1000:.2f}ms"
        previous = (n, cpu)
        print(f"{n:>6} {cold:>10.2f}s {cold / n * 1000:>6.1f}ms {cpu:>6.2f}s {marginal:>18} {check:>10.2f}s "
              f"{check / n * 1000:>6.2f}ms {noop:>6.3f}s {noop / n * 1000:>6.3f}ms", flush=True)


def faces(sizes, repeat: int):
    import numpy as np
    import trimesh

    from robotkit.mesh.decimate import decimate, surface_distance
    from robotkit.mesh.export import stl_bytes
    from robotkit.mesh.inertia import mesh_mass_properties

    cpu_times: dict[str, float] = {}

    def best(fn, name=""):
        out, t, c = None, [], []
        for _ in range(repeat):
            t0, c0 = time.perf_counter(), time.process_time()
            out = fn()
            t.append(time.perf_counter() - t0)
            c.append(time.process_time() - c0)
        cpu_times[name] = min(c)
        return out, min(t)

    small = trimesh.creation.icosphere(subdivisions=3)  # warm-up: imports and first-call costs
    mesh_mass_properties(small.vertices, small.faces), surface_distance(small, decimate(small, ratio=0.5)[0], 100)
    print(f"{'faces':>9} {'mass props':>11} {'/1k faces':>10} {'decimate':>9} {'/1k':>8} {'distance':>9} {'/1k':>8} "
          f"{'STL':>7} {'/1k':>8}")
    for f in sizes:
        minor = max(3, int(round((f / 2) ** 0.5 / 2)))
        major = max(3, int(round(f / 2 / minor)))
        mesh = trimesh.creation.torus(major_radius=0.2, minor_radius=0.05, major_sections=major, minor_sections=minor)
        n = len(mesh.faces)
        V, F = np.asarray(mesh.vertices), np.asarray(mesh.faces)
        _, tm = best(lambda: mesh_mass_properties(V, F), "mass")
        (dec, _), td = best(lambda: decimate(mesh, ratio=0.1, samples=0), "decimate")
        _, ts = best(lambda: surface_distance(mesh, dec, 4000), "distance")
        _, te = best(lambda: stl_bytes(mesh), "stl")
        k = n / 1000
        print(f"{n:>9} {tm:>10.3f}s {tm / k * 1000:>8.3f}ms {td:>8.2f}s {td / k * 1000:>6.2f}ms {ts:>8.2f}s "
              f"{ts / k * 1000:>6.2f}ms {te:>6.3f}s {te / k * 1000:>6.3f}ms   CPU (s): " +
              " ".join(f"{name} {v:.3f}" for name, v in cpu_times.items()), flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--links", type=int, nargs="*", default=[10, 100, 1000])
    ap.add_argument("--faces", type=int, nargs="*", default=[20000, 200000, 2000000])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start")
    if args.faces:
        faces(args.faces, args.repeat)
    if args.links:
        with tempfile.TemporaryDirectory(prefix="bench_scaling.") as tmp:
            links(args.links, Path(tmp))
    print(f"load average {os.getloadavg()[0]:.1f} at the end")
    return 0


if __name__ == "__main__":
    sys.exit(main())
