"""Beyond one machine: a shared mesh cache on a real S3-compatible server (moto's server,
a separate process speaking S3 over HTTP), mesh work on a real Dask scheduler and workers
(separate processes), and ``robotkit catalogue``."""

from __future__ import annotations

import hashlib
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest
import trimesh

from conftest import tree_bytes, write_recipe

RECIPE = """
robot: cached_bot
links:
  base:
    visual: {mesh: torus.stl}
    collision: {strategy: decompose, coacd: {threshold: 0.2, max_hulls: 4}}
  arm:
    visual: {mesh: capsule.stl}
    collision: {strategy: hull, max_vertices: 32}
joints:
  swing:
    type: revolute
    parent: base
    child: arm
    origin: {xyz: [0, 0, 0.1]}
    axis: [0, 0, 1]
    limit: {lower: -1, upper: 1, effort: 1, velocity: 1}
"""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _meshes():
    return {"torus.stl": trimesh.creation.torus(0.08, 0.025, major_sections=24, minor_sections=12),
            "capsule.stl": trimesh.creation.capsule(0.1, 0.03)}


@pytest.fixture(scope="module")
def s3(tmp_path_factory):
    """A real S3-compatible server (``moto_server``) on loopback, and the environment that
    points boto/s3fs at it (the usual AWS variables: credentials never come from recipes)."""
    pytest.importorskip("s3fs") if os.environ.get("CI") != "true" else __import__("s3fs")
    port = _free_port()
    log = tmp_path_factory.mktemp("moto") / "moto.log"
    exe = Path(sys.executable).with_name("moto_server")
    proc = subprocess.Popen([str(exe), "-H", "127.0.0.1", "-p", str(port)], stdout=log.open("wb"),
                            stderr=subprocess.STDOUT)
    url = f"http://127.0.0.1:{port}"
    for _ in range(200):
        try:
            urllib.request.urlopen(url + "/", timeout=1)
            break
        except OSError:
            if proc.poll() is not None:
                pytest.fail(f"moto_server did not start: {log.read_text()}")
            time.sleep(0.1)
    env = {"AWS_ACCESS_KEY_ID": "robotkit", "AWS_SECRET_ACCESS_KEY": "robotkit", "AWS_DEFAULT_REGION": "us-east-1",
           "AWS_ENDPOINT_URL": url}
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    import s3fs

    fs = s3fs.S3FileSystem(skip_instance_cache=True)
    fs.mkdir("robotkit-cache")
    yield fs, env
    for k, v in old.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v
    proc.terminate()
    proc.wait(timeout=20)


def _build(recipe: Path, out: Path, env: dict, *extra: str, forbid_compute: bool = False,
           tally: Path | None = None):
    """``robotkit build`` in its own process; with ``forbid_compute`` the hull and CoACD
    functions raise, so the build can only succeed from the cache; with ``tally`` every cache
    lookup appends its statistics (hits, misses = computations, ...) to that file, a JSON line each."""
    code = ["import sys"]
    if forbid_compute:
        code += ["import robotkit.mesh.hull as h, robotkit.mesh.decompose as d",
                 "def boom(*a, **k): raise AssertionError('computed instead of read from the cache')",
                 "h.convex_hull = boom; d.decompose = boom"]
    if tally is not None:
        code += ["import json, robotkit.mesh.cache as c",
                 "lookup = c.Cache.get_or_compute",
                 "def counted(self, *a, **k):",
                 "    try: return lookup(self, *a, **k)",
                 f"    finally: open({str(tally)!r}, 'a').write(json.dumps(self.stats) + '\\n')",
                 "c.Cache.get_or_compute = counted"]
    code += ["from robotkit.cli import main", "sys.exit(main(sys.argv[1:]))"]
    return subprocess.run([sys.executable, "-c", "\n".join(code), "build", str(recipe), "--out", str(out),
                           "--no-report", "-j", "1", *extra], capture_output=True, text=True,
                          env={**os.environ, **env})


def _objects(fs, prefix: str) -> dict[str, bytes]:
    return {p: fs.cat_file(p) for p in sorted(fs.find(f"robotkit-cache/{prefix}"))}


