"""doit task dictionaries for a resolved robot: one task per unit of work.

- ``<robot>:mesh:<key>``: load one mesh (file, scale, open-mesh policy), repair,
  record its unit-density mass properties as JSON (state folder);
- ``<robot>:collision:<key>``: the collision pieces of one proxy (hull, CoACD, primitives);
- ``<robot>:visual:<file>``, ``<robot>:copy:<file>``, ``<robot>:convert:<file>``: the mesh files
  below ``meshes/`` (processed, copied with their textures, converted for a format);
- ``<robot>:inertial:<link>``: one link's inertial from its mesh facts;
- ``<robot>:<format>``: one output file per registered format (:data:`robotkit.emit.registry.FORMATS`);
- ``<robot>:report-html``, ``world:<world>``, ``<robot>:world:<world>``: the picture report, the worlds.

Every task names its inputs (``file_dep``), outputs (``targets``) and the
recipe values that matter (``config_changed``), so doit reruns exactly what
an edit affects.  The same task list serves ``robotkit build`` and ``doit``
(dodo.py).  Every path comes from :mod:`robotkit.emit.layout`.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import NamedTuple

import yaml
from doit.tools import config_changed

from robotkit.emit import layout
from robotkit.emit.registry import FORMATS
from robotkit.emit.env import template_dirs
from robotkit.emit.formats import Format, Outputs, outputs_of
from robotkit.emit.meshfiles import conversions
from robotkit.emit.ros import has_moveit
from robotkit.geometry import rpy_quat
from robotkit.mesh.io import companions
from robotkit.model.load import load_robots, mesh_locations
from robotkit.model.robot import Robot
from robotkit.paths import file_stem, inside, out_join, recipe_policy
from robotkit.pipeline import actions
from robotkit.pipeline.publish import STATE, stage_dir  # STATE: below the output folder, doit's database and JSON
from robotkit.recipe.yamlsafe import MAX_YAML_BYTES, yaml_limits


@dataclass(frozen=True)
class Place:
    """Where one robot's tasks write: its staged folder (``root``, published by
    :mod:`robotkit.pipeline.publish`) and its records (``state``); ``where`` maps a mesh key, and
    ``link:<name>``, to the recipe location naming it (for messages)."""

    robot: Robot
    root: Path
    state: Path
    where: dict
    with_matrix: bool = True  # False: no self-collision matrix (a verification's build, which reads none)

    @classmethod
    def of(cls, robot: Robot, out_dir: str | os.PathLike, where: dict | None = None,
           with_matrix: bool = True) -> "Place":
        out_dir = Path(out_dir).absolute()
        return cls(robot, out_join(stage_dir(out_dir), robot.name, key="robot"), out_dir / STATE / robot.name,
                   where or {}, with_matrix)

    @property
    def out_dir(self) -> Path:
        """The output folder (``state`` is ``OUT/.robotkit/<robot>``)."""
        return self.state.parent.parent

    def record(self, kind: str, key: str) -> str:
        return str(self.state / layout.RECORDS[kind].format(key=key))

    def out(self, template: str | dict) -> str:
        """A file of the robot's folder (a template of robotkit.emit.layout)."""
        return str(self.root / layout.output_path(template, self.robot.name, self.robot.ros))

    def mesh(self, rel: str, folder: str = layout.MESHES) -> str:
        """A mesh file ``rel`` below ``folder`` of the robot's folder."""
        return str(self.root / folder / rel)

    @property
    def facts(self) -> dict[str, str]:
        """Mesh key -> its mesh facts."""
        return {key: self.record("mesh", key) for key in self.robot.meshes()}

    @property
    def proxies(self) -> dict[str, str]:
        """Proxy key -> the record of its collision pieces."""
        return {key: self.record("collision", key) for key in self.robot.proxies()}

    @property
    def drives(self) -> str | None:
        """The tuner's record (gains, checks) of a robot with actuators."""
        return self.record("drives", "") if self.robot.actuators else None

    @property
    def matrix(self) -> str | None:
        """The self-collision matrix's record, for a robot with two links with collision geometry
        (None in a build without the matrix: outputs render as for a robot without one)."""
        solid = [link for link in self.robot.links if link.collisions_for("mjcf")]
        return self.record("self-collision", "") if len(solid) >= 2 and self.with_matrix else None

    @property
    def inertials(self) -> dict[str, str]:
        """Link -> its inertial, for the links whose inertial a task computes."""
        return {link.name: self.record("inertial", file_stem(link.name)) for link in self.robot.links
                if link.inertial_spec.mode in ("density", "mass", "estimate")}


