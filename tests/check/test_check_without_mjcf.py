"""A build folder whose MJCF the build left out at the format's own limit (issue 33: a chain
deeper than MuJoCo's XML reader nests; report.json's ``left_out`` says why) is still a build
folder: ``robotkit check`` runs every stage that does not need the MJCF and lists the others as
skipped with the reason, ``robotkit report`` writes the page without pictures and says why, and
``robotkit view`` shows the URDF.

The fast tests lower MuJoCo's limit to 3 bodies for the build (as tests/pipeline/test_format_limit.py
does); the check reads the folder's record, not the limit.  The slow ones build a real 600-deep
chain.  The tests that run a check load the consumers (marked ``consumers``)."""

from __future__ import annotations

import json
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

import robotkit.emit.mjcf
import robotkit.model.robot
from conftest import run_cli
from robotkit.check import check_build_dir
from robotkit.commands.check import cases, check
from robotkit.commands.inputs import classify
from robotkit.commands.report import write_report
from robotkit.commands.view import resolve
from robotkit.errors import RobotkitError
from robotkit.pipeline.runner import build


def chain(n: int) -> str:
    """A chain of ``n`` boxes, primitives only, masses computed from the boxes."""
    lines = ["robot: deep", "metadata: {maintainers: [{name: A, email: a@example.com}]}", "links:"]
    lines += [f"  l{i}: {{visual: {{box: {{size: [0.05, 0.05, 0.1]}}}}, inertial: {{mass: 0.1}}}}" for i in range(n)]
    lines.append("joints:")
    lines += [f"  j{i}: {{type: revolute, parent: l{i - 1}, child: l{i}, origin: {{xyz: [0, 0, 0.1]}}, "
              "axis: [0, 0, 1], limit: {lower: -1, upper: 1, effort: 1, velocity: 1}}" for i in range(1, n)]
    return "\n".join(lines) + "\n"


WHY = ("the MJCF was left out: link 'l4' sits 5 links deep and MuJoCo's XML reader stops at 3 nested bodies "
       "(a body per link)")


@pytest.fixture(scope="module")
def lost(tmp_path_factory) -> Path:
    """A 5-link chain built with MuJoCo's limit at 3 bodies: ``out/deep`` has no mjcf/."""
    tmp = tmp_path_factory.mktemp("lost")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("ROBOTKIT_CACHE", str(tmp / "cache"))
        mp.chdir(tmp)
        mp.setattr(robotkit.emit.mjcf, "MJCF_MAX_DEPTH", 3)
        mp.setattr(robotkit.model.robot, "MJCF_MAX_DEPTH", 3)
        (tmp / "deep.yaml").write_text(chain(5))
        build(["deep.yaml"], "out", report=False)
    assert not (tmp / "out" / "deep" / "mjcf").exists()
    return tmp


def test_report_json_records_the_format_left_out_and_why(lost):
    data = json.loads((lost / "out" / "deep" / "report.json").read_text())
    assert data["left_out"] == {"mjcf": WHY.removeprefix("the MJCF was left out: ")}


@pytest.mark.consumers
def test_check_runs_the_stages_without_the_mjcf_and_skips_the_others(lost):
    proc = run_cli("check", "out/deep", "--junit", "junit.xml", cwd=lost)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stderr == ""
    lines = proc.stdout.splitlines()
    assert lines[:-1] == [
        "  ok       check_urdf",
        "  ok       ign sdf -k",
        f"  skipped  mujoco  ({WHY})",
        "  ok       lints (9 links and joints)",
        "  ok       equivalence (URDF, model.sdf and Gazebo's URDF at 100 configurations)",
        "  ok       consumers",
        f"  skipped  simulation  ({WHY})",
        f"  skipped  self-collision  ({WHY})",
        f"  skipped  motion  ({WHY})",
    ]
    assert lines[-1].startswith("out/deep: 5 stages passed, 0 errors, 0 warnings (")
    suite = ET.parse(lost / "junit.xml").getroot().find("testsuite")
    skipped = {c.get("name"): c.find("skipped").get("message") for c in suite if c.find("skipped") is not None}
    assert skipped == {"mujoco": WHY, "simulation": WHY, "self-collision": WHY, "motion": WHY}
    assert suite.get("skipped") == "4" and suite.get("failures") == "0"


@pytest.mark.consumers
def test_check_json_and_the_output_folder(lost):
    """The output folder holding the robot is a build PATH too; the JSON names why a stage was skipped."""
    proc = run_cli("check", "out", "--format", "json", cwd=lost)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    out = json.loads(proc.stdout)
    assert out["findings"] == []
    verdicts = {s["stage"]: (s["verdict"], s.get("why")) for s in out["stages"]}
    assert verdicts == {"check_urdf": ("ok", None), "ign sdf -k": ("ok", None), "mujoco": ("skipped", WHY),
                        "lints": ("ok", None), "equivalence": ("ok", None), "consumers": ("ok", None),
                        "simulation": ("skipped", WHY), "self-collision": ("skipped", WHY),
                        "motion": ("skipped", WHY)}
    assert [s["stage"] for s in out["stages"] if "seconds" in s and s["verdict"] == "skipped"] == []  # not timed


