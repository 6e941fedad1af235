"""A robot a consumer would refuse (issue 31: two massless links welded at the root, which
libsdformat's URDF conversion empties): the build says why, truly, exits 1, and publishes no file
that names one it did not write: the refused URDF and SDF and everything naming them (the ROS
package, its launch files and RViz config, model.config, the picture report) are left out and listed."""

from __future__ import annotations

import re
from pathlib import Path

from conftest import run_cli, write_recipe

RECIPE = """
    robot: m
    ros: ros1
    links:
      a: {}
      b: {}
      c: {visual: {box: {size: [0.1, 0.1, 0.1]}}, inertial: {mass: 1}}
    joints:
      weld: {type: fixed, parent: a, child: b}
      turn:
        type: revolute
        parent: b
        child: c
        axis: [0, 0, 1]
        limit: {lower: -1, upper: 1, effort: 5, velocity: 2}
"""


def files(folder: Path) -> set[str]:
    return {p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()}


def dangling(folder: Path, names: set[str]) -> list[str]:
    """(file: path) for each of ``names`` (paths below the robot folder) that a file of ``folder``
    names, by its path or its file name, and that ``folder`` does not have."""
    have = files(folder)
    out = []
    for rel in sorted(have - {"report.json"}):  # the build's summary: consumers' names, e.g. "Gazebo (model.sdf)"
        try:
            text = (folder / rel).read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue
        for name in sorted(names - have):
            if re.search(r"(^|[\s\"'/>(=])" + re.escape(Path(name).name) + r"($|[\s\"'<)])", text) \
                    or name in text:
                out.append(f"{rel}: {name}")
    return out


def test_a_refused_robot_publishes_no_file_naming_a_missing_one(tmp_path):
    weighed = "{inertial: {mass: 1, inertia: {ixx: 0.01, iyy: 0.01, izz: 0.01}}}"
    good = write_recipe(tmp_path, RECIPE.replace("a: {}", f"a: {weighed}").replace("b: {}", f"b: {weighed}"), "good.yaml")
    assert run_cli("build", good, "--out", tmp_path / "good", cwd=tmp_path).returncode == 0
    every = files(tmp_path / "good" / "m")
    assert {"urdf/m.urdf", "launch/display.launch", "rviz/m.rviz", "CMakeLists.txt", "package.xml"} <= every
    assert dangling(tmp_path / "good" / "m", every) == []
    (tmp_path / "good" / "m" / "urdf" / "m.urdf").unlink()  # the check can fail: what it would have said
    assert {"launch/display.launch: urdf/m.urdf", "launch/gazebo.launch: urdf/m.urdf"} <= set(
        dangling(tmp_path / "good" / "m", every))

    recipe = write_recipe(tmp_path, RECIPE, "m.yaml")
    proc = run_cli("build", recipe, "--out", tmp_path / "out", cwd=tmp_path)
    assert proc.returncode == 1
    left = ["urdf/m.urdf", "urdf/m.urdf.xacro", "model.sdf", "srdf/m.srdf", "model.config", "package.xml",
            "CMakeLists.txt", "env-hooks/50.m.sh.in", "launch/display.launch", "launch/gazebo.launch", "rviz/m.rviz",
            "report/report.html"]
    assert proc.stderr.splitlines() == [
        "m.yaml:4: links.a: link 'a' is the root and has no mass, nor the links welded to it ('b'): Gazebo's URDF "
        "conversion drops it and everything below it (an empty model); name the root 'world' to fix the robot to "
        "the world, or give links.a an inertial",
        "m.yaml: m: left out (refused by a consumer, or naming a file that is): " + ", ".join(f"m/{f}" for f in left)]
    robot = tmp_path / "out" / "m"
    assert files(robot) == {"mjcf/m.xml", "mjcf/scene.xml", "report.json"}
    assert dangling(robot, every) == []
    assert not set(left) & files(robot)
