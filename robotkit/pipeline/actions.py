"""doit task actions: module-level functions with picklable arguments.

They run in worker processes under ``-j N`` (docs/libraries.md, section 6), so
every input arrives as plain data and every output is written atomically.
A user error becomes a failed task whose message is the problem lines; the
build turns those into exit status 2.
"""

from __future__ import annotations

import dataclasses
import filecmp
import functools
import hashlib
import json
import math
import os
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
from doit.exceptions import TaskFailed

from robotkit.emit.registry import FORMATS
from robotkit.emit.layout import robot_layout
from robotkit.errors import ConsumerError, Problem, RendererUnavailable, RobotkitError, display_path
from robotkit.ioutil import write_if_changed
from robotkit.mesh.cache import Cache, Files, canonical_json, code_digest, library_versions, plain
from robotkit.mesh.export import obj_bytes, stl_bytes
from robotkit.mesh.inertia import hull_points, mesh_mass_properties
from robotkit.mesh.io import load_mesh, read_vertices, remember_written_obj, volume_mesh
from robotkit.model.robot import Inertial
from robotkit.model.resolve import (compute_inertial, finalize, finalize_link_inertial, inertial_from_json,
                                    inertial_to_json)
from robotkit.pipeline.distributed import run as run_distributed  # on a Dask cluster when one is configured
from robotkit.pipeline.publish import publish, staged_files

RESULTS_VERSION = 1  # of the task results cached by content (cached_task)
RESULT_LIBRARIES = ("mujoco", "jinja2", "pillow", "numpy", "trimesh")  # beside the mesh cache's own
FACTS_VERSION = 4  # 3: sources relative to the recipe (no absolute or working-folder paths); 4: hull points
DRIVES_VERSION = 1
SELF_COLLISION_VERSION = 1


def _user_errors_fail(fn):
    @functools.wraps(fn)
    def run(*args, **kwargs):
        try:
            fn(*args, **kwargs)
        except RobotkitError as exc:
            failed = TaskFailed("\n".join(exc.lines()))
            failed.exit_status = exc.exit_status  # survives pickling to -j workers
            return failed
        return None

    return run


def dump_json(data) -> str:
    """``json.dumps(data, indent=1, sort_keys=True)`` and a newline.  A top-level list of rows
    of finite floats (a mesh's hull points) is written by one %-format, the same text: json's
    indented encoder is pure Python, and such a list is most of a mesh record."""
    rows = {k: v for k, v in data.items() if _float_rows(v)} if isinstance(data, dict) else {}
    if not rows:
        return json.dumps(data, indent=1, sort_keys=True) + "\n"
    marks = {k: f"\0dump_json {k}\0" for k in rows}
    text = json.dumps({k: marks.get(k, v) for k, v in data.items()}, indent=1, sort_keys=True)
    for k, v in rows.items():
        row = "  [\n" + ",\n".join(["   %r"] * len(v[0])) + "\n  ]"
        text = text.replace(json.dumps(marks[k]), "[\n" + ",\n".join([row] * len(v)) % tuple(
            x for r in v for x in r) + "\n ]", 1)
    return text + "\n"


def _float_rows(value) -> bool:
    """Whether ``value`` is a non-empty list of equally long, non-empty lists of finite floats."""
    return (isinstance(value, list) and len(value) > 0 and all(isinstance(r, list) for r in value)
            and len(value[0]) > 0 and all(len(r) == len(value[0]) for r in value)
            and all(type(x) is float and math.isfinite(x) for r in value for x in r))


