"""The task dicts of a small robot, as data (robotkit.pipeline.tasks: no doit run), and every
registered output format (robotkit.emit.registry.FORMATS) rendered for a small finalized robot."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from robotkit.emit import layout
from robotkit.emit.registry import FORMATS
from robotkit.emit.env import template_dirs
from robotkit.emit.formats import READS
from robotkit.emit.meshfiles import conversions
from robotkit.mesh.io import read_vertices
from robotkit.model.load import load_robots, mesh_locations
from robotkit.model.resolve import finalize
from robotkit.pipeline import actions
from robotkit.pipeline.tasks import robot_tasks
from tests.conftest import RECIPES, write_recipe

RECIPE = """
robot: bot
moveit: true  # every registered format is written
units: m
density: 1000
materials:
  grey: {rgba: [0.5, 0.5, 0.5, 1]}
links:
  base: {visual: {box: {size: [0.2, 0.2, 0.1]}}, collision: {box: {size: [0.2, 0.2, 0.1]}}}
  arm: {visual: {mesh: slider.stl, material: grey}}
joints:
  j1: {type: revolute, parent: base, child: arm, axis: [0, 0, 1],
       limit: {lower: -1, upper: 1, effort: 1, velocity: 1}}
actuators:
  j1: {interface: position, p: 10, i: 0, d: 1}
