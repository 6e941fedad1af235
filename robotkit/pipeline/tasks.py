"""doit task dictionaries for a resolved robot: one task per unit of work.

- ``<robot>:mesh:<key>``: load one mesh (file, scale, open-mesh policy), repair,
  record its unit-density mass properties as JSON (state folder);
- ``<robot>:copy:<file>``: the visual mesh file into ``meshes/visual/``;
- ``<robot>:inertial:<link>``: one link's inertial from its mesh facts;
- ``<robot>:<output>``: one output file per registered emitter.

Every task names its inputs (``file_dep``), outputs (``targets``) and the
recipe values that matter (``config_changed``), so doit reruns exactly what
an edit affects.  The same task list serves ``robotkit build`` and ``doit``
(dodo.py).
"""

from __future__ import annotations

import os
from dataclasses import asdict, replace
from pathlib import Path

from doit.tools import config_changed

from robotkit.pipeline import actions
from robotkit.emit import TEMPLATES, ros
from robotkit.emit.env import template_dirs
from robotkit.model.load import load_robots, mesh_locations
from robotkit.model.robot import Robot
from robotkit.paths import file_stem, out_join
from robotkit.pipeline.publish import STATE, stage_dir  # STATE: below the output folder, doit's database and JSON



# emitter -> path below the robot folder
OUTPUTS = {
    "urdf": lambda r: f"urdf/{r.name}.urdf",
    "xacro": lambda r: f"urdf/{r.name}.urdf.xacro",
    "sdf": lambda r: "model.sdf",
    "mjcf": lambda r: f"mjcf/{r.name}.xml",
    "mjcf-scene": lambda r: "mjcf/scene.xml",
    "report": lambda r: "report.json",
    "model.config": lambda r: "model.config",
    "package.xml": lambda r: "package.xml",
    "CMakeLists.txt": lambda r: "CMakeLists.txt",
    "env-hook": lambda r: ros.env_hook_path(r),
    "display-launch": lambda r: ros.launch_path(r, "display"),
    "gazebo-launch": lambda r: ros.launch_path(r, "gazebo"),
    "rviz": lambda r: f"rviz/{r.name}.rviz",
    "controllers": lambda r: "config/controllers.yaml",
}
# emitters that read only the robot's name and metadata (no geometry, no inertials)
METADATA_ONLY = {"model.config", "mjcf-scene"}
# emitters that read the robot's structure but no inertial or mesh fact
STRUCTURE_ONLY = {"controllers"}
# the ROS package files: the unfinalized robot (which folders, sensors, actuators, worlds, metadata)
ROS_PACKAGE = {"package.xml", "CMakeLists.txt", "env-hook", "display-launch", "gazebo-launch"}


def _template_files(emitter: str) -> list[str]:
    out = []
    for name in TEMPLATES[emitter]:
        for d in template_dirs():
            p = Path(d) / name
            if p.is_file():
                out.append(str(p))
                break
    return out