@_user_errors_fail
def mesh_facts(source: str, scale, policy: str, where: dict, target: str):
    """Load a mesh, make it a closed volume, record its unit-density mass properties.

    What the mesh gives (:func:`measured_mesh`) is cached by content: the file's bytes, the
    scale, the open-mesh policy and the name its warnings give it, not the recipe file and
    line naming it (``where``), so that an import's verification and the later build of its
    recipe, or a second recipe naming the same file, measure it once.  ``where`` only shapes
    the record's ``source`` and the warnings' location."""
    name = display_path(source)
    params = {"scale": [float(v) for v in scale], "policy": policy, "name": name, "version": FACTS_VERSION,
              "code": code_digest()}
    try:
        content = Path(source).read_bytes()
    except OSError:  # load_mesh says why, at the recipe line naming it
        content = None
    if content is None:
        facts = measured_mesh(source, scale, policy, name, where)
    else:
        _, info = Cache().get_or_compute(
            "mesh-facts", params, [content],
            lambda: ([], {"facts": json.dumps(measured_mesh(source, scale, policy, name, where))}))
        facts = json.loads(info["facts"])  # as JSON text: the record's floats (-0.0 too) exactly as measured
    facts = {"version": FACTS_VERSION, "source": _label(source, where), "scale": list(scale), **facts,
             "warnings": [f"{_where_text(where)}{w}" for w in facts["warnings"]]}
    write_if_changed(target, dump_json(facts))


def measured_mesh(source: str, scale, policy: str, name: str, where: dict) -> dict:
    """The facts of one mesh file at one scale: size, extent, hull points, repairs, the volume's
    unit-density mass properties, and its warnings without their location.  A mesh robotkit
    cannot read, or that encloses no volume, is a RobotkitError at ``where``."""
    loc = Problem("", **where)
    mesh = load_mesh(source, scale, loc)
    faces_in = len(mesh.faces)
    bbox_min, bbox_max = mesh.bounds
    vol_mesh, repairs, used, warnings = volume_mesh(mesh, policy, name, loc)
    props = mesh_mass_properties(vol_mesh.vertices, vol_mesh.faces)
    if not props.volume > 0:
        raise RobotkitError(Problem(f"mesh '{name}' encloses no volume", **where))
    return {
        "faces": faces_in,
        "vertices": int(len(mesh.vertices)),
        "bbox_min": [float(v) for v in bbox_min],
        "bbox_max": [float(v) for v in bbox_max],
        "hull": np.asarray(hull_points(mesh.vertices), dtype=np.float64).tolist(),  # bounding primitives
        "volume": props.volume,
        "com": [float(v) for v in props.com],
        "inertia": [[float(v) for v in row] for row in np.asarray(props.inertia)],
        "used": used,
        "convex": bool(vol_mesh.is_convex),
        "repairs": repairs,
        "warnings": warnings,
    }


def _label(source: str, where: dict) -> str:
    """A mesh file as recorded in the build's JSON (and report.json): relative to the recipe
    file that names it, so records never depend on where the recipe sits or robotkit runs."""
    base = os.path.dirname(where["file"]) if where.get("file") else os.path.dirname(source)
    return Path(os.path.relpath(source, base)).as_posix()


def _where_text(where: dict) -> str:
    p = Problem("", **where)
    return str(p)


def read_facts(paths: dict[str, str]) -> dict:
    out = {}
    for key, path in paths.items():
        with open(path, encoding="utf-8") as f:
            out[key] = json.load(f)
    return out


@_user_errors_fail
def link_inertial(link, fact_paths: dict[str, str], target: str):
    """Compute one link's inertial from the mesh facts of its source geometry."""
    inertial = finalize_link_inertial(link, read_facts(fact_paths))
    write_if_changed(target, dump_json(inertial_to_json(inertial)))


def _finalized(robot, fact_paths: dict[str, str], inertial_paths: dict[str, str]):
    return finalize(robot, read_facts(fact_paths), _read_inertials(inertial_paths))


def _read_inertials(inertial_paths: dict[str, str]) -> dict:
    out = {}
    for link, path in inertial_paths.items():
        with open(path, encoding="utf-8") as f:
            out[link] = inertial_from_json(json.load(f))
    return out


@_user_errors_fail
def tune_drives(robot, inertial_paths: dict[str, str], target: str):
    """The actuators' gains and checks (robotkit.model.gains) from the links' inertials."""
    from robotkit.model import gains  # here and below: off the import of every task process

    inertials = _read_inertials(inertial_paths)
    links = tuple(replace(link, inertial=inertials[link.name] if link.name in inertials
                          else compute_inertial(link, {})) for link in robot.links)
    write_if_changed(target, dump_json(gains.tune(replace(robot, links=links))))


