"""Beyond one machine: a warm shared cache against a cold build, and catalogue throughput.

1. **UR5, cold against warm-remote.**  An S3-compatible server (moto's, on loopback) holds
   the team's cache.  ``cold``: ``robotkit build recipes/ur5.yaml`` with an empty shared
   cache and an empty local copy (computes everything and publishes it).  ``warm remote``:
   another machine's view, a fresh output folder and an empty local copy, the shared cache
   warm.  Whole processes, default -j.
2. **Catalogue throughput** (objects per minute) of ``robotkit catalogue`` on generated
   meshes (L-brackets and tori, CoACD decomposition), each configuration on an empty cache:
   plain ``-j 1`` and ``-j N`` (doit worker processes), and a Dask cluster of 1..N
   single-threaded workers (``--scheduler``), the scheduler and workers separate processes.

``python benchmarks/bench_distributed.py [--objects 12] [--skip-ur5]``; prints a Markdown
table and the load average before and after (the figures are wall clock: note the load).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def timed(cmd: list[str], env: dict) -> float:
    t = time.perf_counter()
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if r.returncode not in (0, 1):
        sys.exit(f"{' '.join(cmd)} failed:\n{r.stderr}")
    return time.perf_counter() - t


def ur5(root: Path) -> list[tuple[str, float]]:
    port = free_port()
    moto = subprocess.Popen([str(BIN / "moto_server"), "-H", "127.0.0.1", "-p", str(port)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        url = f"http://127.0.0.1:{port}"
        for _ in range(200):
            try:
                urllib.request.urlopen(url + "/", timeout=1)
                break
            except OSError:
                time.sleep(0.1)
        env = {**os.environ, "AWS_ACCESS_KEY_ID": "k", "AWS_SECRET_ACCESS_KEY": "s",
               "AWS_DEFAULT_REGION": "us-east-1", "AWS_ENDPOINT_URL": url,
               "ROBOTKIT_CACHE": "s3://bench/team"}
        import s3fs

        os.environ.update({k: env[k] for k in ("AWS_ACCESS_KEY_ID", "AWS_SECRET_ACCESS_KEY", "AWS_DEFAULT_REGION",
                                                "AWS_ENDPOINT_URL")})
        s3fs.S3FileSystem(skip_instance_cache=True).mkdir("bench")
        cmd = [str(BIN / "robotkit"), "build", str(REPO / "recipes" / "ur5.yaml"), "--no-report"]
        cold = timed(cmd + ["--out", str(root / "a")], {**env, "ROBOTKIT_CACHE_LOCAL": str(root / "local_a")})
        warm = timed(cmd + ["--out", str(root / "b")], {**env, "ROBOTKIT_CACHE_LOCAL": str(root / "local_b")})
        return [("UR5 cold (empty shared and local cache)", cold),
                ("UR5 warm remote (fresh machine: empty local copy, warm shared cache)", warm)]
    finally:
        moto.terminate()
        moto.wait()


def make_objects(folder: Path, n: int) -> None:
    import trimesh

    folder.mkdir(parents=True)
    for i in range(n):
        if i % 2:
            m = trimesh.creation.torus(0.05 + 0.005 * i, 0.015, major_sections=20, minor_sections=10)
        else:
            s = 0.1 + 0.01 * i
            a = trimesh.creation.box((s, s / 4, s / 4))
            b = trimesh.creation.box((s / 4, s, s / 4))
            b.apply_translation((s * 3 / 8, s * 3 / 8, 0))
            m = trimesh.boolean.union([a, b]).subdivide()
        m.export(folder / f"object_{i:03d}.stl")


def catalogue(root: Path, n: int, cores: int) -> list[tuple[str, float]]:
    objs = root / "objects"
    make_objects(objs, n)
    rows = []
    cmd = [str(BIN / "robotkit"), "catalogue", str(objs)]
    for j in sorted({1, cores}):
        env = {**os.environ, "ROBOTKIT_CACHE": str(root / f"cache_j{j}")}
        t = timed(cmd + ["--out", str(root / f"out_j{j}"), "-j", str(j)], env)
        rows.append((f"catalogue of {n}, -j {j} (no Dask)", t))
    for w in sorted({1, cores}):
        env = {**os.environ, "ROBOTKIT_CACHE": str(root / f"cache_w{w}")}
        sched_file = root / f"sched_{w}.json"
        procs = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                                   "--port", "0", "--no-dashboard", "--scheduler-file", str(sched_file)],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
        try:
            while not sched_file.exists():
                time.sleep(0.1)
            time.sleep(0.2)
            address = json.loads(sched_file.read_text())["address"]
            procs.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address,
                                           "--nworkers", str(w), "--nthreads", "1", "--no-dashboard"],
                                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
            t = timed(cmd + ["--out", str(root / f"out_w{w}"), "--scheduler", address], env)
            rows.append((f"catalogue of {n}, Dask cluster of {w} worker(s)", t))
        finally:
            for p in procs:
                p.terminate()
            for p in procs:
                p.wait()
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", type=int, default=12)
    ap.add_argument("--skip-ur5", action="store_true")
    opts = ap.parse_args()
    cores = len(os.sched_getaffinity(0))
    print(f"load before: {os.getloadavg()[0]:.2f} (cores: {cores})")
    root = Path(tempfile.mkdtemp(prefix="robotkit-bench-dist-"))
    try:
        rows = [] if opts.skip_ur5 else ur5(root)
        rows += catalogue(root, opts.objects, cores)
    finally:
        shutil.rmtree(root, ignore_errors=True)
    print("| run | wall s | objects / min |")
    print("|---|---|---|")
    for name, t in rows:
        rate = f"{opts.objects / t * 60:.1f}" if name.startswith("catalogue") else ""
        print(f"| {name} | {t:.1f} | {rate} |")
    if not opts.skip_ur5:
        print(f"warm remote / cold: {rows[1][1] / rows[0][1]:.3f}")
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
