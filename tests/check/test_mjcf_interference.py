"""Interference in a foreign MJCF: the file's own filter decides which pairs count."""

from __future__ import annotations

import json

from tests.conftest import run_cli

MJCF = """<mujoco model="pendulum">
  <worldbody>
    <body name="base">
      <geom type="box" size="0.1 0.1 0.1"/>
      <body name="arm" pos="0 0 0.3">
        <joint name="hinge" type="hinge" axis="0 1 0" range="-170 170"/>
        <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.02"/>
        <body name="tip" pos="0.4 0 0">
          <joint name="wrist" type="hinge" axis="0 1 0" range="-10 10"/>
          <geom type="sphere" size="0.03"/>
        </body>
      </body>
    </body>
  </worldbody>
  {contact}
  <keyframe>
    <key name="down" qpos="1.5708 0"/>
  </keyframe>
</mujoco>
"""


def check(tmp_path, contact: str = ""):
    path = tmp_path / "pendulum.xml"
    path.write_text(MJCF.format(contact=contact))
    proc = run_cli("check", path, "--format", "json")
    return proc, [f for f in json.loads(proc.stdout)["findings"] if f["check"] == "self-collision"]


def test_a_keyframe_that_folds_the_arm_into_the_base_is_an_error(tmp_path):
    proc, found = check(tmp_path)
    assert proc.returncode == 1
    [error] = [f for f in found if f["severity"] == "error"]
    assert error["subject"] == "pose 'down'"
    # the arm hangs from z 0.3 to z -0.1 inside the base's top at z 0.1: the tip's ball is in the base too
    assert error["message"].startswith("links 'base' and 'tip' interpenetrate by ")


def test_an_exclude_in_the_file_disables_the_pair(tmp_path):
    proc, found = check(tmp_path, '<contact><exclude body1="base" body2="tip"/></contact>')
    assert [f for f in found if f["severity"] == "error"] == [], found