"""


@pytest.fixture
def bot(tmp_path):
    recipe = write_recipe(tmp_path / "recipe", RECIPE, "bot.yaml",
                          {"slider.stl": RECIPES / "meshes" / "turret_bot" / "slider.stl"})
    [(loaded, robot)] = load_robots([recipe])
    out = tmp_path / "out"
    return robot, out, robot_tasks(robot, out, mesh_locations(loaded, robot))


def by_name(tasks: list[dict]) -> dict[str, dict]:
    return {t["name"]: t for t in tasks}


def test_task_names_one_per_unit_of_work_and_one_per_format(bot):
    robot, _, tasks = bot
    names = [t["name"] for t in tasks]
    assert len(names) == len(set(names))
    [key] = robot.meshes()
    # the arm collides with its visual mesh: converted to OBJ for every format
    assert names == [f"bot:mesh:{key}", "bot:copy:slider.stl", "bot:convert:collision/slider.obj",
                     "bot:inertial:base", "bot:inertial:arm", "bot:drives", "bot:self-collision",
                     *(f"bot:{name}" for name in FORMATS)]


def test_targets_below_the_staged_robot_folder_and_the_records(bot):
    robot, out, tasks = bot
    stage, state = out / ".robotkit" / "stage" / "bot", out / ".robotkit" / "bot"
    [key] = robot.meshes()
    t = by_name(tasks)
    assert t[f"bot:mesh:{key}"]["targets"] == [str(state / "mesh" / f"{key}.json")]
    assert t["bot:copy:slider.stl"]["targets"] == [str(stage / "meshes" / "visual" / "slider.stl")]
    assert t["bot:inertial:arm"]["targets"] == [str(state / "inertial" / "arm.json")]
    assert t["bot:urdf"]["targets"] == [str(stage / "urdf" / "bot.urdf")]
    assert t["bot:report"]["targets"] == [str(stage / "report.json")]
    assert t["bot:env-hook"]["targets"] == [str(stage / "hooks" / "bot.dsv.in")]
    assert t["bot:controllers"]["targets"] == [str(stage / "config" / "controllers.yaml")]
    for fmt in FORMATS.values():
        assert t[f"bot:{fmt.name}"]["doc"] == layout.output_path(fmt.path, "bot", robot.ros)


def test_file_deps_name_the_records_templates_and_mesh_files_each_output_reads(bot):
    robot, out, tasks = bot
    [key] = robot.meshes()
    facts, state = str(out / ".robotkit" / "bot" / "mesh" / f"{key}.json"), out / ".robotkit" / "bot"
    inertials = [str(state / "inertial" / "base.json"), str(state / "inertial" / "arm.json")]
    t = by_name(tasks)
    assert t["bot:copy:slider.stl"]["file_dep"][1:] == [facts]  # never copied before its mesh task checked it
    assert t["bot:inertial:arm"]["file_dep"] == [facts]
    assert t["bot:inertial:base"]["file_dep"] == []
    drives = str(state / "drives.json")  # the actuators' gains and checks, from every inertial
    assert t["bot:drives"]["file_dep"] == inertials and t["bot:drives"]["targets"] == [drives]
    matrix = str(state / "self_collision.json")  # the self-collision matrix, on the MJCF's collision geometry
    collide = t["bot:self-collision"]
    assert collide["targets"] == [matrix] and collide["file_dep"] == [facts, *(  # geometry only, no inertial
        t["bot:copy:slider.stl"]["targets"] + t["bot:convert:collision/slider.obj"]["targets"])] + [
        str(Path(collide["file_dep"][-1]))] and collide["file_dep"][-1].endswith("robot.xml.j2")
    urdf = t["bot:urdf"]["file_dep"]
    assert urdf[:2] == inertials and [Path(p).name for p in urdf[2:]] == ["robot.urdf.j2", "sdf.j2", "classic.j2",
                                                                          "drives.json", "self_collision.json"]
    assert t["bot:report"]["file_dep"] == [facts, *inertials, drives, matrix]  # every fact and inertial
    assert [Path(p).name for p in t["bot:srdf"]["file_dep"]] == ["robot.srdf.j2", "self_collision.json"]
    assert t["bot:rviz"]["file_dep"] == [facts]  # the visual mesh's extent: no inertial
    assert [Path(p).name for p in t["bot:package.xml"]["file_dep"]] == ["package.xml.j2"]
    assert t["bot:controllers"]["file_dep"] == []
    mjcf = t["bot:mjcf"]["file_dep"]  # the MJCF measures the mesh files written beside it
    assert mjcf[-4:] == (t["bot:copy:slider.stl"]["targets"] + t["bot:convert:collision/slider.obj"]["targets"]
                         + t["bot:drives"]["targets"] + [matrix])
    assert t["bot:convert:collision/slider.obj"]["file_dep"] == [robot.meshes()[key].source, facts]
    for fmt in FORMATS.values():  # no output before every mesh task succeeded, nor before the files it names
        assert t[f"bot:{fmt.name}"]["task_dep"] == [f"bot:mesh:{key}"] + [f"bot:{n}" for n in fmt.needs if
                                                                         f"bot:{n}" in t]
    assert t["bot:display-launch"]["task_dep"][1:] == ["bot:urdf", "bot:rviz"]
    assert t["bot:model.config"]["task_dep"][1:] == ["bot:sdf"]
    assert t["bot:mjcf-scene"]["task_dep"][1:] == ["bot:mjcf"]


def config(task: dict) -> dict:
    """The values a task's config_changed hashes (doit's own encoding: JSON)."""
    [check] = task["uptodate"]
    return json.loads(check.config) if isinstance(check.config, str) else check.config


def test_config_changed_holds_exactly_what_each_output_reads(bot):
    robot, _, tasks = bot
    t = by_name(tasks)
    [key] = robot.meshes()
    assert config(t[f"bot:mesh:{key}"]) == {"scale": [1.0, 1.0, 1.0], "policy": "error",
                                             "version": actions.FACTS_VERSION}
    assert set(config(t["bot:model.config"])["robot"]) == {"name", "metadata"}  # no geometry, no inertial
    assert config(t["bot:model.config"])["options"] == {"sdf": "model.sdf"}
    assert set(config(t["bot:package.xml"])["robot"]) == {"name", "metadata", "ros", "gazebo", "sensors",
                                                           "actuators", "poses", "worlds", "meshes", "moveit"}
    controllers = config(t["bot:controllers"])["robot"]
    assert set(controllers) == {"name", "ros", "gazebo", "actuators", "poses"}
    assert {k: controllers["actuators"][0][k] for k in ("joint", "interface", "p", "i", "d", "auto")} == {
        "joint": "j1", "interface": "position", "p": 10.0, "i": 0.0, "d": 1.0, "auto": False}
    assert config(t["bot:controllers"])["options"] == {"raw": True}  # given gains: not the drives' record
    assert config(t["bot:mjcf"])["options"] == {"meshes": True, "drives": True, "matrix": True}
    assert config(t["bot:report"])["options"] == {"facts": True, "drives": True, "matrix": True}
    assert set(config(t["bot:srdf"])["robot"]) == {"name", "base", "poses", "joints", "links"}
    assert set(config(t["bot:self-collision"])["robot"]) == {"name", "links", "joints", "base", "poses",
                                                             "self_collision"}
    assert config(t["bot:rviz"])["options"] == {"raw": True, "facts": True}
    rviz_links = config(t["bot:rviz"])["robot"]["links"]
    assert rviz_links and not any("inertial" in link or "inertial_spec" in link for link in rviz_links)
    assert "inertial_spec" in config(t["bot:urdf"])["robot"]["links"][0]


def test_a_robot_without_actuators_has_no_controllers_task(tmp_path):
    recipe = write_recipe(tmp_path, RECIPE.split("actuators:")[0], "bot.yaml",
                          {"slider.stl": RECIPES / "meshes" / "turret_bot" / "slider.stl"})
    [(loaded, robot)] = load_robots([recipe])
    names = [t["name"] for t in robot_tasks(robot, tmp_path / "out")]
    assert "bot:controllers" not in names and "bot:urdf" in names


def test_the_report_task_reads_the_written_descriptions_and_meshes(bot, tmp_path):
    robot, out, _ = bot
    tasks = robot_tasks(robot, out, report=True)
    [report] = [t for t in tasks if t["name"] == "bot:report-html"]
    stage = out / ".robotkit" / "stage" / "bot"
    assert report["targets"] == [str(stage / "report" / "report.html"), str(out / ".robotkit" / "bot" / "pictures.json")]
    # redrawn when it was written without pictures (MuJoCo could not draw): the record says so
    pictures_drawn, [record] = report["uptodate"][1]
    assert pictures_drawn(record)  # no record yet: nothing to redraw
    Path(record).parent.mkdir(parents=True, exist_ok=True)
    Path(record).write_text('{"no_pictures": "no OpenGL"}')
    assert not pictures_drawn(record)
    assert report["file_dep"][:4] == [str(stage / "urdf" / "bot.urdf"), str(stage / "mjcf" / "bot.xml"),
                                      str(stage / "report.json"), str(stage / "meshes" / "visual" / "slider.stl")]


# ---------------------------------------------------------------- the format registry


@pytest.fixture(scope="module")
def finalized(tmp_path_factory):
    """A small robot finalized with its real mesh facts (the mesh task's action, no doit)."""
    folder = tmp_path_factory.mktemp("formats")
    recipe = write_recipe(folder / "recipe", RECIPE, "bot.yaml",
                          {"slider.stl": RECIPES / "meshes" / "turret_bot" / "slider.stl"})
    [(loaded, robot)] = load_robots([recipe])
    facts = {}
    for key, mesh in robot.meshes().items():
        target = str(folder / f"{key}.json")
        assert actions.mesh_facts(mesh.source, list(mesh.scale), mesh.open_mesh, {}, target) is None
        facts[key] = json.loads(Path(target).read_text())
    return finalize(robot, facts), facts


@pytest.mark.parametrize("name", list(FORMATS))
def test_every_registered_format_renders_below_the_robot_folder(name, finalized, tmp_path):
    robot, facts = finalized
    fmt = FORMATS[name]
    assert fmt.reads in READS
    options = dict(fmt.options, **({"facts": facts} if fmt.reads in ("summary", "rviz") else {}))
    if fmt.points is not None:  # the files the build writes first (here: the arm's collision OBJ)
        [(rel, (source, scale))] = conversions(robot).items()
        assert fmt.points(robot) == [rel]
        actions.convert_mesh(source, str(tmp_path / rel), list(scale))
        options["points"] = {rel: read_vertices(str(tmp_path / rel))}
    text = fmt.render(robot, **options)
    assert isinstance(text, str) and text.strip()
    root = Path("/out/bot")
    path = layout.robot_layout(root).path(fmt.path, robot.ros)
    assert path.is_relative_to(root) and ".." not in path.relative_to(root).parts
    for template in fmt.templates:
        assert any((Path(d) / template).is_file() for d in template_dirs()), template


def test_dump_json_writes_float_rows_as_json_does():
    """dump_json formats a record's rows of floats (hull points) itself: the text json.dumps gives,
    for rows with -0.0, tiny and huge numbers, and for what it leaves to json (ints, bools, NaN,
    rows of unequal length, empty lists, a list at the top)."""
    hull = [[0.1 * i, -0.0, 1e-300 * i, 1e22 + i] for i in range(50)]
    cases = [{"version": 4, "hull": hull, "inertia": [[1.0, 0.0, 0.0]] * 3, "source": "a \"b\" é", "faces": 12},
             {"a": [[1.0, 2]], "b": [[1.0], [2.0, 3.0]], "c": [[float("nan")]], "d": [[True]], "e": [], "f": [[]]},
             [[1.0, 2.0]], {}]
    for data in cases:
        assert actions.dump_json(data) == json.dumps(data, indent=1, sort_keys=True) + "\n"
