"""Two bases welded to the world (two arms on one table, as Menagerie's ALOHA): every reader keeps
where each base stands, so check compares the same frames in the URDF, model.sdf, the MJCF and the
programs that load them; Pinocchio makes one body of everything welded to the world."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from conftest import write_recipe
from robotkit.check import kinematics as k
from robotkit.check.equivalence import equivalence
from robotkit.emit.layout import robot_layout
from robotkit.pipeline.runner import build

ARM = """
  {side}_base: {{visual: {{box: {{size: [0.1, 0.1, 0.04]}}}}, inertial: {{mass: 1}}}}
  {side}_arm: {{visual: {{cylinder: {{radius: 0.02, length: 0.2}}, origin: {{xyz: [0, 0, 0.1]}}}}, inertial: {{mass: 0.5}}}}"""
JOINTS = """
  {side}_base_fixed: {{type: fixed, parent: world, child: {side}_base, origin: {{xyz: [{x}, 0, 0.02], rpy: [0, 0, {yaw}]}}}}
  {side}_j: {{type: revolute, parent: {side}_base, child: {side}_arm, origin: {{xyz: [0, 0, 0.05]}}, axis: [0, 1, 0],
            limit: {{lower: -1, upper: 1, effort: 10, velocity: 1}}}}"""


@pytest.fixture(scope="module")
def two_bases(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("two_bases")
    recipe = write_recipe(folder, "robot: two_arms\nlinks:\n  world: {}" + ARM.format(side="left")
                          + ARM.format(side="right") + "\njoints:" + JOINTS.format(side="left", x=-0.4, yaw=0)
                          + JOINTS.format(side="right", x=0.4, yaw=3.141592653589793) + "\n")
    build([recipe], folder / "out")
    return folder / "out" / "two_arms"


def _apart(model: k.KModel, q=None) -> np.ndarray:
    T = model.fk(q or {})
    return np.linalg.inv(T["left_base"]) @ T["right_base"]


def test_every_reader_keeps_where_each_base_stands(two_bases):
    layout = robot_layout(two_bases)
    for model in (k.read_urdf(layout.urdf), k.read_sdf(layout.sdf), k.read_mjcf(layout.mjcf)):
        assert model.root() == "left_base"
        np.testing.assert_allclose(_apart(model)[:3, 3], [0.8, 0, 0], atol=1e-12)
        np.testing.assert_allclose(_apart(model)[:3, :3], np.diag([-1.0, -1, 1]), atol=1e-12)


def test_the_formats_agree(two_bases):
    assert all(diffs == [] for diffs in equivalence(two_bases).values()), equivalence(two_bases)


def test_lumped_as_pinocchio_lumps_one_body_of_the_bases(two_bases):
    urdf = k.read_urdf(robot_layout(two_bases).urdf)
    assert {n: m.mass for n, m in k.lump(urdf).links.items()} == {
        "left_base": 1, "left_arm": 0.5, "right_base": 1, "right_arm": 0.5}  # libsdformat keeps both
    lumped = k.lump(urdf, world=True)
    assert {n: m.mass for n, m in lumped.links.items()} == {"left_base": 2, "left_arm": 0.5, "right_arm": 0.5}
    np.testing.assert_allclose(lumped.links["left_base"].com, [0.4, 0, 0], atol=1e-12)  # midway, in left_base
    T = lumped.fk({"right_j": 0.3})
    np.testing.assert_allclose((np.linalg.inv(T["left_base"]) @ T["right_arm"])[:3, 3], [0.8, 0, 0.05], atol=1e-12)


@pytest.mark.consumers
@pytest.mark.slow
def test_every_program_reads_both_bases_where_they_stand(two_bases):
    from robotkit.check.consumers import Build, consumer_findings

    d = two_bases
    build = Build("two_arms", d, d / "urdf" / "two_arms.urdf", d / "model.sdf", d / "mjcf" / "two_arms.xml")
    findings, _ = consumer_findings(build)
    assert [f for f in findings if f.severity == "error"] == []
