"""Task results cached by content (robotkit.pipeline.actions.cached_task): a build into a fresh
output folder takes every pure task's files from the cache (the picture report among them),
byte-identical to the build that stored them; a changed model is another key."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from robotkit.mesh.cache import Cache, Files
from robotkit.model.load import load_robots, mesh_locations
from robotkit.pipeline.runner import build, warm
from robotkit.pipeline.tasks import robot_tasks

REPO = Path(__file__).resolve().parents[2]

RECIPE = """robot: bot
units: m
density: 1000
links:
  base: {visual: {box: {size: [0.2, 0.2, 0.1]}}}
  arm: {visual: {mesh: slider.stl}}
joints:
  j1: {type: revolute, parent: base, child: arm, axis: [0, 0, 1],
       limit: {lower: -1, upper: 1, effort: 1, velocity: 1}}
"""


@pytest.fixture
def project(tmp_path, monkeypatch):
    monkeypatch.setenv("ROBOTKIT_CACHE", str(tmp_path / "cache"))
    (tmp_path / "bot.yaml").write_text(RECIPE)
    shutil.copy(REPO / "recipes" / "meshes" / "turret_bot" / "slider.stl", tmp_path / "slider.stl")
    return tmp_path


def files(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def entries(cache: Path, op: str) -> dict[str, dict]:
    """The cache's manifests of task results of ``op`` (report-html, urdf...), by key."""
    out = {}
    for m in cache.glob("v1/*/*.json"):
        manifest = json.loads(m.read_text())
        if manifest["op"] == f"task/{op}":
            out[manifest["key"]] = manifest
    return out


def test_files_entry_round_trip_and_verification(tmp_path):
    cache = Cache(tmp_path, versions={})
    value = Files({"a/b.txt": b"hello", "c.bin": bytes(range(256)), "empty": b""})
    key = cache.key("task/test", {"n": 1}, [b"input"])
    assert cache.put(key, value, op="task/test") == value
    assert cache.get(key) == value and isinstance(cache.get(key), Files)
    payload = next(tmp_path.glob("v1/*/*.bin"))
    payload.write_bytes(payload.read_bytes()[:-1] + b"x")  # same size, other bytes: a corrupt entry
    assert cache.get(key) is None and not payload.exists()
    # a manifest naming a file outside the output folder is refused, never written
    empty = "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
    (cache.folder(key) / f"{key}.e3b0c44298fc1c14.bin").write_bytes(b"")
    cache.manifest_path(key).write_text(json.dumps({
        "format": 1, "key": key, "kind": "files", "meshes": [{"file": "../escape", "size": 0}],
        "payload": {"file": f"{key}.e3b0c44298fc1c14.bin", "size": 0, "sha256": empty}}))
    assert cache.get(key) is None and not cache.manifest_path(key).exists()

def test_a_fresh_folder_is_built_from_the_cache_byte_for_byte(project):
    """The second build into another folder takes its report from the cache (an entry changed
    in the cache shows in it) and its other files are the first build's, byte for byte."""
    build([project / "bot.yaml"], project / "one", report=True)
    reports = entries(project / "cache", "report-html")
    assert len(reports) == 1 and entries(project / "cache", "urdf")
    key = next(iter(reports))
    cache = Cache(project / "cache", versions={})
    stored = cache.get(key)
    assert "bot/report/report.html" in [name.split(".robotkit/stage/", 1)[-1] for name in stored]
    page = next(name for name in stored if name.endswith("report/report.html"))
    assert any(name.endswith("report/front.png") for name in stored)
    marked = Files({**stored, page: stored[page] + b"<!-- from the cache -->\n"})
    cache.put(key, marked, op="task/report-html")

    build([project / "bot.yaml"], project / "two", report=True)

    one, two = files(project / "one" / "bot"), files(project / "two" / "bot")
    assert two.pop("report/report.html").endswith(b"<!-- from the cache -->\n")
    one.pop("report/report.html")
    assert one == two