def cached(task: dict, place: Place, outputs: dict | None = None) -> dict:
    """``task`` with its action run through :func:`robotkit.pipeline.actions.cached_task`: its
    output files come from the cache when its inputs (the action's arguments, robotkit's code,
    the content of its ``file_dep``: what its ``config_changed`` values derive from) were built
    before, in any output folder.  ``outputs``: what the action writes (default: its targets)."""
    (fn, args), = task["actions"]
    task["actions"] = [(actions.cached_task, [task["name"].split(":", 1)[1].split(":")[0], str(place.out_dir),
                                              list(task["file_dep"]), outputs or {"files": list(task["targets"])},
                                              fn.__name__, list(args)])]
    return task


def robot_tasks(robot: Robot, out_dir: str | os.PathLike, where: dict | None = None,
                report: bool = False, outputs: Outputs | None = None, matrix: bool = True) -> list[dict]:
    """The task dicts that build ``robot`` into ``out_dir/<robot>/``.

    ``where`` maps a mesh key, and ``link:<name>``, to the recipe location naming it (for messages);
    ``report`` adds the picture report (``report/report.html``, drawn from the MJCF: not without it);
    ``outputs``: the formats written (default: :func:`robotkit.emit.formats.outputs_of` the robot);
    ``matrix``: False leaves out the self-collision matrix (:meth:`Place.matrix`).
    """
    outputs = outputs or outputs_of(robot, FORMATS)
    place = Place.of(robot, out_dir, where, matrix)
    meshes = mesh_tasks(place)
    # collision pieces before the other mesh work: CoACD is the longest, and doit -j N hands
    # out tasks in list order, so the slow ones start first and the quick ones fill in around them
    collisions = collision_tasks(place)
    files = visual_tasks(place) + copy_tasks(place) + convert_tasks(place)  # the mesh files below meshes/
    textures = texture_tasks(place)
    written = output_tasks(place, [t["targets"][0] for t in files], outputs)
    tasks = meshes + collisions + files + textures + inertial_tasks(place) + drive_tasks(place)
    tasks += self_collision_tasks(place, [t["targets"][0] for t in files]) + written
    if report and "mjcf" in outputs:
        tasks.append(report_task(place, collisions + files + textures, meshes))
    return tasks + world_tasks(robot, out_dir)


def mesh_tasks(place: Place) -> list[dict]:
    """``<robot>:mesh:<key>``: a mesh's facts (mass properties, extent, repairs, warnings)."""
    robot, tasks = place.robot, []
    for key, mesh in robot.meshes().items():
        target = place.record("mesh", key)
        tasks.append(cached({
            "name": f"{robot.name}:mesh:{key}",
            "doc": f"mass properties of {os.path.basename(mesh.source)}",
            "actions": [(actions.mesh_facts, [mesh.source, list(mesh.scale), mesh.open_mesh,
                                              place.where.get(key, {}), target])],
            "file_dep": [mesh.source],
            "targets": [target],
            "uptodate": [config_changed({"scale": list(mesh.scale), "policy": mesh.open_mesh,
                                         "version": actions.FACTS_VERSION})],
            "clean": True,
        }, place))
    return tasks


