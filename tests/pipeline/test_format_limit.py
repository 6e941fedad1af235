"""A format that cannot hold a robot by a limit of its own (issue 33: MuJoCo's XML reader nests at
most 496 bodies, so a 1000-deep chain has no MJCF) is a stated loss, not a failed build: exit 0,
one warning naming the recipe, the format and why, the other formats written, what needs the MJCF
(the scene, the picture report) left out and listed, and the no-op stamp recorded.  A recipe that
lists the format under ``outputs:`` fails as before (exit 1, naming the link and the limit).

The fast tests lower the limit to 3 bodies (the constant MuJoCo's reader is measured at); the slow
one builds a real 500-deep chain, which MuJoCo itself refuses."""

from __future__ import annotations

from pathlib import Path

import pytest

import robotkit.emit.mjcf
import robotkit.model.robot
from conftest import run_cli
from robotkit.errors import RobotkitError
from robotkit.pipeline import stamp
from robotkit.pipeline.runner import build


def chain(n: int, outputs: str = "") -> str:
    lines = ["robot: deep", *([outputs] if outputs else []), "links:"]
    lines += [f"  l{i}: {{visual: {{box: {{size: [0.05, 0.05, 0.1]}}}}, inertial: {{mass: 0.1, inertia: "
              "{ixx: 0.001, iyy: 0.001, izz: 0.001}}}" for i in range(n)]
    lines.append("joints:")
    lines += [f"  j{i}: {{type: revolute, parent: l{i - 1}, child: l{i}, origin: {{xyz: [0, 0, 0.1]}}, "
              "axis: [0, 0, 1], limit: {lower: -1, upper: 1, effort: 1, velocity: 1}}" for i in range(1, n)]
    return "\n".join(lines) + "\n"


def files(folder: Path) -> set[str]:
    return {p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()}


@pytest.fixture
def shallow(tmp_path, monkeypatch):
    """MuJoCo's nesting limit as 3 bodies, in this process."""
    monkeypatch.setenv("ROBOTKIT_CACHE", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(robotkit.emit.mjcf, "MJCF_MAX_DEPTH", 3)
    monkeypatch.setattr(robotkit.model.robot, "MJCF_MAX_DEPTH", 3)
    return tmp_path


LOSS = ("deep.yaml:1: warning: deep: not written, a limit of the format: MJCF: link 'l4' sits 5 links deep and "
        "MuJoCo's XML reader stops at 3 nested bodies (a body per link); left out: deep/mjcf/deep.xml, "
        "deep/mjcf/scene.xml{report} (list it under outputs: to make this an error)")


def test_a_format_beyond_its_limit_is_a_stated_loss_and_the_noop_is_recorded(shallow):
    (shallow / "deep.yaml").write_text(chain(5))
    result = build(["deep.yaml"], "out", report=True)
    assert result.failed == [] and result.left_out == {}
    assert result.warning_lines[0] == LOSS.format(report=", deep/report/report.html")
    assert sum("not written" in w for w in result.warning_lines) == 1
    got = files(shallow / "out" / "deep")
    assert {"urdf/deep.urdf", "model.sdf", "srdf/deep.srdf", "package.xml", "report.json"} <= got
    assert not {"mjcf/deep.xml", "mjcf/scene.xml", "report/report.html"} & got
    # the no-op fast path answers the next build, its warning with it
    opts = stamp.build_options(["deep.yaml"], "out", report=True)
    recorded = stamp.up_to_date("out", opts)
    assert recorded is not None and recorded["warnings"][0] == result.warning_lines[0]


def test_the_loss_without_the_report(shallow):
    (shallow / "deep.yaml").write_text(chain(5))
    result = build(["deep.yaml"], "out", report=False)
    assert result.warning_lines[0] == LOSS.format(report="")
    assert stamp.up_to_date("out", stamp.build_options(["deep.yaml"], "out", report=False)) is not None


def test_a_robot_within_the_limit_loses_nothing(shallow):
    (shallow / "deep.yaml").write_text(chain(3))
    result = build(["deep.yaml"], "out")
    assert not any("not written" in w for w in result.warning_lines)
    assert {"mjcf/deep.xml", "mjcf/scene.xml"} <= files(shallow / "out" / "deep")


def test_a_format_the_recipe_lists_fails_the_build_naming_the_link_and_the_limit(shallow):
    (shallow / "deep.yaml").write_text(chain(5, "outputs: [urdf, mjcf-scene]"))
    with pytest.raises(RobotkitError) as caught:
        build(["deep.yaml"], "out")
    assert caught.value.exit_status == 1
    assert [str(p) for p in caught.value.problems][0] == (
        "deep.yaml:8: links.l4: link 'l4' sits 5 links deep: MuJoCo's XML reader stops at 3 nested bodies, so "
        "it could not load the MJCF (a body per link); make the chain shorter")


def test_outputs_writes_the_formats_listed_and_what_they_need(shallow):
    (shallow / "deep.yaml").write_text(chain(3, "outputs: [mjcf-scene, srdf]"))
    build(["deep.yaml"], "out")
    assert files(shallow / "out" / "deep") == {"mjcf/deep.xml", "mjcf/scene.xml", "urdf/deep.urdf",
                                               "srdf/deep.srdf"}


def test_an_unknown_format_under_outputs_is_bad_input(shallow):
    (shallow / "deep.yaml").write_text(chain(3, "outputs: [urdf, mjfc]"))
    with pytest.raises(RobotkitError) as caught:
        build(["deep.yaml"], "out")
    assert caught.value.exit_status == 2
    assert [str(p) for p in caught.value.problems] == [
        "deep.yaml:2: outputs: 'mjfc' is not an output format (one of: urdf, xacro, sdf, mjcf, mjcf-scene, srdf, "
        "report, model.config, package.xml, CMakeLists.txt, env-hook, display-launch, gazebo-launch, rviz, "
        "controllers, moveit-kinematics, moveit-joint-limits, moveit-controllers, ros2-controllers, moveit-rviz, "
        "moveit-launch)"]
    assert not (shallow / "out" / "deep").exists()


@pytest.mark.slow
def test_a_chain_deeper_than_mujoco_reads_builds_without_its_mjcf(tmp_path):
    """The real limit: 500 links, which MuJoCo's XML reader refuses (measured at 496)."""
    (tmp_path / "deep.yaml").write_text(chain(500))
    proc = run_cli("build", "deep.yaml", "--out", "out", "--no-report", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert [line for line in proc.stderr.splitlines() if "not written" in line] == [
        "deep.yaml:1: warning: deep: not written, a limit of the format: MJCF: link 'l499' sits 500 links deep and "
        "MuJoCo's XML reader stops at 496 nested bodies (a body per link); left out: deep/mjcf/deep.xml, "
        "deep/mjcf/scene.xml (list it under outputs: to make this an error)"]
    assert {"urdf/deep.urdf", "model.sdf"} <= files(tmp_path / "out" / "deep")
    again = run_cli("build", "deep.yaml", "--out", "out", "--no-report", cwd=tmp_path)
    assert again.returncode == 0 and "up to date" in again.stdout
