"""robotkit import model.sdf / MODEL_FOLDER: SDF read through libsdformat into a recipe, each
conversion stated on the ledger and proved against the rebuilt model.sdf (through libsdformat)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

from robotkit.commands.import_ import build_sdf
from robotkit.importer import import_sdf
from tests.conftest import run_cli

pytestmark = pytest.mark.skipif(shutil.which("ign") is None, reason="needs libsdformat's ign sdf")
MODELS = Path(__file__).resolve().parents[1] / "data" / "gazebo_models"


def _imported(tmp_path: Path, name: str, build=build_sdf):
    result = import_sdf(MODELS / name, tmp_path / f"{name}.yaml", build=build)
    return result, yaml.safe_load(result.recipe_path.read_text())


def _joints(recipe: dict) -> dict:
    """The recipe's joints with its ``defaults: joint:`` applied."""
    base = recipe.get("defaults", {}).get("joint", {})
    return {name: {**base, **j} for name, j in recipe["joints"].items()}


def test_folder_takes_newest_sdf_metadata_and_invalid_inertia_recomputed(tmp_path):
    result, recipe = _imported(tmp_path, "simple_arm")
    assert result.verdict.ok, result.verdict.lines()
    assert recipe["metadata"]["authors"] == [{"name": "John Hsu", "email": "hsu@osrfoundation.org"}]
    assert recipe["metadata"]["description"] == "A simple SCARA arm."
    assert recipe["links"]["arm_base"]["inertial"]["policy"] == "recompute"
    assert any("link 'arm_base' inertial: all: the original's" in line and "recomputed from its collision geometry"
               in line for line in result.ledger)
    assert recipe["base"] == "free"


def test_joint_named_like_a_link_is_renamed(tmp_path):
    result, recipe = _imported(tmp_path, "simple_gripper")
    assert result.verdict.ok, result.verdict.lines()
    assert any(line.endswith("model.sdf:203: joint 'left_finger_tip': all: renamed 'left_finger_tip_joint' (a link "
               "has its name: libsdformat refuses the pair)") for line in result.ledger)
    assert "left_finger_tip_joint" in recipe["joints"] and "left_finger_tip" in recipe["links"]


def test_joint_types_urdf_lacks_are_approximated_or_dropped(tmp_path):
    result, recipe = _imported(tmp_path, "demo_joint_types")
    assert result.verdict.ok, result.verdict.lines()
    joints = _joints(recipe)
    assert [joints[f"ball_demo_{a}"]["axis"] for a in "xyz"] == [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    assert joints["ball_demo_x"]["child"] in recipe["links"] and joints["ball_demo_z"]["child"] == "ball_ball"
    assert joints["revolute_demo"]["type"] == "continuous"  # SDF's +-1e16 limits
    assert joints["prismatic_demo"]["type"] == "prismatic"
    assert "gearbox_demo" not in joints
    text = "\n".join(result.ledger)
    assert "joint 'gearbox_demo' (gearbox): all: dropped" in text
    assert "joint 'ball_demo' (ball): all: approximated: three revolute joints" in text
    assert "joint 'universal_demo' (universal): all: approximated: two revolute joints" in text
    assert "(screw): all: approximated: a revolute joint" in text


def test_file_libsdformat_refuses_is_read_from_its_xml(tmp_path):
    result, recipe = _imported(tmp_path, "ragdoll")
    assert result.verdict.ok, result.verdict.lines()
    assert "libsdformat refuses it" in result.ledger[0] and "read from its own XML" in result.ledger[0]
    assert len(recipe["joints"]) == 23 and {j["type"] for j in _joints(recipe).values()} == {"revolute"}
    assert recipe["base"] == "free"


def test_verification_compares_poses_at_random_configurations(tmp_path):
    result, _ = _imported(tmp_path, "simple_arm")
    assert result.verdict.configurations == 11
    assert "verified through libsdformat against the original at 11 configurations: every quantity agrees" \
        == result.verdict.lines()[0]


def test_sdf_file_through_the_cli(tmp_path):
    proc = run_cli("import", MODELS / "simple_gripper" / "model.sdf", "-o", tmp_path / "g.yaml", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "every quantity agrees" in proc.stdout
    assert (tmp_path / "g.yaml").is_file()


def test_bad_sdf_one_line_exit_2_nothing_written(tmp_path):
    bad = tmp_path / "bad.sdf"
    bad.write_text("<sdf version='1.9'><model name='m'><link name='a'></model></sdf>\n")
    proc = run_cli("import", bad, "-o", tmp_path / "out" / "bad.yaml", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr == "bad.sdf:1: not well-formed XML: mismatched tag: line 1, column 52\n"
    assert not (tmp_path / "out").exists()


def test_folder_without_model_config_exit_2(tmp_path):
    (tmp_path / "empty").mkdir()
    proc = run_cli("import", "empty", "-o", tmp_path / "out" / "x.yaml", cwd=tmp_path)
    assert (proc.returncode, proc.stderr) == (2, "empty: a model folder without model.config\n")
    assert not (tmp_path / "out").exists()