def collision_tasks(place: Place) -> list[dict]:
    """``<robot>:collision:<key>``: one proxy's collision pieces, below ``meshes/collision/``."""
    robot, facts, tasks = place.robot, place.facts, []
    for key, shape in robot.proxies().items():
        m = shape.mesh
        target = place.record("collision", key)
        stem = os.path.splitext(m.file_name)[0]
        tasks.append(cached({
            "name": f"{robot.name}:collision:{key[len('proxy-'):]}",
            "doc": f"{shape.strategy.kind} collision of {os.path.basename(m.source)}",
            "actions": [(actions.collision_proxy, [m.source, list(m.scale), shape.strategy.params(), stem,
                                                   place.out(layout.COLLISION_MESHES), place.where.get(m.key, {}),
                                                   target])],
            "file_dep": [m.source, facts[m.key]],
            "targets": [target],
            "uptodate": [config_changed({"scale": list(m.scale), "strategy": shape.strategy.params(),
                                         "version": actions.FACTS_VERSION})],
            "clean": True,
        }, place, {"files": [target], "pieces": (target, place.out(layout.MESHES))}))
    return tasks


def shown_meshes(robot: Robot) -> set[str]:
    """The keys of the meshes some geometry draws or collides with (not only a proxy's source)."""
    return {g.shape.mesh.key for link in robot.links for g in robot.all_geoms(link) if g.shape.kind == "mesh"}


def visual_tasks(place: Place) -> list[dict]:
    """``<robot>:visual:<file>``: a processed (decimated, repaired, mirrored) visual mesh."""
    robot, facts, shown = place.robot, place.facts, shown_meshes(place.robot)
    processed: dict[str, object] = {}
    for key, mesh in robot.meshes().items():
        if key in shown and mesh.processed:
            processed.setdefault(mesh.path, mesh)
    tasks = []
    for rel, mesh in sorted(processed.items()):
        target = place.mesh(rel)
        visual_report = place.record("visual", mesh.key)
        tasks.append(cached({
            "name": f"{robot.name}:visual:{mesh.file_name}",
            "doc": f"processed visual mesh {mesh.file_name}",
            "actions": [(actions.process_visual, [mesh.source, list(mesh.scale), list(mesh.decimate), mesh.repair,
                                                  place.where.get(mesh.key, {}), target, visual_report])],
            "file_dep": [mesh.source, facts[mesh.key]],
            "targets": [target, visual_report],
            "uptodate": [config_changed({"scale": list(mesh.scale), "decimate": list(mesh.decimate),
                                         "repair": mesh.repair, "version": actions.FACTS_VERSION})],
            "clean": True,
        }, place))
    return tasks


def copied_meshes(place: Place) -> dict[str, tuple[str, list[str]]]:
    """The visual mesh files copied verbatim: file name -> (source, the facts of its mesh tasks)."""
    robot, facts, shown = place.robot, place.facts, shown_meshes(place.robot)
    copies: dict[str, tuple[str, list[str]]] = {}
    for key, mesh in robot.meshes().items():
        if key in shown and not mesh.processed:
            copies.setdefault(mesh.file_name, (mesh.source, []))[1].append(facts[key])
    return copies


def copy_tasks(place: Place) -> list[dict]:
    """``<robot>:copy:<file>``: a visual mesh file copied verbatim into ``meshes/visual/``."""
    tasks = []
    for file_name, (source, checked) in sorted(copied_meshes(place).items()):
        target = place.mesh(file_name, layout.VISUAL_MESHES)
        tasks.append({
            "name": f"{place.robot.name}:copy:{file_name}",
            "doc": f"visual mesh {file_name}",
            "actions": [(actions.copy_file, [source, target])],
            # after its mesh tasks: a file that cannot be used is never copied
            "file_dep": [source, *checked],
            "targets": [target],
            "clean": True,
        })
    return tasks


def texture_tasks(place: Place) -> list[dict]:
    """``<robot>:copy:<file>``: the textures and material files the copied meshes reference."""
    extras: dict[str, str] = {}
    for _, (source, _) in sorted(copied_meshes(place).items()):
        allowed = _reads_allowed(place, source)
        for rel in companions(source):
            path = os.path.join(os.path.dirname(source), rel)
            if allowed(path):
                extras.setdefault(rel, path)
    tasks, own = [], {os.path.normpath(place.mesh(name, layout.VISUAL_MESHES)) for name in copied_meshes(place)}
    for rel, source in sorted(extras.items()):
        target = os.path.normpath(place.mesh(rel, layout.VISUAL_MESHES))
        if not _texture_fits(place, target) or target in own:
            continue
        tasks.append({
            "name": f"{place.robot.name}:copy:{rel}",
            "doc": f"texture or material file {rel}",
            "actions": [(actions.copy_file, [source, target])],
            "file_dep": [source],
            "targets": [target],
            "clean": True,
        })
    return tasks