def with_drives(robot, path: str | None, matrix: str | None = None):
    """``robot`` with the tuner's gains of the record at ``path`` and the self-collision matrix of
    the record at ``matrix`` (None: as it is)."""
    from robotkit.model import gains, selfcollision

    if matrix:
        with open(matrix, encoding="utf-8") as f:
            record = json.load(f)
        if "unavailable" not in record:  # else MuJoCo could not load the robot: no matrix
            robot = selfcollision.apply(robot, selfcollision.Matrix.from_json(record))
    if not path:
        return robot
    with open(path, encoding="utf-8") as f:
        return gains.apply(robot, json.load(f))


@_user_errors_fail
def self_collision(robot, fact_paths: dict[str, str], meshes: str, target: str):
    """The self-collision matrix (robotkit.model.selfcollision) on the MJCF's collision geometry
    (the files below ``meshes``), cached by content: the MJCF without its inertials (geometry
    only: every link gets the same placeholder, so a density edit does not resample), the mesh
    files it reads, the settings."""
    from robotkit.emit.mjcf import collision_meshes, render_mjcf
    from robotkit.model import selfcollision

    placeholder = {link.name: Inertial(1.0, (0.0, 0.0, 0.0), (1e-3, 0.0, 0.0, 1e-3, 0.0, 1e-3)) for link in robot.links}
    full = replace(finalize(robot, read_facts(fact_paths), placeholder), self_collide=False, collision_matrix=None,
                   actuators=(), sensors=(), mjcf_extras=(), loops=())
    files = collision_meshes(full)
    xml = render_mjcf(full, points={rel: read_vertices(os.path.join(meshes, rel)) for rel in files})
    geometry = "\n".join(line for line in xml.splitlines() if "<inertial " not in line)
    settings = full.self_collision
    params = {"samples": settings.samples, "seed": settings.seed, "allow": [list(p) for p in settings.allow],
              "check": [list(p) for p in settings.check], "version": SELF_COLLISION_VERSION,
              "clearance": selfcollision.CLEARANCE}

    def compute():
        try:
            sampler = selfcollision.Sampler(xml, meshdir=meshes)
        except ValueError as exc:  # MuJoCo refuses the robot: the MJCF's task says why
            return [], {"unavailable": str(exc).strip().splitlines()[0]}
        return [], selfcollision.classify(sampler, settings).to_json()

    inputs = [geometry] + [Path(meshes, rel).read_bytes() for rel in files]
    # computed here, never on a cluster's workers: it reads the mesh files of this build
    _, info = Cache().get_or_compute("self-collision", params, inputs, compute)
    write_if_changed(target, dump_json(info))


@_user_errors_fail
def emit(name: str, robot, fact_paths: dict[str, str], inertial_paths: dict[str, str], target: str,
         how: dict, where: dict | None = None):
    """Render one output file through the registered format ``name`` (robotkit.emit.registry.FORMATS).

    ``how``: ``raw`` renders the resolved robot (else the robot finalized with the facts and
    inertials), ``facts`` gives the render the mesh facts, ``meshes`` is the folder of the mesh files
    whose vertices the format needs.  The robot descriptions (URDF, SDF, MJCF) are not written for a
    robot that their consumers would refuse (a moving link without mass...): ConsumerError, naming the
    link (``where``: link -> recipe location)."""
    fmt = FORMATS[name]
    full = with_drives(robot if how.get("raw") else _finalized(robot, fact_paths, inertial_paths), how.get("drives"),
                       how.get("matrix"))
    if fmt.consumed:
        problems = [Problem(msg, **(where or {}).get(link, {}))
                    for link, msg, formats in full.consumer_problems() if name in formats]
        if problems:
            raise ConsumerError(problems)
    options = dict(fmt.options)
    if how.get("facts"):
        options["facts"] = read_facts(fact_paths)
    if fmt.points is not None and how.get("meshes"):  # the vertices of the mesh files written beside it
        options["points"] = {rel: read_vertices(os.path.join(how["meshes"], rel)) for rel in fmt.points(full)}
    write_if_changed(target, fmt.render(full, **options))


