"""The MJCF import on what Menagerie models outside the shared set do (issue 30: the reviewers
import models they keep back): each test a small MJCF written here that holds one such feature,
with its known answer (ledger lines word for word)."""

from __future__ import annotations

from robotkit.importer.mjcf import convert

INCLUDED_MAIN = """<mujoco model="two">
  <worldbody>
    <body name="a">
      <geom size="0.1"/>
      <joint name="j" axis="0 0 1" range="-1 1"/>
      <site name="grip" pos="0 0 0.1"/>
    </body>
  </worldbody>
  <include file="parts/acts.xml"/>
</mujoco>
"""
INCLUDED_ACTS = """<mujoco>
  <actuator>
    <position name="grip" joint="j" kp="10" ctrlrange="-0.5 0.5"/>
  </actuator>
  <keyframe>
    <key name="home" qpos="0.2" ctrl="0.1"/>
  </keyframe>
</mujoco>
"""


def test_ledger_names_the_included_file_and_line(tmp_path):
    """ALOHA's actuators and keyframe come from an ``<include>``d file (MuJoCo records their line
    as 0): the ledger names that file and the element's line there, and an actuator named like a
    site of the main file is not placed at the site's line."""
    (tmp_path / "parts").mkdir()
    (tmp_path / "main.xml").write_text(INCLUDED_MAIN)
    (tmp_path / "parts" / "acts.xml").write_text(INCLUDED_ACTS)
    recipe, ledger, src, _ = convert(tmp_path / "main.xml", tmp_path / "out" / "two.yaml")
    assert ledger.lines()[1:] == [
        "parts/acts.xml:3: actuator 'grip': all: ctrlrange [-0.5, 0.5] written as the joint's range "
        "[-0.0174533, 0.0174533]",
        "main.xml:6: site 'grip': mjcf: a frame link (in the rebuilt MJCF a body without mass holding a site of its "
        "name): its sphere of size 0.005 is not drawn",
        "parts/acts.xml:6: keyframe 'home': all: ctrl dropped (the MJCF keyframe's ctrl is the pose's position "
        "targets)",
    ]
    assert src.includes() == [tmp_path / "parts" / "acts.xml"]