def _reads_allowed(place: Place, source: str):
    """Which of a mesh's companion files the build may read: the read rules of the recipe naming
    the mesh (robotkit.paths); without a recipe (tasks made in code), only files below the
    mesh's own folder."""
    meshes = place.robot.meshes()
    recipes = sorted(place.where[key]["file"] for key, mesh in meshes.items()
                     if mesh.source == source and place.where.get(key, {}).get("file"))
    if recipes:
        return recipe_policy(recipes[0]).allows
    return lambda path: inside(path, os.path.dirname(source))


def _texture_fits(place: Place, target: str) -> bool:
    """Whether a companion file's place in the package is free for it: below ``meshes/`` (a
    Gazebo model's ``../materials/textures/`` lands in ``meshes/materials/textures/``), outside
    the folder of processed meshes that robotkit writes itself."""
    meshes = os.path.normpath(place.mesh("", layout.MESHES))
    inside = os.path.commonpath([meshes, target]) == meshes and target != meshes
    processed = os.path.normpath(place.mesh("", layout.COLLISION_MESHES))
    return inside and os.path.commonpath([processed, target]) != processed


def convert_tasks(place: Place) -> list[dict]:
    """``<robot>:convert:<file>``: a mesh in the format an output needs (robotkit.emit.meshfiles)."""
    robot, facts, tasks = place.robot, place.facts, []
    for rel, (source, scale) in conversions(robot).items():
        target = place.mesh(rel)
        checked = [facts[k] for k, m in robot.meshes().items() if m.source == source]
        tasks.append(cached({
            "name": f"{robot.name}:convert:{rel}",
            "actions": [(actions.convert_mesh, [source, target, list(scale)])],
            "file_dep": [source, *checked],
            "targets": [target],
            "uptodate": [config_changed({"version": actions.FACTS_VERSION, "scale": list(scale)})],
            "clean": True,
            "doc": f"{layout.MESHES}/{rel}",
        }, place))
    return tasks


def inertial_tasks(place: Place) -> list[dict]:
    """``<robot>:inertial:<link>``: one link's inertial from the facts of its source geometry."""
    robot, facts, tasks = place.robot, place.facts, []
    for link in robot.links:
        if link.name not in place.inertials:
            continue
        keys = sorted({g.shape.mesh.key for g in link.source_geoms() if g.shape.mesh is not None})
        deps = {k: facts[k] for k in keys}
        target = place.inertials[link.name]
        tasks.append(cached({
            "name": f"{robot.name}:inertial:{link.name}",
            "doc": f"inertial of link {link.name}",
            "actions": [(actions.link_inertial, [link, deps, target])],
            "file_dep": list(deps.values()),
            "targets": [target],
            "uptodate": [config_changed({"link": asdict(link), "version": actions.FACTS_VERSION})],
            "clean": True,
        }, place))
    return tasks


def drive_tasks(place: Place) -> list[dict]:
    """``<robot>:drives``: the actuators' gains from the robot's inertia and their checks
    (:mod:`robotkit.model.gains`), for the outputs that write gains."""
    robot = place.robot
    if place.drives is None:
        return []
    structure = {k: v for k, v in robot.to_dict().items() if k not in ("worlds", "sensors", "metadata")}
    return [cached({
        "name": f"{robot.name}:drives",
        "doc": "actuator gains and checks",
        "actions": [(actions.tune_drives, [robot, place.inertials, place.drives])],
        "file_dep": list(place.inertials.values()),
        "targets": [place.drives],
        "uptodate": [config_changed({"robot": structure, "version": actions.DRIVES_VERSION})],
        "clean": True,
    }, place)]