@_user_errors_fail
def convert_mesh(source: str, target: str, scale=(1.0, 1.0, 1.0)):
    """A mesh in a format its consumers read (OBJ for collision, binary STL for MuJoCo's
    visuals), coordinates times ``scale``, byte-reproducible."""
    mesh = load_mesh(source, scale)
    obj = target.lower().endswith(".obj")
    write_if_changed(target, obj_bytes(mesh) if obj else stl_bytes(mesh))
    if obj:  # the MJCF's task reads its vertices back
        remember_written_obj(target, mesh.vertices, mesh.faces)


@_user_errors_fail
def copy_file(source: str, target: str):
    """Copy a file verbatim (visual meshes keep their format, colours and textures)."""
    if os.path.exists(target) and _same_file(source, target):
        return
    tmp = target + ".tmp"
    os.makedirs(os.path.dirname(target), exist_ok=True)
    shutil.copyfile(source, tmp)
    os.replace(tmp, target)


def _same_file(a: str, b: str) -> bool:
    return filecmp.cmp(a, b, shallow=False)


@_user_errors_fail
def world(map_yaml: str, out_dir: str, name: str, height: float, unknown_as_wall: bool, robot: dict | None = None):
    """One world from an occupancy map (robotkit.world), optionally with the robot placed in it."""
    from robotkit.world import build_world

    build_world(map_yaml, out_dir, name=name, height=height, unknown_as_wall=unknown_as_wall, robot=robot)


def _cache():
    return Cache(run=run_distributed)


@_user_errors_fail
def process_visual(source: str, scale, decimate, repair: bool, where: dict, target: str, report: str):
    """A processed visual mesh: repaired and decimated, written as a binary STL in metres."""
    # trimesh: loaded by these modules, only in the tasks that need it
    from robotkit.mesh.decimate import decimate as run_decimate, library
    from robotkit.mesh.repair import repair as run_repair

    loc = Problem("", **where)
    mesh = load_mesh(source, scale, loc)
    info: dict = {"source": _label(source, where)}
    if repair:
        mesh, info["repair"] = run_repair(mesh)
    kind, value = decimate
    if kind == "none":  # only mirrored (load_mesh flipped the faces of a mirroring scale)
        write_if_changed(target, stl_bytes(mesh))
        write_if_changed(report, dump_json(plain(info)))
        return
    faces = len(mesh.faces)
    target_faces = int(value) if kind == "faces" else max(4, int(round(faces * float(value))))
    if target_faces > faces:
        raise RobotkitError(Problem(f"decimation target {target_faces} faces is above the mesh's {faces} "
                                    f"faces ('{display_path(source)}')", **where))

    def compute():
        out, rep = run_decimate(mesh, target_faces=target_faces)
        return out, rep

    out, rep = _cache().get_or_compute("decimate/4", {"faces": target_faces, **library(), "samples": 4000,
                                                      "seed": 0, "report": True}, [mesh], compute)
    info["decimate"] = rep
    write_if_changed(target, stl_bytes(out))
    write_if_changed(report, dump_json(plain(info)))


@_user_errors_fail
def collision_proxy(source: str, scale, strategy: dict, stem: str, meshes_dir: str, where: dict, target: str):
    """Collision pieces for one mesh and strategy (cached), their files, and a fidelity report."""
    from robotkit.mesh.repair import repair as run_repair  # trimesh: only in the tasks that need it

    loc = Problem("", **where)
    mesh = load_mesh(source, scale, loc)
    info: dict = {"source": _label(source, where), "strategy": strategy}
    if strategy["repair"]:
        mesh, info["repair"] = run_repair(mesh)
    kind = strategy["kind"]
    params = {k: v for k, v in strategy.items() if k != "repair"}
    try:
        pieces, fid = _proxy_pieces(mesh, kind, strategy, params)
    except (ValueError, RuntimeError) as exc:
        raise RobotkitError(Problem(f"collision '{kind}' of '{display_path(source)}' failed: {exc}", **where)) from None
    out_pieces = []
    for i, piece in enumerate(pieces):
        if hasattr(piece, "vertices"):
            # OBJ: Drake takes convex collision meshes only as OBJ, VTK or glTF
            name = f"{stem}_{kind}_{i}.obj" if len(pieces) > 1 or kind != "mesh" else f"{stem}_mesh.obj"
            write_if_changed(os.path.join(meshes_dir, name), obj_bytes(piece))
            out_pieces.append({"kind": "mesh", "file": f"collision/{name}", "vertices": int(len(piece.vertices))})
        else:
            d = piece.to_dict()
            out_pieces.append({"kind": d["kind"], **d["params"], "xyz": list(d["xyz"]), "rpy": list(d["rpy"])})
    info["pieces"] = out_pieces
    info["fidelity"] = fid
    write_if_changed(target, dump_json(plain(info)))