def robot_tasks(robot: Robot, out_dir: str | os.PathLike, where: dict | None = None,
                report: bool = False) -> list[dict]:
    """The task dicts that build ``robot`` into ``out_dir/<robot>/``.

    ``where`` maps a mesh key, and ``link:<name>``, to the recipe location naming it (for messages);
    ``report`` adds the picture report (``report/report.html``).
    """
    where = where or {}
    out_dir = Path(out_dir).absolute()
    root = out_join(stage_dir(out_dir), robot.name, key="robot")  # published by robotkit.pipeline.publish
    state = out_dir / STATE / robot.name
    where = where or {}
    tasks: list[dict] = []

    facts: dict[str, str] = {}
    for key, mesh in robot.meshes().items():
        target = str(state / "mesh" / f"{key}.json")
        facts[key] = target
        tasks.append({
            "name": f"{robot.name}:mesh:{key}",
            "doc": f"mass properties of {os.path.basename(mesh.source)}",
            "actions": [(actions.mesh_facts, [mesh.source, list(mesh.scale), mesh.open_mesh,
                                              where.get(key, {}), target])],
            "file_dep": [mesh.source],
            "targets": [target],
            "uptodate": [config_changed({"scale": list(mesh.scale), "policy": mesh.open_mesh,
                                         "version": actions.FACTS_VERSION})],
            "clean": True,
        })

    mesh_outputs: list[str] = []  # mesh files written below meshes/ (the MJCF measures them)
    copies: dict[str, tuple[str, list[str]]] = {}
    processed: dict[str, object] = {}
    shown = {g.shape.mesh.key for link in robot.links for g in robot.all_geoms(link) if g.shape.kind == "mesh"}
    for key, mesh in robot.meshes().items():
        if key not in shown:  # only the source of collision pieces
            continue
        if mesh.processed:
            processed.setdefault(mesh.path, mesh)
            continue
        copies.setdefault(mesh.file_name, (mesh.source, []))[1].append(facts[key])
    # collision pieces before the other mesh work: CoACD is the longest, and doit -j N hands
    # out tasks in list order, so the slow ones start first and the quick ones fill in around them
    proxies: dict[str, str] = {}
    for key, shape in robot.proxies().items():
        m = shape.mesh
        target = str(state / "collision" / f"{key}.json")
        proxies[key] = target
        stem = os.path.splitext(m.file_name)[0]
        tasks.append({
            "name": f"{robot.name}:collision:{key[len('proxy-'):]}",
            "doc": f"{shape.strategy.kind} collision of {os.path.basename(m.source)}",
            "actions": [(actions.collision_proxy, [m.source, list(m.scale), shape.strategy.params(), stem,
                                                   str(root / "meshes" / "collision"), where.get(m.key, {}),
                                                   target])],
            "file_dep": [m.source, facts[m.key]],
            "targets": [target],
            "uptodate": [config_changed({"scale": list(m.scale), "strategy": shape.strategy.params(),
                                         "version": actions.FACTS_VERSION})],
            "clean": True,
        })
    for rel, mesh in sorted(processed.items()):
        target = str(root / "meshes" / rel)
        mesh_outputs.append(target)
        visual_report = str(state / "visual" / f"{mesh.key}.json")
        tasks.append({
            "name": f"{robot.name}:visual:{mesh.file_name}",
            "doc": f"processed visual mesh {mesh.file_name}",
            "actions": [(actions.process_visual, [mesh.source, list(mesh.scale), list(mesh.decimate), mesh.repair,
                                                  where.get(mesh.key, {}), target, visual_report])],
            "file_dep": [mesh.source, facts[mesh.key]],
            "targets": [target, visual_report],
            "uptodate": [config_changed({"scale": list(mesh.scale), "decimate": list(mesh.decimate),
                                         "repair": mesh.repair, "version": actions.FACTS_VERSION})],
            "clean": True,
        })

    from robotkit.mesh.io import companions

    extras: dict[str, str] = {}  # textures and material files the copied meshes reference
    for file_name, (source, checked) in sorted(copies.items()):
        target = str(root / "meshes" / "visual" / file_name)
        mesh_outputs.append(target)
        for rel in companions(source):
            extras.setdefault(rel, os.path.join(os.path.dirname(source), rel))
        tasks.append({
            "name": f"{robot.name}:copy:{file_name}",
            "doc": f"visual mesh {file_name}",
            "actions": [(actions.copy_file, [source, target])],
            # after its mesh tasks: a file that cannot be used is never copied
            "file_dep": [source, *checked],
            "targets": [target],
            "clean": True,
        })

    for rel, source in sorted(extras.items()):
        tasks.append({
            "name": f"{robot.name}:copy:{rel}",
            "doc": f"texture or material file {rel}",
            "actions": [(actions.copy_file, [source, str(root / "meshes" / "visual" / rel)])],
            "file_dep": [source],
            "targets": [str(root / "meshes" / "visual" / rel)],
            "clean": True,
        })

    from robotkit.emit.meshfiles import conversions

    for rel, (source, scale) in conversions(robot).items():
        target = str(root / "meshes" / rel)
        mesh_outputs.append(target)
        checked = [facts[k] for k, m in robot.meshes().items() if m.source == source]
        tasks.append({
            "name": f"{robot.name}:convert:{rel}",
            "actions": [(actions.convert_mesh, [source, target, list(scale)])],
            "file_dep": [source, *checked],
            "targets": [target],
            "uptodate": [config_changed({"version": actions.FACTS_VERSION, "scale": list(scale)})],
            "clean": True,
            "doc": f"meshes/{rel}",
        })

    inertials: dict[str, str] = {}
    for link in robot.links:
        if link.inertial_spec.mode not in ("density", "mass", "estimate"):
            continue
        keys = sorted({g.shape.mesh.key for g in link.source_geoms() if g.shape.mesh is not None})
        deps = {k: facts[k] for k in keys}
        target = str(state / "inertial" / f"{file_stem(link.name)}.json")
        inertials[link.name] = target
        tasks.append({
            "name": f"{robot.name}:inertial:{link.name}",
            "doc": f"inertial of link {link.name}",
            "actions": [(actions.link_inertial, [link, deps, target])],
            "file_dep": list(deps.values()),
            "targets": [target],
            "uptodate": [config_changed({"link": asdict(link), "version": actions.FACTS_VERSION})],
            "clean": True,
        })

    # outputs need the facts of recentered meshes (their offsets) and every inertial
    recentered = sorted({g.shape.mesh.key for link in robot.links for g in robot.all_geoms(link)
                         if g.shape.mesh is not None and g.recenter != "none"})
    out_facts = {**{k: facts[k] for k in recentered}, **proxies}
    structure = {k: v for k, v in robot.to_dict().items() if k != "worlds"}
    options = {"model.config": {"sdf": "model.sdf"}, "report": {"facts": True}, "controllers": {"raw": True},
               "mjcf": {"meshes": True}, "rviz": {"raw": True, "facts": True},
               **{e: {"raw": True} for e in ROS_PACKAGE}}
    for emitter, rel in OUTPUTS.items():
        if emitter == "controllers" and not robot.actuators:
            continue
        target = str(root / rel(robot))
        opts = options.get(emitter, {})
        if emitter == "report":
            subject, reads, facts_in, inertials_in = robot, structure, {**facts, **proxies}, inertials
        elif emitter == "rviz":  # the visual geometry's extent, the sensors' topics: no inertial
            subject, facts_in, inertials_in = robot, {k: facts[k] for k in shown if k in facts}, {}
            reads = {**structure, "links": [{k: v for k, v in link.items() if k not in ("inertial_spec", "inertial")}
                                            for link in structure["links"]]}
        elif emitter in ROS_PACKAGE:
            subject, facts_in, inertials_in = robot, {}, {}
            reads = {k: structure.get(k) for k in ("name", "metadata", "ros", "gazebo", "sensors", "actuators")}
            reads.update(worlds=[(w.name, w.spawn and asdict(w.spawn)) for w in robot.worlds],
                         meshes=bool(robot.meshes()))
        elif emitter in STRUCTURE_ONLY:
            subject, facts_in, inertials_in = robot, {}, {}
            reads = {"name": robot.name, "ros": robot.ros, "gazebo": robot.gazebo,
                     "actuators": [asdict(a) for a in robot.actuators]}
        elif emitter in METADATA_ONLY:
            subject = replace(robot, links=(), joints=(), materials=())
            reads: dict = {"name": robot.name, "metadata": asdict(robot.metadata)}
            facts_in, inertials_in = {}, {}
        else:
            subject, reads, facts_in, inertials_in = robot, structure, out_facts, inertials
        tasks.append({
            "name": f"{robot.name}:{emitter}",
            "doc": f"{rel(robot)}",
            "actions": [(actions.emit, [emitter, subject, facts_in, inertials_in, target, opts,
                                        {k[5:]: v for k, v in where.items() if k.startswith("link:")}])],
            "file_dep": list(facts_in.values()) + list(inertials_in.values()) + _template_files(emitter)
            + (mesh_outputs if opts.get("meshes") else []),
            "targets": [target],
            "uptodate": [config_changed({"robot": reads, "options": opts})],
            # no output is written while any mesh of the robot fails
            "task_dep": [f"{robot.name}:mesh:{k}" for k in facts],
            "clean": True,
        })
    if report:
        tasks.append(report_task(robot, root, tasks))
    return tasks + world_tasks(robot, out_dir)