def self_collision_tasks(place: Place, written: list[str]) -> list[dict]:
    """``<robot>:self-collision``: the self-collision matrix (:mod:`robotkit.model.selfcollision`)
    on the MJCF's collision geometry (the collision pieces' records and the mesh files written)."""
    robot, target = place.robot, place.matrix
    if target is None:
        return []
    facts = {**place.facts, **place.proxies}
    plain = robot.to_dict()
    geometry = {k: v for k, v in plain.items() if k in ("name", "joints", "base", "poses", "self_collision")}
    geometry["links"] = [{k: v for k, v in link.items() if k not in ("inertial_spec", "inertial")}
                         for link in plain["links"]]
    return [cached({
        "name": f"{robot.name}:self-collision",
        "doc": "self-collision matrix",
        "actions": [(actions.self_collision, [robot, facts, place.out(layout.MESHES), target])],
        "file_dep": list(facts.values()) + written
        + template_files(("mjcf/robot.xml.j2",)),
        "targets": [target],
        "uptodate": [config_changed({"robot": geometry, "version": actions.SELF_COLLISION_VERSION})],
        "task_dep": [f"{robot.name}:mesh:{k}" for k in place.facts],
        "clean": True,
    }, place)]


class Reading(NamedTuple):
    """What an output's task gives its action and hashes, for one kind of ``reads``
    (:data:`robotkit.emit.formats.READS`)."""

    robot: Robot  # the robot its action renders (finalized there unless ``raw``)
    config: dict  # the robot's values the output depends on (config_changed)
    facts: dict[str, str]  # the mesh and collision records it reads
    inertials: dict[str, str]  # the inertials it reads
    raw: bool = False  # rendered from the resolved robot, not the finalized one
    with_facts: bool = False  # the render gets the mesh facts (keyword facts)
    drives: str | None = None  # the tuner's record: gains applied before rendering
    matrix: str | None = None  # the self-collision matrix's record: applied before rendering


def readings(place: Place) -> dict[str, Reading]:
    """Every kind of ``reads``, for this robot."""
    robot, facts, proxies, inertials = place.robot, place.facts, place.proxies, place.inertials
    structure = {k: v for k, v in robot.to_dict().items() if k != "worlds"}
    # the finalized robot needs the facts of recentered meshes (their offsets) and every inertial
    recentered = sorted({g.shape.mesh.key for link in robot.links for g in robot.all_geoms(link)
                         if g.shape.mesh is not None and g.recenter != "none"})
    package = {k: structure.get(k) for k in ("name", "metadata", "ros", "gazebo", "sensors", "actuators", "poses")}
    package.update(moveit=has_moveit(robot), worlds=[(w.name, w.spawn and asdict(w.spawn)) for w in robot.worlds], meshes=bool(robot.meshes()))
    no_inertials = {**structure, "links": [{k: v for k, v in link.items() if k not in ("inertial_spec", "inertial")}
                                           for link in structure["links"]]}
    drives, matrix = place.drives, place.matrix
    return {
        "robot": Reading(robot, structure, {**{k: facts[k] for k in recentered}, **proxies}, inertials,
                         drives=drives, matrix=matrix),
        "summary": Reading(robot, structure, {**facts, **proxies}, inertials, with_facts=True, drives=drives,
                           matrix=matrix),
        # the visual geometry's extent, the sensors' topics: no inertial
        "rviz": Reading(robot, no_inertials, {k: facts[k] for k in shown_meshes(robot) if k in facts}, {},
                        raw=True, with_facts=True),
        "ros-package": Reading(robot, package, {}, {}, raw=True),
        "structure": Reading(robot, {"name": robot.name, "ros": robot.ros, "gazebo": robot.gazebo,
                                     "actuators": [asdict(a) for a in robot.actuators],
                                     "poses": [asdict(p) for p in robot.poses]}, {}, {}, raw=True,
                             drives=drives if any(a.auto for a in robot.actuators) else None),
        "groups": Reading(robot, {"name": robot.name, "base": robot.base, "poses": [asdict(p) for p in robot.poses],
                                  "joints": [asdict(j) for j in robot.joints],
                                  "links": [link.name for link in robot.links]}, {}, {}, raw=True, matrix=matrix),
        "metadata": Reading(replace(robot, links=(), joints=(), materials=()),
                            {"name": robot.name, "metadata": asdict(robot.metadata)}, {}, {}),
    }