def _assert_entries_whole(objects: dict[str, bytes]):
    manifests = {p: json.loads(b) for p, b in objects.items() if p.endswith(".json")}
    assert manifests
    for path, m in manifests.items():
        payload = objects[path.rsplit("/", 1)[0] + "/" + m["payload"]["file"]]
        assert len(payload) == m["payload"]["size"]
        assert hashlib.sha256(payload).hexdigest() == m["payload"]["sha256"]


@pytest.mark.slow
def test_shared_cache_on_s3(s3, tmp_path):
    """One machine computes and publishes; another with an empty local cache rebuilds the
    same bytes from the shared copy without computing anything."""
    fs, env = s3
    recipe = write_recipe(tmp_path / "src", RECIPE, meshes=_meshes())
    shared = {"ROBOTKIT_CACHE": "s3://robotkit-cache/team"}
    first = _build(recipe, tmp_path / "a", {**shared, "ROBOTKIT_CACHE_LOCAL": str(tmp_path / "local_a")})
    assert first.returncode == 0, first.stderr
    assert "shared cache" not in first.stderr
    objects = _objects(fs, "team")
    _assert_entries_whole(objects)
    manifests = [json.loads(b) for p, b in objects.items() if p.endswith(".json")]
    kinds = [m["kind"] for m in manifests]
    # the hull, the decomposition, the self-collision matrix, each mesh's facts (keyed by content); the
    # rest are the pure tasks' output files
    ops = [m["op"] for m in manifests if m["kind"] != "files"]
    assert len(ops) == 5 and ops.count("mesh-facts") == 2 and kinds.count("files") > 0

    second = _build(recipe, tmp_path / "b", {**shared, "ROBOTKIT_CACHE_LOCAL": str(tmp_path / "local_b")},
                    forbid_compute=True)
    assert second.returncode == 0, second.stderr
    assert tree_bytes(tmp_path / "a" / "cached_bot") == tree_bytes(tmp_path / "b" / "cached_bot")
    # the read-through copy now holds the entries it read (the tasks' results; the mesh results
    # behind them were not needed): a third build needs no server at all
    local_b = sorted(p.name for p in (tmp_path / "local_b").rglob("*") if p.suffix in (".json", ".bin"))
    assert local_b and set(local_b) <= {p.rsplit("/", 1)[1] for p in objects}
    third = _build(recipe, tmp_path / "c", {"ROBOTKIT_CACHE": str(tmp_path / "local_b")}, forbid_compute=True)
    assert third.returncode == 0, third.stderr
    # a warm local copy publishes its entries into a new, empty shared cache (one HEAD per key)
    later = _build(recipe, tmp_path / "d", {"ROBOTKIT_CACHE": "s3://robotkit-cache/later",
                                            "ROBOTKIT_CACHE_LOCAL": str(tmp_path / "local_b")}, forbid_compute=True)
    assert later.returncode == 0, later.stderr
    later_objects = {p.split("/", 2)[2]: b for p, b in _objects(fs, "later").items()}
    assert sorted(p.rsplit("/", 1)[1] for p in later_objects) == local_b
    assert later_objects == {k: b for k, b in ((p.split("/", 2)[2], b) for p, b in objects.items())
                             if k in later_objects}