def _proxy_pieces(mesh, kind: str, strategy: dict, params: dict):
    """(pieces, fidelity report).  Mesh results and their report come from the cache: the
    report's surface sampling costs as much as a hull.  (The mesh modules load trimesh: imported
    here, in the tasks that need them.)"""
    from robotkit.mesh.fidelity import fidelity

    cache = _cache()

    def with_report(make):
        def compute():
            pieces = make()
            return pieces, {"fidelity": fidelity(mesh, pieces)}
        return compute

    if kind == "primitive" or kind in ("box", "cylinder", "sphere", "capsule"):
        from robotkit.mesh.primitives import fit

        pieces = [fit(mesh, kind)]
        return pieces, fidelity(mesh, pieces)
    if kind == "mesh":
        if not strategy["decimate"]:
            return [mesh], fidelity(mesh, [mesh])
        how, value = strategy["decimate"]
        faces = int(value) if how == "faces" else max(4, int(round(len(mesh.faces) * float(value))))
        if faces > len(mesh.faces):
            raise ValueError(f"decimation target {faces} faces is above the mesh's {len(mesh.faces)} faces")
        from robotkit.mesh.decimate import decimate, library

        op, args, make = "collision-decimate/4", {"faces": faces, **library(), "seed": 0}, \
            (lambda: [decimate(mesh, target_faces=faces, samples=0)[0]])
    elif kind == "hull":
        from robotkit.mesh.hull import convex_hull

        op, args, make = "collision-hull/1", {"max_vertices": strategy["max_vertices"], "contain": False}, \
            (lambda: [convex_hull(mesh, strategy["max_vertices"])])
    else:
        from robotkit.mesh.decompose import INPUT_FACES, decompose

        c = strategy["coacd"]
        args = dict(threshold=c["threshold"], max_hulls=c["max_hulls"], resolution=c["resolution"],
                    preprocess=c["preprocess"], preprocess_resolution=c["preprocess_resolution"], seed=c["seed"],
                    max_hull_vertices=strategy["max_vertices"], mcts_iterations=c["mcts_iterations"],
                    input_faces=INPUT_FACES)  # in the cache key: the effective parameters
        op, make = "collision-coacd/5", (lambda: decompose(mesh, **args))  # /2: bodies joined (coacd_input)
        # /3: its large inputs decimated with the meshoptimizer first pass; /4: first pass with locks;
        # /5: large inputs decimated by MeshLib alone (decimate's default since issue 33)
    pieces, info = cache.get_or_compute(op, {**args, "fidelity_samples": 4000}, [mesh], with_report(make))
    return list(pieces) if isinstance(pieces, (list, tuple)) else [pieces], info["fidelity"]


def publish_outputs(out_dir: str, robot: str, tasks: list[dict]):
    """``<robot>:publish`` (dodo.py): the robot's staged folders, published (robotkit.pipeline.publish)."""
    publish(out_dir, robot, staged_files(tasks, out_dir))


@_user_errors_fail
def picture_report(robot_dir: str, out_dir: str, record: str):
    """report.html and its pictures (robotkit.picture imports MuJoCo in the task).  Where MuJoCo
    cannot draw, the page is written without pictures and ``record`` says why (the build warns)."""
    from robotkit.picture import report_build_dir

    shutil.rmtree(out_dir, ignore_errors=True)  # the staged report folder: no picture of an earlier build stays
    urdf = Path(os.path.relpath(robot_layout(robot_dir).urdf, out_dir)).as_posix()  # ../urdf/<robot>.urdf
    try:
        report_build_dir(Path(robot_dir), Path(out_dir), urdf)
        why = None
    except RendererUnavailable as exc:  # an optional stage: the descriptions stand without it
        why = exc.lines()[0]
        shutil.rmtree(out_dir, ignore_errors=True)
        report_build_dir(Path(robot_dir), Path(out_dir), urdf, no_pictures=why)
    write_if_changed(record, dump_json({"no_pictures": why}))