def output_tasks(place: Place, written: list[str], outputs: Outputs | None = None) -> list[dict]:
    """``<robot>:<format>``: one output file per registered format the robot wants (of ``outputs``);
    ``written``: the mesh files below ``meshes/`` (a format that measures them waits for them)."""
    reads = readings(place)
    outputs = outputs or outputs_of(place.robot, FORMATS)
    return [output_task(place, FORMATS[name], reads[FORMATS[name].reads], written) for name in outputs.written]


def output_task(place: Place, fmt: Format, reading: Reading, written: list[str]) -> dict:
    robot = place.robot
    target = place.out(fmt.path)
    how = {"raw": reading.raw, "facts": reading.with_facts, "drives": reading.drives, "matrix": reading.matrix,
           "meshes": place.out(layout.MESHES) if fmt.points is not None else None}
    options = {**fmt.options, **{k: True for k, v in how.items() if v}}  # hashed with the robot's values
    return cached({
        "name": f"{robot.name}:{fmt.name}",
        "doc": layout.output_path(fmt.path, robot.name, robot.ros),
        "actions": [(actions.emit, [fmt.name, reading.robot, reading.facts, reading.inertials, target, how,
                                    {k[5:]: v for k, v in place.where.items() if k.startswith("link:")}])],
        "file_dep": list(reading.facts.values()) + list(reading.inertials.values()) + template_files(fmt.templates)
        + (written if fmt.points is not None else []) + [r for r in (reading.drives, reading.matrix) if r],
        "targets": [target],
        "uptodate": [config_changed({"robot": reading.config, "options": options})],
        # no output is written while any mesh of the robot fails, nor while a file it names is not
        "task_dep": [f"{robot.name}:mesh:{k}" for k in place.facts]
        + [f"{robot.name}:{n}" for n in fmt.needs if FORMATS[n].wanted(robot)],
        "clean": True,
    }, place)


def template_files(names) -> list[str]:
    """The files of the templates ``names``, each where the template search path finds it first."""
    out = []
    for name in names:
        for d in template_dirs():
            p = Path(d) / name
            if p.is_file():
                out.append(str(p))
                break
    return out


def report_task(place: Place, drawn: list[dict], meshes: list[dict]) -> dict:
    """``<robot>:report-html``: report.html and its pictures, from the written URDF, MJCF,
    report.json and every mesh file MuJoCo reads (the targets of ``drawn``: the meshes the MJCF
    draws and the collision pieces' records), after the ``meshes`` tasks (rendering imports stay
    in the action)."""
    from robotkit.picture import VERSION as PICTURE_VERSION  # the check package: only with the report
    from robotkit.picture.page import TEMPLATE as PICTURE_TEMPLATE

    built, record = layout.RobotLayout(place.root), place.record("pictures", "")
    inputs = [str(built.urdf), str(built.mjcf), str(built.report_json)]
    inputs += [target for t in drawn for target in t["targets"]]
    return cached({
        "name": f"{place.robot.name}:report-html",
        "doc": layout.REPORT_HTML,
        "actions": [(actions.picture_report, [str(place.root), str(built.pictures), record])],
        "file_dep": inputs + template_files([PICTURE_TEMPLATE]),
        "targets": [str(built.report_html), record],
        "uptodate": [config_changed({"version": PICTURE_VERSION}), (actions.pictures_drawn, [record])],
        "task_dep": [t["name"] for t in meshes],
        "clean": True,
    }, place, {"files": [record], "tree": str(built.pictures), "unless": record, "gl": True})