@pytest.mark.slow
def test_corrupt_shared_entry_is_detected_and_rebuilt(s3, tmp_path):
    fs, env = s3
    recipe = write_recipe(tmp_path / "src", RECIPE, meshes=_meshes())
    shared = {"ROBOTKIT_CACHE": "s3://robotkit-cache/corrupt"}
    assert _build(recipe, tmp_path / "a", {**shared, "ROBOTKIT_CACHE_LOCAL": str(tmp_path / "l1")}).returncode == 0
    before = _objects(fs, "corrupt")
    payloads = [p for p in before if p.endswith(".bin")]
    for p in payloads:  # flip bytes in the middle of every payload: same size, wrong checksum
        data = bytearray(before[p])
        if not data:  # the self-collision matrix: no mesh, its record is in the (verified) manifest
            continue
        data[len(data) // 2] ^= 0xFF
        fs.pipe_file(p, bytes(data))
    # a reader with an empty local copy must not use them: it computes again ...
    bad = _build(recipe, tmp_path / "b", {**shared, "ROBOTKIT_CACHE_LOCAL": str(tmp_path / "l2")},
                 forbid_compute=True)
    assert bad.returncode != 0 and "computed instead of read from the cache" in bad.stdout + bad.stderr
    good = _build(recipe, tmp_path / "c", {**shared, "ROBOTKIT_CACHE_LOCAL": str(tmp_path / "l3")})
    assert good.returncode == 0, good.stderr
    assert tree_bytes(tmp_path / "a" / "cached_bot") == tree_bytes(tmp_path / "c" / "cached_bot")
    # ... and republishes whole entries
    after = _objects(fs, "corrupt")
    _assert_entries_whole(after)
    assert after == before


@pytest.mark.slow
def test_read_only_shared_cache_is_never_written(s3, tmp_path):
    fs, env = s3
    recipe = write_recipe(tmp_path / "src", RECIPE, meshes=_meshes())
    run = _build(recipe, tmp_path / "a", {"ROBOTKIT_CACHE": "s3://robotkit-cache/readonly",
                                          "ROBOTKIT_CACHE_LOCAL": str(tmp_path / "l"),
                                          "ROBOTKIT_CACHE_READONLY": "1"})
    assert run.returncode == 0, run.stderr
    assert _objects(fs, "readonly") == {}
    assert list((tmp_path / "l").rglob("*.json"))  # the local copy still works


@pytest.mark.slow
def test_unreachable_shared_cache_costs_time_not_the_build(tmp_path):
    recipe = write_recipe(tmp_path / "src", RECIPE, meshes=_meshes())
    port = _free_port()  # nothing listens there
    env = {"ROBOTKIT_CACHE": "s3://robotkit-cache/x", "ROBOTKIT_CACHE_LOCAL": str(tmp_path / "l"),
           "AWS_ENDPOINT_URL": f"http://127.0.0.1:{port}", "AWS_ACCESS_KEY_ID": "a", "AWS_SECRET_ACCESS_KEY": "b",
           "AWS_DEFAULT_REGION": "us-east-1", "AWS_MAX_ATTEMPTS": "1", "AWS_RETRY_MODE": "standard"}
    run = _build(recipe, tmp_path / "a", env)
    assert run.returncode == 0, run.stderr
    warnings = [line for line in run.stderr.splitlines() if "shared cache" in line]
    assert len(warnings) == 1
    assert warnings[0].startswith("robotkit: warning: shared cache: cannot read v1/")
    assert warnings[0].endswith("(building without it)")


def _tally(path: Path) -> dict:
    """The statistics of every cache lookup of a build, summed."""
    total: dict = {}
    for line in (path.read_text().splitlines() if path.exists() else []):
        for k, v in json.loads(line).items():
            total[k] = total.get(k, 0) + v
    return total


def _entries(root: Path) -> dict[str, bytes]:
    """The entries' files below a cache folder (no locks), by name relative to it."""
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.suffix in (".json", ".bin")}


def test_local_entries_are_published_to_a_new_shared_cache(tmp_path, monkeypatch):
    """Entries made before the team shared its cache are published on their first use, by one
    existence check per key and process; a read-only shared cache is never written."""
    from robotkit.mesh.cache import Cache

    meshes = [trimesh.creation.icosphere(2), trimesh.creation.box((0.1, 0.2, 0.3))]
    alone = Cache(tmp_path / "local", versions={"v": "1"})
    keys = [alone.key("op", {}, m) for m in meshes]
    for key, m in zip(keys, meshes):
        alone.put(key, [m], op="op")
    assert alone.stats["published"] == 0

    monkeypatch.setenv("ROBOTKIT_CACHE_READONLY", "1")
    readonly = Cache(f"file://{tmp_path}/ro", local=tmp_path / "local", versions={"v": "1"})
    monkeypatch.delenv("ROBOTKIT_CACHE_READONLY")
    assert readonly.get(keys[0]) is not None and not (tmp_path / "ro").exists()

    team = Cache(f"file://{tmp_path}/shared", local=tmp_path / "local", versions={"v": "1"})
    checks = []
    exists = team.remote.exists
    team.remote.exists = lambda name: checks.append(name) or exists(name)
    for key, m in zip(keys, meshes):
        got = team.get_or_compute("op", {}, m, lambda: pytest.fail("computed a local entry"))
        assert got is not None
        assert team.get(key) is not None  # again: known published, not checked again
    assert team.stats["published"] == 2 and team.stats["misses"] == 0
    assert checks == [Cache.entry_name(k, f"{k}.json") for k in keys]
    assert _entries(tmp_path / "shared") == _entries(tmp_path / "local")

    fresh = Cache(f"file://{tmp_path}/shared", local=tmp_path / "fresh", versions={"v": "1"})
    for m in meshes:
        fresh.get_or_compute("op", {}, m, lambda: pytest.fail("computed an entry of the shared cache"))
    assert fresh.stats["remote_hits"] == 2 and fresh.stats["misses"] == 0