@pytest.mark.consumers
def test_check_of_the_recipe_warns_of_the_loss_and_skips_what_needs_the_mjcf(lost, monkeypatch):
    monkeypatch.setenv("ROBOTKIT_CACHE", str(lost / "cache"))
    monkeypatch.chdir(lost)
    monkeypatch.setattr(robotkit.emit.mjcf, "MJCF_MAX_DEPTH", 3)
    monkeypatch.setattr(robotkit.model.robot, "MJCF_MAX_DEPTH", 3)
    findings = check("deep.yaml", "out")
    assert [(f.severity, f.check, f.line, f.message) for f in findings] == [
        ("warning", "build", 1, "deep: not written, a limit of the format: MJCF: link 'l4' sits 5 links deep and "
         "MuJoCo's XML reader stops at 3 nested bodies (a body per link); left out: deep/mjcf/deep.xml, "
         "deep/mjcf/scene.xml (list it under outputs: to make this an error)")]
    assert [c for c in cases("deep.yaml", "out") if c[1].startswith("skipped: ")] == [
        (stage, f"skipped: {WHY}") for stage in ("mujoco", "simulation", "self-collision", "motion")]


def test_a_folder_without_its_mjcf_and_without_the_record_is_still_refused(lost, tmp_path):
    folder = tmp_path / "deep"
    shutil.copytree(lost / "out" / "deep", folder)
    data = json.loads((folder / "report.json").read_text())
    del data["left_out"]
    (folder / "report.json").write_text(json.dumps(data))
    with pytest.raises(RobotkitError) as caught:
        check_build_dir(folder)
    assert [str(p) for p in caught.value.problems] == [f"{folder}: not a robotkit build folder: mjcf/deep.xml is missing"]
    with pytest.raises(RobotkitError) as caught:
        classify(tmp_path)
    assert [str(p) for p in caught.value.problems] == [f"{tmp_path}: not a build folder (no <robot>/model.sdf below it)"]


def test_report_writes_the_page_without_pictures_and_says_why(lost, tmp_path):
    page = write_report(lost / "out" / "deep", tmp_path / "report")
    text = page.read_text(encoding="utf-8")
    assert f"No pictures: {WHY} (the pictures are drawn in MuJoCo, from the MJCF)".replace("'", "&#39;") in text
    assert sorted(p.name for p in (tmp_path / "report").iterdir()) == ["report.html"]


def test_view_shows_the_urdf(lost):
    for path in (lost / "out" / "deep", lost / "out"):
        kind, make = resolve(path, "build")
        [shown] = make()
        assert kind == "build" and shown.urdf == lost / "out" / "deep" / "urdf" / "deep.urdf"


REAL = ("the MJCF was left out: link 'l599' sits 600 links deep and MuJoCo's XML reader stops at 496 nested "
        "bodies (a body per link)")


@pytest.fixture(scope="module")
def deep600(tmp_path_factory) -> Path:
    """A real 600-deep chain (MuJoCo refuses it): built once, without its MJCF."""
    tmp = tmp_path_factory.mktemp("deep600")
    (tmp / "deep.yaml").write_text(chain(600))
    proc = run_cli("build", "deep.yaml", "--out", "out", "--no-report", cwd=tmp)
    assert proc.returncode == 0, proc.stderr
    return tmp


@pytest.mark.consumers
@pytest.mark.slow
def test_check_of_a_600_deep_chain_skips_what_needs_the_mjcf(deep600):
    """Every stage but MuJoCo's runs; the only findings are the programs with limits of their own
    (PyBullet holds at most 128 links in a body; Pinocchio's data grows with the cube of the joints)."""
    proc = run_cli("check", "out/deep", "--format", "json", cwd=deep600)
    out = json.loads(proc.stdout)
    verdicts = {s["stage"]: s["verdict"] for s in out["stages"]}
    assert {s["stage"]: s.get("why") for s in out["stages"] if s["verdict"] == "skipped"} == {
        "mujoco": REAL, "simulation": REAL, "self-collision": REAL, "motion": REAL}
    assert [verdicts[s] for s in ("check_urdf", "ign sdf -k", "lints", "equivalence")] == ["ok"] * 4
    limited = {f["message"].split(": not checked, a limit of the program: ")[0] for f in out["findings"]}
    assert all(f["check"] == "consumer" and f["severity"] == "warning" and ": not checked, a limit of the program: "
               in f["message"] for f in out["findings"])
    assert limited <= {"PyBullet (URDF)", "Pinocchio (URDF)"} and "MuJoCo" not in proc.stdout.replace(REAL, "")
    assert proc.returncode == 0, proc.stderr  # the programs' own limits are warnings, not the robot's errors


@pytest.mark.slow
def test_report_of_a_600_deep_chain_has_no_pictures(deep600):
    proc = run_cli("report", "out/deep", cwd=deep600)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("wrote out/deep/report/report.html (")
    page = (deep600 / "out" / "deep" / "report" / "report.html").read_text(encoding="utf-8")
    assert f"No pictures: {REAL} (the pictures are drawn in MuJoCo, from the MJCF)".replace("'", "&#39;") in page