def world_tasks(robot: Robot, out_dir: str | os.PathLike) -> list[dict]:
    """Two tasks per world of the recipe: OUT/<world>/ with its five files (the robot placed at
    its spawn pose), and the same world without the robot in the package's worlds/ (launch/gazebo
    spawns it)."""
    out_dir = stage_dir(out_dir)  # published by robotkit.pipeline.publish with the robot
    pkg = out_dir / robot.name / layout.WORLDS
    tasks = []
    for w in robot.worlds:
        root = out_join(out_dir, w.name, key=f"worlds.{w.name}")
        targets = [root / f.format(name=w.name) for f in layout.WORLD_FILES]
        spawn = None
        if w.spawn is not None:
            spawn = {"name": robot.name, "root": robot.root, "xyz": list(w.spawn.xyz), "rpy": list(w.spawn.rpy),
                     "quat": list(rpy_quat(w.spawn.rpy))}
        deps = [w.map] + map_image(w.map)
        config = {"height": w.height, "unknown_as_wall": w.unknown_as_wall}
        tasks.append({
            "name": f"world:{w.name}",
            "doc": f"world {w.name} from {os.path.basename(w.map)}",
            "actions": [(actions.world, [w.map, str(out_dir), w.name, w.height, w.unknown_as_wall, spawn])],
            "file_dep": deps,
            "targets": [str(t) for t in targets],
            "uptodate": [config_changed({**config, "spawn": spawn, "templates": world_templates()})],
            # a world with the robot in it names its model.sdf (model://) and its MJCF
            "task_dep": [f"{robot.name}:{n}" for n in ("sdf", "model.config", "mjcf") if spawn is not None],
            "clean": True,
        })
        tasks.append({
            "name": f"{robot.name}:world:{w.name}",
            "doc": f"{layout.WORLDS}/{w.name}/ of package {robot.name}",
            "actions": [(actions.world, [w.map, str(pkg), w.name, w.height, w.unknown_as_wall, None])],
            "file_dep": deps,
            "targets": [str(pkg / t.relative_to(root.parent)) for t in targets],
            "uptodate": [config_changed({**config, "templates": world_templates()})],
            "clean": True,
        })
    return tasks


def map_image(map_yaml: str) -> list[str]:
    """The image a map YAML names (cheap: the YAML only), when it exists; the task reports the rest."""
    try:
        if os.path.getsize(map_yaml) > MAX_YAML_BYTES:
            return []
        with open(map_yaml, encoding="utf-8") as f:
            text = f.read()
        if yaml_limits(text) is not None:  # the world task reports it
            return []
        image = (yaml.safe_load(text) or {}).get("image")
    except (OSError, UnicodeDecodeError, yaml.YAMLError, AttributeError):
        return []
    path = Path(map_yaml).parent / str(image)
    return [str(path)] if image and path.is_file() else []


def world_templates() -> list[str]:
    """A digest of the world templates (their edits rebuild the worlds)."""
    out = []
    for d in template_dirs():
        for p in sorted((Path(d) / "world").glob("*.j2")):
            out.append(p.read_text(encoding="utf-8"))
        if out:
            break
    return [hashlib.sha1("".join(out).encode()).hexdigest()]


def all_tasks(recipe_files, out_dir, args: dict[str, str] | None = None, ignore_unknown_args: bool = False,
              report: bool = True) -> list[dict]:
    """Every recipe's tasks, each robot's followed by ``<robot>:publish`` (dodo.py; ``robotkit
    build`` publishes after doit ran, robotkit.pipeline.runner)."""
    tasks = []
    for loaded, robot in load_robots(recipe_files, None, args, ignore_unknown_args):
        mine = robot_tasks(robot, out_dir, mesh_locations(loaded, robot), report=report,
                           outputs=outputs_of(robot, FORMATS, loaded.recipe.outputs))
        tasks.extend(mine)
        tasks.append(publish_task(robot.name, out_dir, mine))
    return tasks


def publish_task(name: str, out_dir, tasks: list[dict]) -> dict:
    """Publish the robot's folders once all its tasks succeeded (doit skips it otherwise)."""
    plain = [{"name": t["name"], "targets": list(t.get("targets", []))} for t in tasks]
    return {
        "name": f"{name}:publish",
        "doc": f"publish {name}",
        "actions": [(actions.publish_outputs, [str(Path(out_dir).absolute()), name, plain])],
        "task_dep": [t["name"] for t in tasks],
        "uptodate": [False],  # cheap when nothing changed: the published files are the staged ones
    }