def pictures_drawn(record: str) -> bool:
    """doit's ``uptodate`` of the picture report: False when it was last written without pictures,
    so that it is drawn again once MuJoCo can draw (nothing else about the build changed)."""
    try:
        with open(record, encoding="utf-8") as f:
            return not json.load(f).get("no_pictures")
    except (OSError, ValueError, AttributeError):
        return True


# --- task results cached by content -----------------------------------------------------------

def _keyed(value, out: str):
    """``value`` as plain JSON for a cache key: paths below the output folder ``out`` relative to
    it (a fresh output folder hits), dataclasses as dicts, sets sorted."""
    if isinstance(value, os.PathLike):
        value = os.fspath(value)
    if isinstance(value, str):
        return "<out>" + value[len(out):] if value == out or value.startswith(out + os.sep) else value
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _keyed(getattr(value, f.name), out) for f in dataclasses.fields(value)}
    if isinstance(value, dict):
        return {str(k): _keyed(v, out) for k, v in value.items()}
    if isinstance(value, (set, frozenset)):
        return sorted((_keyed(v, out) for v in value), key=repr)
    if isinstance(value, (list, tuple)):
        return [_keyed(v, out) for v in value]
    return value


def gl_backend() -> str:
    """MuJoCo's GL backend (``$MUJOCO_GL``, robotkit's default osmesa) and whether its library
    loads here: a report drawn with pictures is not reused where none could be drawn."""
    import ctypes
    import ctypes.util

    backend = os.environ.get("MUJOCO_GL") or "osmesa"
    library = {"osmesa": ("OSMesa", "8"), "egl": ("EGL", "1")}.get(backend)
    if library is None:
        return backend
    name, version = library
    for find in (lambda: f"lib{name}.so.{version}", lambda: ctypes.util.find_library(name) or f"lib{name}.so"):
        try:  # the usual name, else a search
            ctypes.CDLL(find())
            return backend
        except OSError:
            continue
    return f"{backend} without lib{name}"


_DIGESTS: dict = {}  # (id, out) -> (object, digest): a robot shared by many tasks is hashed once per process


def _arg_key(value, out: str):
    """One action argument for a cache key: a dataclass (a robot, a link) by the digest of its
    plain JSON, computed once per object and process; anything else as :func:`_keyed`."""
    if not dataclasses.is_dataclass(value) or isinstance(value, type):
        return _keyed(value, out)
    hit = _DIGESTS.get((id(value), out))
    if hit is None or hit[0] is not value:
        digest = hashlib.sha256(canonical_json(_keyed(value, out)).encode()).hexdigest()
        hit = _DIGESTS[(id(value), out)] = (value, digest)
    return {type(value).__name__: hit[1]}


def cached_task(op: str, out: str, deps: list[str], outputs: dict, action: str, args: list):
    """Run the action ``action`` (a name in this module) on ``args`` unless its output files are
    in the cache (robotkit.mesh.cache.Cache, kind Files): the key is ``op``, robotkit's code
    (so the versions in the tasks' ``config_changed`` too), the libraries' versions, $MUJOCO_GL,
    ``args`` (paths below ``out`` relative to it) and the content of every file in ``deps``.
    ``outputs``: ``files`` (written by the action), ``tree`` (a folder written whole),
    ``pieces`` ((record, meshes folder): the collision pieces the record lists), ``unless`` (a
    picture record: a report drawn without pictures is not stored), ``gl`` (the key holds
    :func:`gl_backend`).  A failed action stores
    nothing.  Hits and misses write the same bytes: a rebuild from the cache is byte-identical."""
    out = os.path.abspath(out)
    run = globals()[action]
    try:
        cache, key = _task_key(op, out, deps, outputs, args)
    except (OSError, TypeError, ValueError):  # a dependency missing, or args that are no key: just run it
        return run(*args)
    files = cache.get(key)
    if isinstance(files, Files) and _restore(files, out, outputs):
        return None
    failed = run(*args)
    if failed is not None:
        return failed
    files = _collect(out, outputs, Files)
    if files is not None:
        cache.put(key, files, op=f"task/{op}", params={"op": op})
    return None


