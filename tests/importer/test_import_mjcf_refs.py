"""Joint refs and forces that vanish: an MJCF joint equality couples the joints' moves from their
refs, and a model whose gravity forces are zero (vertical axes, links balanced on their joints)
verifies without counting rounding noise as a disagreement."""

from __future__ import annotations

import math

import pytest
import yaml

from robotkit.commands.import_ import build_mjcf
from robotkit.importer import import_mjcf

MODEL = """<mujoco model="mref">
  <worldbody>
    <body name="a">
      <geom type="box" size="0.1 0.1 0.1" mass="1"/>
      <joint name="j1" type="hinge" axis="0 0 1"{ref1}/>
      <body name="b" pos="0.3 0 0">
        <geom type="box" size="0.05 0.05 0.05" mass="0.5"/>
        <joint name="j2" type="hinge" axis="0 1 0"{ref2} range="-1 1"/>
      </body>
    </body>
  </worldbody>
  {equality}
  <actuator>
    <position joint="j1" kp="10"/>
  </actuator>
</mujoco>
"""
COUPLED = '<equality><joint joint1="j2" joint2="j1" polycoef="0.1 0.5 0 0 0"/></equality>'


def _imported(tmp_path, **parts):
    source = tmp_path / "m.xml"
    source.write_text(MODEL.format(**{"ref1": "", "ref2": "", "equality": "", **parts}))
    result = import_mjcf(source, tmp_path / "out" / "m.yaml", build=build_mjcf)
    return result, yaml.safe_load((tmp_path / "out" / "m.yaml").read_text())


def test_mimic_offset_takes_in_both_refs(tmp_path):
    # MuJoCo: j2 - ref2 = 0.1 + 0.5 (j1 - ref1), refs in degrees (the compiler's default angle unit)
    result, recipe = _imported(tmp_path, ref1=' ref="0.3"', ref2=' ref="-0.2"', equality=COUPLED)
    mimic = recipe["joints"]["j2"]["mimic"]
    assert mimic == {"joint": "j1", "multiplier": 0.5,
                     "offset": pytest.approx(0.1 + math.radians(-0.2) - 0.5 * math.radians(0.3), abs=1e-15)}
    assert result.verdict.ok, result.verdict.lines()
    assert result.verdict.worst["equality"][0] < 1e-12
    assert result.verdict.worst["rollout"][0] < 1e-9


def test_mimic_without_refs_keeps_the_polynomial(tmp_path):
    result, recipe = _imported(tmp_path, equality=COUPLED)
    assert recipe["joints"]["j2"]["mimic"] == {"joint": "j1", "multiplier": 0.5, "offset": 0.1}
    assert result.verdict.ok, result.verdict.lines()


def test_vanishing_gravity_forces_are_not_disagreements(tmp_path):
    # a vertical axis and a link balanced on its joint: MuJoCo gives 0 or 1e-16 N m on either side
    result, _ = _imported(tmp_path)
    assert result.verdict.ok, result.verdict.lines()
    assert result.verdict.worst["matrix"][0] < 1e-12 and result.verdict.worst["pinocchio"][0] < 1e-12