def test_the_report_key_is_what_the_pictures_are_drawn_from(project):
    """A comment in the recipe (every line below it moves) leaves the model the pictures are drawn
    from as it was: one report entry, the same files; a changed link makes another entry."""
    build([project / "bot.yaml"], project / "one", report=True)
    (project / "bot.yaml").write_text(RECIPE.replace("density: 1000", "density: 1000\n# a comment\n"))
    build([project / "bot.yaml"], project / "two", report=True)
    assert len(entries(project / "cache", "report-html")) == 1
    (project / "bot.yaml").write_text(RECIPE.replace("[0.2, 0.2, 0.1]", "[0.3, 0.2, 0.1]"))
    build([project / "bot.yaml"], project / "three", report=True)
    assert len(entries(project / "cache", "report-html")) == 2
    assert files(project / "one" / "bot") == files(project / "two" / "bot")


def tasks_of(recipe: Path, out: Path) -> list[dict]:
    return [t for loaded, robot in load_robots([recipe])
            for t in robot_tasks(robot, out.absolute(), mesh_locations(loaded, robot))]


def test_a_build_from_the_cache_runs_in_this_process(project):
    """warm(): a build whose tasks all find their results in the cache runs in this process (no
    doit process pool) even with -j 2; a cold one, or one with a changed mesh, in the pool.  The
    files and the tasks run are the same either way."""
    recipe = project / "bot.yaml"
    assert not warm(tasks_of(recipe, project / "one"))  # an empty cache
    first = build([recipe], project / "one", jobs=2)
    assert warm(tasks_of(recipe, project / "two"))
    second = build([recipe], project / "two", jobs=2)
    assert sorted(second.ran) == sorted(first.ran) and not second.failed and not second.errors
    assert files(project / "two" / "bot") == files(project / "one" / "bot")
    shutil.copy(REPO / "recipes" / "meshes" / "turret_bot" / "rotor.stl", project / "slider.stl")
    assert not warm(tasks_of(recipe, project / "three"))  # the mesh's facts are to compute


def test_mesh_facts_are_shared_by_recipes_naming_the_same_file(project):
    """A mesh's facts are cached by its content, scale and policy, not by the recipe file and
    line naming it: a second recipe (the mesh two lines further down) measures nothing again (an
    entry changed in the cache shows in its record, which is otherwise the first's); another
    scale is another entry."""
    build([project / "bot.yaml"], project / "one", report=False)

    def measured() -> dict:
        return {m["key"]: m for m in (json.loads(p.read_text()) for p in (project / "cache").glob("v1/*/*.json"))
                if m["op"] == "mesh-facts"}

    assert len(measured()) == 1
    key = next(iter(measured()))
    cache = Cache(project / "cache", versions={})
    _, info = cache.get(key)
    facts = json.loads(info["facts"])
    assert facts["volume"] > 0 and facts["warnings"] == [] and "source" not in facts
    cache.put(key, ([], {"facts": json.dumps({**facts, "repairs": ["from the cache"]})}), op="mesh-facts")

    other = "# another recipe\n\n" + RECIPE.replace("robot: bot", "robot: other")
    (project / "other.yaml").write_text(other)
    build([project / "other.yaml"], project / "two", report=False)

    one = json.loads(next((project / "one" / ".robotkit" / "bot" / "mesh").glob("*.json")).read_text())
    two = json.loads(next((project / "two" / ".robotkit" / "other" / "mesh").glob("*.json")).read_text())
    assert one["repairs"] == [] and two["repairs"] == ["from the cache"]
    assert {**two, "repairs": []} == one and one["source"] == "slider.stl"

    (project / "other.yaml").write_text(other.replace("mesh: slider.stl}", "mesh: slider.stl, scale: [2, 2, 2]}"))
    build([project / "other.yaml"], project / "three", report=False)
    assert len(measured()) == 2