REPORT = "report/report.html"  # the picture report, below the robot folder


def report_task(robot: Robot, root: Path, tasks: list[dict]) -> dict:
    """``<robot>:report-html``: report.html and its pictures, from the written URDF, MJCF,
    report.json and every mesh file MuJoCo reads (rendering imports stay in the action)."""
    from robotkit.picture import VERSION
    from robotkit.picture.page import TEMPLATE

    inputs = [str(root / OUTPUTS[e](robot)) for e in ("urdf", "mjcf", "report")]
    for t in tasks:  # the meshes the MJCF draws, and the collision pieces' records
        kind = t["name"].split(":")[1]
        if kind in ("copy", "visual", "convert", "collision"):
            inputs += t["targets"]
    template = [p for d in template_dirs() if (p := Path(d) / TEMPLATE).is_file()][:1]
    return {
        "name": f"{robot.name}:report-html",
        "doc": REPORT,
        "actions": [(actions.picture_report, [str(root), str(root / "report")])],
        "file_dep": inputs + [str(p) for p in template],
        "targets": [str(root / REPORT)],
        "uptodate": [config_changed({"version": VERSION})],
        "task_dep": [t["name"] for t in tasks if ":mesh:" in t["name"]],
        "clean": True,
    }


def world_tasks(robot: Robot, out_dir: str | os.PathLike) -> list[dict]:
    """One task per world of the recipe: OUT/<world>/ with its five files."""
    out_dir = stage_dir(out_dir)  # published by robotkit.pipeline.publish with the robot
    tasks = []
    for w in robot.worlds:
        root = out_join(out_dir, w.name, key=f"worlds.{w.name}")
        targets = [root / "model.config", root / "model.sdf", root / "meshes" / f"{w.name}.stl",
                   root / f"{w.name}.world", root / "scene.xml"]
        spawn = None
        if w.spawn is not None:
            from robotkit.geometry import rpy_quat

            spawn = {"name": robot.name, "root": robot.root, "xyz": list(w.spawn.xyz), "rpy": list(w.spawn.rpy),
                     "quat": list(rpy_quat(w.spawn.rpy))}
        tasks.append({
            "name": f"world:{w.name}",
            "doc": f"world {w.name} from {os.path.basename(w.map)}",
            "actions": [(actions.world, [w.map, str(out_dir), w.name, w.height, w.unknown_as_wall, spawn])],
            "file_dep": [w.map] + _map_image(w.map),
            "targets": [str(t) for t in targets],
            "uptodate": [config_changed({"height": w.height, "unknown_as_wall": w.unknown_as_wall,
                                         "spawn": spawn, "templates": _world_templates()})],
            "clean": True,
        })
        # the same world, without the robot (launch/gazebo spawns it), in the ROS package's worlds/
        pkg = out_dir / robot.name / "worlds"
        tasks.append({
            "name": f"{robot.name}:world:{w.name}",
            "doc": f"worlds/{w.name}/ of package {robot.name}",
            "actions": [(actions.world, [w.map, str(pkg), w.name, w.height, w.unknown_as_wall, None])],
            "file_dep": [w.map] + _map_image(w.map),
            "targets": [str(pkg / t.relative_to(root.parent)) for t in targets],
            "uptodate": [config_changed({"height": w.height, "unknown_as_wall": w.unknown_as_wall,
                                         "templates": _world_templates()})],
            "clean": True,
        })
    return tasks


def _map_image(map_yaml: str) -> list[str]:
    """The image a map YAML names (cheap: the YAML only), when it exists; the task reports the rest."""
    import yaml

    from robotkit.recipe.load import MAX_YAML_BYTES, yaml_limits

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


def _world_templates() -> list[str]:
    out = []
    for d in template_dirs():
        for p in sorted((Path(d) / "world").glob("*.j2")):
            out.append(p.read_text(encoding="utf-8"))
        if out:
            break
    import hashlib

    return [hashlib.sha1("".join(out).encode()).hexdigest()]


def all_tasks(recipe_files, out_dir, args: dict[str, str] | None = None, ignore_unknown_args: bool = False,
              report: bool = True) -> list[dict]:
    """Every recipe's tasks, each robot's followed by ``<robot>:publish`` (dodo.py; ``robotkit
    build`` publishes after doit ran, robotkit.pipeline.runner)."""
    tasks = []
    for loaded, robot in load_robots(recipe_files, None, args, ignore_unknown_args):
        mine = robot_tasks(robot, out_dir, mesh_locations(loaded, robot), report=report)
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
