"""What a PATH given to a command is (robotkit.commands.inputs): each kind of file, build
folders holding one or several robots, and bad input with its exact message."""

from __future__ import annotations

import pytest

from robotkit.commands.inputs import (
    NOT_A_BUILD, Input, classify, enclosing_build, package_paths, robot_dirs,
)
from robotkit.emit.layout import robot_layout
from robotkit.errors import RobotkitError


def fake_build(folder, name: str):
    """A robot's build folder as far as telling one apart goes: model.sdf and its MJCF."""
    layout = robot_layout(folder / name)
    for f in (layout.sdf, layout.mjcf, layout.urdf):
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text("<x/>", encoding="utf-8")
    return layout


def problem(path, *args) -> tuple[str, str, int]:
    """(message, file, exit status) of the one problem ``classify`` raises."""
    with pytest.raises(RobotkitError) as info:
        classify(path, *args)
    (p,) = info.value.problems
    return p.message, p.file, info.value.exit_status


@pytest.mark.parametrize("name, kind", [
    ("robot.yaml", "recipe"), ("robot.yml", "recipe"), ("ROBOT.YAML", "recipe"), ("arm.urdf", "urdf"),
    ("arm.urdf.xacro", "xacro"), ("arm.xacro", "xacro"), ("model.sdf", "sdf"), ("empty.world", "sdf"),
    ("scene.xml", "mjcf"),
])
def test_each_kind_of_file(tmp_path, name, kind):
    f = tmp_path / name
    f.write_text("", encoding="utf-8")
    assert classify(f) == Input(kind, f)
    assert classify(str(f)).path == f  # a str is a path too


def test_a_robots_build_folder_is_one_robot(tmp_path):
    rover = fake_build(tmp_path, "rover")
    what = classify(rover.root)
    assert what == Input("build", rover.root, (rover,))
    assert what.one_robot() == rover


def test_an_output_folder_holds_its_robots_sorted(tmp_path):
    b, a = fake_build(tmp_path, "b_arm"), fake_build(tmp_path, "a_rover")
    (tmp_path / "notes").mkdir()  # not a robot: left out
    (tmp_path / "half").mkdir()
    (tmp_path / "half" / "model.sdf").write_text("<x/>", encoding="utf-8")  # no mjcf/: not a build
    (tmp_path / "file.txt").write_text("", encoding="utf-8")
    what = classify(tmp_path)
    assert what == Input("build", tmp_path, (a, b))
    assert robot_dirs(tmp_path) == [a, b]
    with pytest.raises(RobotkitError) as info:
        what.one_robot()
    assert [(p.message, p.file) for p in info.value.problems] == [
        ("holds 2 robots (a_rover, b_arm); name one folder", str(tmp_path))]


def test_a_folder_that_is_not_a_build(tmp_path):
    (tmp_path / "meshes").mkdir()
    assert robot_dirs(tmp_path) == []
    assert problem(tmp_path) == (NOT_A_BUILD, str(tmp_path), 2)
    assert NOT_A_BUILD == "not a build folder (no <robot>/model.sdf below it)"


def test_a_folder_where_a_command_takes_no_build(tmp_path):
    assert problem(tmp_path, ("recipe", "urdf"), "a recipe .yaml or a .urdf") == (
        "no such file or folder", str(tmp_path), 2)


def test_a_missing_path(tmp_path):
    missing = tmp_path / "nowhere.urdf"
    assert problem(missing) == ("no such file or folder", str(missing), 2)
    assert problem(str(missing)) == ("no such file or folder", str(missing), 2)
    assert robot_dirs(missing) == []


def test_an_unknown_suffix(tmp_path):
    f = tmp_path / "robot.json"
    f.write_text("{}", encoding="utf-8")
    assert problem(f) == ("unknown kind of file (expected a recipe .yaml, .urdf, .xacro, .sdf or MJCF .xml)",
                          str(f), 2)


def test_a_kind_the_command_does_not_take(tmp_path):
    f = tmp_path / "arm.xacro"
    f.write_text("", encoding="utf-8")
    assert problem(f, ("recipe", "build", "urdf"), "a recipe .yaml, a build folder or a .urdf") == (
        "unknown kind of file (expected a recipe .yaml, a build folder or a .urdf)", str(f), 2)


def test_the_message_names_the_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "robot.txt").write_text("", encoding="utf-8")
    with pytest.raises(RobotkitError) as info:
        classify("robot.txt")
    assert info.value.lines() == [
        "robot.txt: unknown kind of file (expected a recipe .yaml, .urdf, .xacro, .sdf or MJCF .xml)"]


def test_the_build_a_model_sdf_belongs_to(tmp_path):
    rover = fake_build(tmp_path, "rover")
    assert enclosing_build(rover.sdf) == rover
    loose = tmp_path / "loose.sdf"
    loose.write_text("<sdf/>", encoding="utf-8")
    assert enclosing_build(loose) is None


def test_package_paths(capsys):
    assert package_paths([]) == {}
    assert package_paths(["arm=/tmp/arm", "gripper=rel/dir=x"]) == {"arm": "/tmp/arm", "gripper": "rel/dir=x"}
    assert package_paths(["arm=/tmp/arm", "nopath"]) is None
    assert capsys.readouterr().err == "robotkit: error: --package-path takes PKG=DIR (got 'nopath')\n"
    for bad in ("=dir", "pkg="):
        assert package_paths([bad]) is None
        assert capsys.readouterr().err == f"robotkit: error: --package-path takes PKG=DIR (got '{bad}')\n"
