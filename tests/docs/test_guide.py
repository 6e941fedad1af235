"""docs/guide.md: every file it shows is written and every command block run, in order, in a
scratch folder holding the repository's example meshes; the results are looked at."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest
import yaml

from conftest import REPO, RECIPES
from tests.check.test_render import SCHEMA, workflow_command

GUIDE = REPO / "docs" / "guide.md"
BLOCK = re.compile(r"(?:<!-- file: (?P<file>\S+) -->\n)?```(?P<lang>\w+)\n(?P<body>.*?)```", re.S)
WARNING = re.compile(r"^[^\s:]+:\d+: [^\s:]+: warning: ")


def blocks() -> list[tuple[str | None, str, str]]:
    return [(m["file"], m["lang"], m["body"]) for m in BLOCK.finditer(GUIDE.read_text(encoding="utf-8"))]


def test_every_example_is_marked():
    """An unmarked block would be an example nobody runs."""
    assert [b for b in blocks() if b[0] is None] == []


@pytest.fixture(scope="module")
def guide_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("guide")
    meshes = folder / "recipes" / "meshes"
    shutil.copytree(RECIPES / "meshes" / "turret_bot", meshes / "turret_bot")
    (meshes / "turtlebot3").mkdir()
    shutil.copy(RECIPES / "meshes" / "turtlebot3" / "lds.stl", meshes / "turtlebot3")
    env = {**os.environ, "PATH": os.path.dirname(sys.executable) + os.pathsep + os.environ["PATH"]}
    runs = {}
    for name, lang, body in blocks():
        if lang == "sh":
            runs[name] = proc = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", body], cwd=folder, env=env,
                                               capture_output=True, text=True)
            assert proc.returncode == 0, f"{name}:\n{body}\n{proc.stdout}\n{proc.stderr}"
        else:
            (folder / name).parent.mkdir(parents=True, exist_ok=True)
            (folder / name).write_text(body, encoding="utf-8")
    return folder, runs


@pytest.mark.slow
def test_guide_commands_run(guide_run):
    folder, runs = guide_run
    for name, proc in runs.items():
        assert "Traceback" not in proc.stderr, name
        # a build's warnings are one line each, located in the recipe; other lines are progress or
        # summaries (the importer's notes are about the file it reads)
        unplaced = [line for line in proc.stderr.splitlines() if "warning:" in line and not WARNING.match(line)]
        assert name == "import" or unplaced == [], name
    for robot in ("my_bot", "meshes_demo", "inertials_demo", "rover_mini", "contacts_demo", "world_bot"):
        out = folder / "build" / robot
        assert (out / "urdf" / f"{robot}.urdf").is_file() and (out / "mjcf" / f"{robot}.xml").is_file(), robot
    assert (folder / "worlds" / "room" / "meshes" / "room.stl").is_file()
    assert (folder / "build" / "room" / "room.world").is_file()  # the recipe's world, beside the robot
    imported = yaml.safe_load((folder / "imported.yaml").read_text())
    assert imported["robot"] == "contacts_demo" and set(imported["links"]) == {"base", "slider"}


@pytest.mark.slow
def test_guide_inertials_are_the_known_answers(guide_run):
    folder, _ = guide_run
    report = json.loads((folder / "build" / "inertials_demo" / "report.json").read_text())["inertials"]
    assert report["base"]["mass"] == pytest.approx(2700 * 0.3 * 0.2 * 0.05, rel=1e-12)  # 8.1 kg
    assert report["arm"]["mass"] == pytest.approx(0.4, rel=1e-12)
    assert report["tool"]["mass"] == 1.0 and report["tool"]["com"] == [0, 0, 0.01]
    assert "marker" not in report
    check = json.loads((folder / "inertials-check.json").read_text())
    assert check["errors"] == 0  # 8.1 + 0.4 + 1.0 = 9.5 kg: the measured mass


@pytest.mark.slow
def test_guide_ci_outputs_are_what_ci_reads(guide_run):
    import xmlschema

    folder, runs = guide_run
    report = folder / "contacts-junit.xml"
    xmlschema.XMLSchema(SCHEMA).validate(str(report))
    suite = ET.parse(report).getroot().find("testsuite")
    assert int(suite.get("tests")) >= 1
    for line in runs["ci"].stdout.splitlines():
        command, props, _ = workflow_command(line)
        assert props["file"] in ("meshes.yaml", "rover_mini.yaml"), line
    assert not (folder / "build" / "rover_mini" / "report").exists()  # --temp-out: built elsewhere


@pytest.mark.slow
def test_guide_workflow_and_hook_name_what_exists(guide_run):
    folder, _ = guide_run
    action = yaml.safe_load((REPO / "action.yml").read_text())
    workflow = yaml.safe_load((folder / ".github" / "workflows" / "robots.yml").read_text())
    step = next(s for s in workflow["jobs"]["check"]["steps"] if "robotkit@" in s.get("uses", ""))
    assert set(step["with"]) <= set(action["inputs"])
    hooks = {h["id"] for h in yaml.safe_load((REPO / ".pre-commit-hooks.yaml").read_text())}
    config = yaml.safe_load((folder / ".pre-commit-config.yaml").read_text())
    assert {h["id"] for r in config["repos"] for h in r["hooks"]} <= hooks
