"""A mimic of a mimic (a telescoping arm): the URDF writes each mimic joint against the joint its
chain starts from, multipliers and offsets composed; the recipe and the MJCF keep the chain."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from conftest import write_recipe
from robotkit.emit.mjcf import render_mjcf
from robotkit.emit.urdf import render_urdf
from robotkit.model.load import load_robots
from robotkit.model.resolve import finalize

SLIDE = "{{type: prismatic, parent: {p}, child: {c}, axis: [1, 0, 0], limit: {{lower: 0, upper: 0.1, effort: 1, velocity: 1}}{m}}}"
RECIPE = f"""
robot: telescope
links:
  base: {{visual: {{box: {{size: [0.1, 0.02, 0.02]}}}}, inertial: {{mass: 1}}}}
  l3: {{visual: {{box: {{size: [0.1, 0.02, 0.02]}}}}, inertial: {{mass: 0.2}}}}
  l2: {{visual: {{box: {{size: [0.1, 0.02, 0.02]}}}}, inertial: {{mass: 0.15}}}}
  l1: {{visual: {{box: {{size: [0.1, 0.02, 0.02]}}}}, inertial: {{mass: 0.1}}}}
joints:
  j3: {SLIDE.format(p="base", c="l3", m="")}
  j2: {SLIDE.format(p="l3", c="l2", m=", mimic: {joint: j3, multiplier: 0.5, offset: 0.02}")}
  j1: {SLIDE.format(p="l2", c="l1", m=", mimic: {joint: j2, multiplier: 2, offset: 0.01}")}
"""


def test_urdf_composes_the_chain_and_the_mjcf_keeps_it(tmp_path):
    robot = finalize(load_robots([write_recipe(tmp_path, RECIPE)])[0][1], {}, {})
    mimics = {j.get("name"): j.find("mimic").attrib for j in ET.fromstring(render_urdf(robot)).iter("joint")
              if j.find("mimic") is not None}
    # j1 = 2 j2 + 0.01 = 2 (0.5 j3 + 0.02) + 0.01 = j3 + 0.05
    assert mimics["j2"] == {"joint": "j3", "multiplier": "0.5", "offset": "0.02"}
    assert mimics["j1"]["joint"] == "j3" and float(mimics["j1"]["multiplier"]) == 1.0
    assert float(mimics["j1"]["offset"]) == pytest.approx(0.05, abs=1e-15)
    mjcf = render_mjcf(robot)
    assert 'joint1="j1" joint2="j2" polycoef="0.01 2 0 0 0"' in mjcf
    assert 'joint1="j2" joint2="j3" polycoef="0.02 0.5 0 0 0"' in mjcf


def test_check_compares_the_chain_with_its_composition(tmp_path):
    from robotkit.check.equivalence import equivalence
    from robotkit.pipeline.runner import build

    build([write_recipe(tmp_path, RECIPE)], tmp_path / "out")
    result = equivalence(tmp_path / "out" / "telescope")
    assert result and all(diffs == [] for diffs in result.values()), result