@pytest.mark.slow
def test_build_publishes_a_warm_local_cache(tmp_path):
    """A build with a warm local copy into a new, empty shared cache (file://) leaves every
    entry it used there; a fresh machine then rebuilds the same bytes computing nothing."""
    recipe = write_recipe(tmp_path / "src", RECIPE, meshes=_meshes())
    local = tmp_path / "local"
    cold = _build(recipe, tmp_path / "a", {"ROBOTKIT_CACHE": str(local)}, tally=tmp_path / "cold.log")
    assert cold.returncode == 0, cold.stderr
    used = _entries(local)
    kinds = {n: json.loads(b)["kind"] for n, b in used.items() if n.endswith(".json")}
    # the hull, the decomposition, the matrix, each mesh's facts (keyed by content)
    meshes = [n for n, k in kinds.items() if k != "files"]
    assert len(meshes) == 5 == _tally(tmp_path / "cold.log")["misses"]

    shared = {"ROBOTKIT_CACHE": f"file://{tmp_path}/shared"}
    warm = _build(recipe, tmp_path / "b", {**shared, "ROBOTKIT_CACHE_LOCAL": str(local)}, tally=tmp_path / "warm.log")
    assert warm.returncode == 0, warm.stderr
    assert "shared cache" not in warm.stderr
    # every task's result came from the local copy (no mesh result was even asked for) and is published
    assert _tally(tmp_path / "warm.log").get("misses", 0) == 0
    published = _entries(tmp_path / "shared")
    assert published == {n: b for n, b in used.items() if n.split(".")[0] in
                         {m.split(".")[0] for m, k in kinds.items() if k == "files"}}

    fresh = _build(recipe, tmp_path / "c", {**shared, "ROBOTKIT_CACHE_LOCAL": str(tmp_path / "fresh")},
                   forbid_compute=True, tally=tmp_path / "fresh.log")
    assert fresh.returncode == 0, fresh.stderr
    assert _tally(tmp_path / "fresh.log").get("misses", 0) == 0
    assert tree_bytes(tmp_path / "a" / "cached_bot") == tree_bytes(tmp_path / "c" / "cached_bot")


def test_two_writers_of_one_entry(tmp_path):
    """Concurrent publication of the same entry to a shared folder (file:// URL) leaves one
    whole entry; no reader sees a partial one."""
    from robotkit.mesh.cache import Cache

    mesh = trimesh.creation.icosphere(3)
    errors = []

    def writer(i):
        try:
            for _ in range(5):
                c = Cache(f"file://{tmp_path}/shared", local=tmp_path / f"local{i}")
                c.put(c.key("op", {}, mesh), [mesh], op="op")
                reader = Cache(f"file://{tmp_path}/shared", local=tmp_path / f"r{i}")
                got = reader.get(reader.key("op", {}, mesh))
                assert got is None or np.array_equal(got[0].vertices, mesh.vertices)
                assert reader.stats["remote_corrupt"] == 0
        except Exception as exc:  # pragma: no cover - reported below
            errors.append(exc)

    threads = [threading.Thread(target=writer, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    files = sorted(p.name for p in (tmp_path / "shared").rglob("*") if p.is_file())
    assert len(files) == 2 and not any(f.endswith(".tmp") for f in files)


# --- Dask ------------------------------------------------------------------------------------

class Cluster:
    """A Dask scheduler and ``n`` workers without nannies, each its own process, so that
    killing one is a real loss the scheduler has to recover from."""

    def __init__(self, folder: Path, n: int = 2):
        self.folder, self.n = folder, n
        self.workers: list[subprocess.Popen] = []

    def __enter__(self):
        pytest.importorskip("distributed") if os.environ.get("CI") != "true" else __import__("distributed")
        sched_file = self.folder / "scheduler.json"
        quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
        self.scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host",
                                           "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file",
                                           str(sched_file)], **quiet)
        for _ in range(600):
            if sched_file.exists():
                try:
                    self.address = json.loads(sched_file.read_text())["address"]
                    break
                except (ValueError, KeyError):
                    pass
            time.sleep(0.1)
        else:
            pytest.fail("the Dask scheduler did not start")
        for i in range(self.n):
            self.workers.append(subprocess.Popen(
                [sys.executable, "-m", "distributed.cli.dask_worker", self.address, "--no-nanny", "--nthreads", "1",
                 "--no-dashboard", "--local-directory", str(self.folder / f"w{i}")], **quiet))
        from distributed import Client

        self.client = Client(self.address, timeout="60s")
        self.client.wait_for_workers(self.n, timeout=120)
        return self

    def tasks_done(self) -> int:
        """How many robotkit computations the scheduler has seen finish."""
        def count(dask_scheduler):
            return sum(tp.state_counts["memory"] for name, tp in dask_scheduler.task_prefixes.items()
                       if name.startswith("compute"))
        return self.client.run_on_scheduler(count)

    def __exit__(self, *exc):
        self.client.close()
        for p in [*self.workers, self.scheduler]:
            if p.poll() is None:
                p.terminate()
        for p in [*self.workers, self.scheduler]:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()