_KEYS: dict = {}  # (op, out, id(args), its files' stats) -> (args, key): warm() asked, cached_task runs


def _task_key(op: str, out: str, deps: list[str], outputs: dict, args: list) -> tuple[Cache, str]:
    """The cache and the key of :func:`cached_task`'s result (OSError: a dependency is missing;
    TypeError, ValueError: ``args`` are no key).  Computed once per task and process while its
    files keep their size and time (:func:`in_cache`, then the task in the same process)."""
    deps = sorted(set(deps))  # file_dep built from a set comes in any order
    stats = tuple((d, s.st_size, s.st_mtime_ns) for d in deps for s in (os.stat(d),))
    memo = (op, out, id(args), stats, bool(outputs.get("gl")))
    hit = _KEYS.get(memo)
    if hit is not None and hit[0] is args:
        return Cache(versions={}), hit[1]
    cache, key = _compute_key(op, out, deps, outputs, args)
    _KEYS[memo] = (args, key)
    return cache, key


def _compute_key(op: str, out: str, deps: list[str], outputs: dict, args: list) -> tuple[Cache, str]:
    params = {"op": op, "version": RESULTS_VERSION, "code": code_digest(),
              "libraries": library_versions(RESULT_LIBRARIES), "gl": gl_backend() if outputs.get("gl") else None,
              "args": [_arg_key(a, out) for a in args], "deps": [_keyed(d, out) for d in deps]}
    inputs = [Path(d).read_bytes() for d in deps]
    cache = Cache(versions={})
    return cache, cache.key(f"task/{op}", params, inputs)


def in_cache(op: str, out: str, deps: list[str], outputs: dict, action: str, args: list) -> bool:
    """Whether :func:`cached_task` on these arguments would find its result in this machine's
    cache (an entry of a shared cache not copied here yet counts as absent).  Only asks: the
    entry is not read."""
    try:
        cache, key = _task_key(op, os.path.abspath(out), deps, outputs, args)
    except (OSError, TypeError, ValueError):
        return False
    return cache.manifest_path(key).exists()


def _output_paths(outputs: dict) -> list[str] | None:
    """Every file an action wrote (absolute), or None when its result is not to be cached."""
    paths = list(outputs.get("files", []))
    unless = outputs.get("unless")  # a record whose "no_pictures" says the result is provisional
    if unless and not pictures_drawn(unless):
        return None
    tree = outputs.get("tree")
    if tree:
        for root, _dirs, names in os.walk(tree):
            paths += [os.path.join(root, n) for n in names]
    if outputs.get("pieces"):
        record, meshes = outputs["pieces"]
        try:
            with open(record, encoding="utf-8") as f:
                pieces = json.load(f).get("pieces", [])
        except (OSError, ValueError, AttributeError):
            return None
        paths += [os.path.join(meshes, p["file"]) for p in pieces if isinstance(p, dict) and p.get("file")]
    return paths


def _collect(out: str, outputs: dict, files_type):
    """The files an action wrote, relative to ``out`` (None: nothing to store)."""
    paths = _output_paths(outputs)
    if paths is None:
        return None
    files = files_type()
    for path in paths:
        rel = os.path.relpath(path, out)
        if rel.startswith(".."):
            return None
        try:
            files[Path(rel).as_posix()] = Path(path).read_bytes()
        except OSError:
            return None
    return files


def _restore(files: dict, out: str, outputs: dict) -> bool:
    """Write a cached result's files below ``out``; False (nothing written) when it lacks one
    the task promises."""
    rel = {Path(os.path.relpath(p, out)).as_posix() for p in outputs.get("files", [])}
    if not rel <= set(files):
        return False
    if outputs.get("tree"):
        shutil.rmtree(outputs["tree"], ignore_errors=True)  # no file of an earlier result stays
    for name, data in sorted(files.items()):
        write_if_changed(os.path.join(out, *name.split("/")), data)
    return True