@pytest.mark.slow
def test_build_sends_mesh_work_to_the_cluster(tmp_path):
    recipe = write_recipe(tmp_path / "src", RECIPE, meshes=_meshes())
    local = _build(recipe, tmp_path / "here", {"ROBOTKIT_CACHE": str(tmp_path / "c1")})
    assert local.returncode == 0, local.stderr
    with Cluster(tmp_path, 2) as cluster:
        run = _build(recipe, tmp_path / "there", {"ROBOTKIT_CACHE": str(tmp_path / "c2")}, "--scheduler",
                     cluster.address)
        assert run.returncode == 0, run.stderr
        assert cluster.tasks_done() == 2  # the hull and the decomposition ran on the workers
    # two caches, each build sampling the self-collision matrix itself: the same bytes (no time recorded)
    assert tree_bytes(tmp_path / "here" / "cached_bot") == tree_bytes(tmp_path / "there" / "cached_bot")


def _l_shape(size: float) -> trimesh.Trimesh:
    a = trimesh.creation.box((size, size / 4, size / 4))
    b = trimesh.creation.box((size / 4, size, size / 4))
    b.apply_translation((size * 3 / 8, size * 3 / 8, 0))
    return trimesh.boolean.union([a, b]).subdivide()


@pytest.mark.slow
def test_catalogue_on_a_cluster_survives_a_killed_worker(tmp_path):
    """A catalogue with broken meshes among good ones, on two workers, one of which is killed
    while it works: every good object is made once, every broken one is reported, and the
    masses equal trimesh's own computation of the meshes at the catalogue's density."""
    objs = tmp_path / "objects"
    (objs / "kitchen").mkdir(parents=True)
    good = {
        "kitchen/l_bracket.stl": (_l_shape(0.2), 1.0),
        "kitchen/ring.stl": (trimesh.creation.torus(0.06, 0.02, major_sections=20, minor_sections=10), 1.0),
        "part_mm.stl": (_l_shape(120.0), 0.001),  # millimetres, to be guessed
        "beam.obj": (_l_shape(0.5), 1.0),
        "knot.stl": (trimesh.creation.torus(0.09, 0.015, major_sections=18, minor_sections=8), 1.0),
    }
    for rel, (mesh, _) in good.items():
        mesh.export(objs / rel)
    (objs / "broken.stl").write_bytes(b"solid broken\nfacet normal 0 0 1\n")
    (objs / "kitchen" / "empty.obj").write_bytes(b"")
    out = tmp_path / "out"
    env = {**os.environ, "ROBOTKIT_CACHE": str(tmp_path / "cache")}
    with Cluster(tmp_path, 2) as cluster:
        proc = subprocess.Popen([sys.executable, "-m", "robotkit", "catalogue", str(objs), "--out", str(out),
                                 "--density", "800", "--scheduler", cluster.address], env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        pids = dict(cluster.client.run(os.getpid))
        killed = None
        deadline = time.monotonic() + 300
        while killed is None and time.monotonic() < deadline and proc.poll() is None:
            busy = [w for w, keys in cluster.client.processing().items() if keys]
            if busy:
                time.sleep(0.3)  # let it get into the work
                killed = pids[busy[0]]
                os.kill(killed, signal.SIGKILL)
            time.sleep(0.05)
        stdout, stderr = proc.communicate(timeout=600)
        assert killed is not None, "no worker was ever busy"
    assert proc.returncode == 1, stderr  # two broken meshes
    assert "5 objects made, 2 failed" in stdout
    problems = [line for line in stderr.splitlines() if not line.startswith("catalogue [")]  # progress lines
    assert problems == ["broken.stl: mesh file 'broken.stl' holds no triangles",
                        "kitchen/empty.obj: mesh file 'empty.obj' holds no triangles"]
    index = json.loads((out / "catalogue.json").read_text())
    names = [o["name"] for o in index["objects"]]
    assert len(names) == len(set(names)) == 7
    by_source = {o["source"]: o for o in index["objects"]}
    for rel, (mesh, scale) in good.items():
        o = by_source[rel]
        assert o["status"] == "ok", o
        assert o["units"] == ("mm" if scale == 0.001 else "m") and o["units_from"] == "guessed"
        m = trimesh.load(objs / rel, force="mesh")  # the file as written (STL holds float32)
        m.apply_scale(scale)
        m.density = 800.0
        assert o["mass"] == pytest.approx(m.mass, rel=1e-9)
        assert np.allclose(o["com"], m.center_mass, atol=1e-9)  # the mesh's own origin is the link frame
        assert o["collision_pieces"] >= 1
        for fmt in ("urdf", "sdf", "mjcf"):
            assert (out / o[fmt]).is_file()
    # a rerun does only what is missing: nothing, then one deleted object
    again = subprocess.run([sys.executable, "-m", "robotkit", "catalogue", str(objs), "--out", str(out),
                            "--density", "800", "-j", "1"], env=env, capture_output=True, text=True)
    assert "; 0 tasks run," in again.stdout, again.stdout
    (out / by_source["knot.stl"]["urdf"]).unlink()  # a deleted output comes back from the stage
    third = subprocess.run([sys.executable, "-m", "robotkit", "catalogue", str(objs), "--out", str(out),
                            "--density", "800", "-j", "1"], env=env, capture_output=True, text=True)
    assert "; 0 tasks run," in third.stdout and (out / by_source["knot.stl"]["urdf"]).is_file()
    assert json.loads((out / "catalogue.json").read_text()) == index
    # a changed mesh: that object is built again, the others are not
    trimesh.creation.torus(0.1, 0.02, major_sections=18, minor_sections=8).export(objs / "knot.stl")
    fourth = subprocess.run([sys.executable, "-m", "robotkit", "catalogue", str(objs), "--out", str(out),
                             "--density", "800", "-j", "1"], env=env, capture_output=True, text=True)
    assert "; 0 tasks run," not in fourth.stdout, fourth.stdout
    after = {o["source"]: o for o in json.loads((out / "catalogue.json").read_text())["objects"]}
    assert after["knot.stl"]["mass"] != by_source["knot.stl"]["mass"]
    assert {k: v for k, v in after.items() if k != "knot.stl"} == {k: v for k, v in by_source.items()
                                                                    if k != "knot.stl"}


@pytest.mark.slow
def test_catalogue_bad_input(tmp_path):
    from conftest import run_cli

    (tmp_path / "objs").mkdir()
    trimesh.creation.box().export(tmp_path / "objs" / "a.stl")
    (tmp_path / "masses.csv").write_text("name,mass\na,-1\nzzz,2\n")
    r = run_cli("catalogue", tmp_path / "objs", "--out", tmp_path / "out", "--masses", tmp_path / "masses.csv")
    assert r.returncode == 2
    assert r.stderr.splitlines() == [f"{tmp_path / 'masses.csv'}:2: mass: mass must be a number > 0 (got '-1')"]
    r = run_cli("catalogue", tmp_path / "nothing", "--out", tmp_path / "out")
    assert r.returncode == 2 and r.stderr.splitlines() == [f"{tmp_path / 'nothing'}: no such folder or list file"]
    assert not (tmp_path / "out").exists()
