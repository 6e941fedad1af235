"""``mjcf_extras``: MJCF section elements copied verbatim into the MJCF (their children appended to
the generated sections), every frame link a site of its name so that they can name it, checked
by MuJoCo at build time, listed as a limit of the URDF and model.sdf."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from conftest import write_recipe
from robotkit import mj
from robotkit.emit.mjcf import render_mjcf
from robotkit.errors import RobotkitError
from robotkit.model.load import load_robots
from robotkit.model.resolve import finalize
from robotkit.pipeline.runner import build

LOOP = """
robot: loop
links:
  base:
    visual: {box: {size: [0.2, 0.2, 0.1]}}
    inertial: {mass: 1}
  tip: {}
  arm:
    visual: {cylinder: {radius: 0.02, length: 0.3}}
    inertial: {mass: 0.2}
  arm_tip: {}
joints:
  tip_joint: {type: fixed, parent: base, child: tip, origin: {xyz: [0.1, 0, 0.05]}}
  hinge:
    type: revolute
    parent: base
    child: arm
    axis: [0, 1, 0]
    limit: {lower: -1, upper: 1, effort: 5, velocity: 2}
  arm_tip_joint: {type: fixed, parent: arm, child: arm_tip, origin: {xyz: [0, 0, 0.15]}}
actuators:
  hinge: {interface: position, p: 10}
"""

EXTRAS = """
mjcf_extras:
  - |
    <tendon>
      <fixed name="t"><joint joint="hinge" coef="0.5"/></fixed>
      <spatial name="s"><site site="tip"/><site site="arm_tip"/></spatial>
    </tendon>
  - <actuator><motor name="tm" tendon="t" gear="2"/></actuator>
  - <sensor><framepos name="tp" objtype="site" objname="tip"/></sensor>
  - <contact><pair geom1="base_collision_0" geom2="arm_collision_0"/></contact>
  - <size memory="1M"/>
"""


def _robot(tmp_path, text: str):
    return finalize(load_robots([write_recipe(tmp_path, text)])[0][1], {}, {})


def test_frame_links_are_sites_of_their_name(tmp_path):
    """Each frame link (no mass, no shape, fixed) is also a site of its name, at its pose, in the
    body that carries it (its own body stays: tf's frame, the SDF's <frame>)."""
    xml = render_mjcf(_robot(tmp_path, LOOP))
    assert ('      <site name="tip" pos="0.1 0 0.05" quat="1 0 0 0" group="4"/>\n'
            '      <geom name="base_visual_0"') in xml
    assert '        <site name="arm_tip" pos="0 0 0.15" quat="1 0 0 0" group="4"/>\n' in xml
    assert '      <body name="tip" pos="0.1 0 0.05" quat="1 0 0 0">\n      </body>\n' in xml
    assert '<site name="base"' not in xml and '<site name="arm"' not in xml  # links with mass are not frames


def test_a_frame_of_the_world_is_a_site_of_the_worldbody(tmp_path):
    robot = _robot(tmp_path, """
robot: fixed
links:
  world: {}
  mark: {}
  base: {visual: {box: {size: [0.1, 0.1, 0.1]}}, inertial: {mass: 1}}
joints:
  mark_joint: {type: fixed, parent: world, child: mark, origin: {xyz: [1, 2, 3], rpy: [0, 0, 1.5707963267948966]}}
  base_joint: {type: fixed, parent: world, child: base}
""")
    xml = render_mjcf(robot)
    assert '  <worldbody>\n    <site name="mark" pos="1 2 3" quat="0.707106781186548 0 0 0.707106781186547" group="4"/>\n' in xml


def test_extras_join_the_generated_sections(tmp_path):
    xml = render_mjcf(_robot(tmp_path, LOOP + EXTRAS + "self_collide: true\n"))
    assert xml.count("<actuator>") == 1 and xml.count("<contact>") == 1
    assert ('    <exclude body1="base" body2="arm"/>\n'
            '    <exclude body1="arm" body2="arm_tip"/>\n'
            '    <pair geom1="base_collision_0" geom2="arm_collision_0"/>\n'
            "  </contact>\n"
            "  <tendon>\n"
            '    <fixed name="t">\n'
            '      <joint joint="hinge" coef="0.5"/>\n'
            "    </fixed>\n"
            '    <spatial name="s">\n'
            '      <site site="tip"/>\n'
            '      <site site="arm_tip"/>\n'
            "    </spatial>\n"
            "  </tendon>\n"
            "  <actuator>\n"
            '    <position name="hinge_position" joint="hinge" kp="10" ctrlrange="-1 1" forcerange="-5 5"/>\n'
            '    <motor name="tm" tendon="t" gear="2"/>\n'
            "  </actuator>\n"
            "  <sensor>\n"
            '    <framepos name="tp" objtype="site" objname="tip"/>\n'
            "  </sensor>\n") in xml
    assert '  <option integrator="implicitfast"/>\n  <size memory="1M"/>\n' in xml


def test_extras_behave_in_mujoco(tmp_path):
    mujoco = mj.load()
    m = mujoco.MjModel.from_xml_string(render_mjcf(_robot(tmp_path, LOOP + EXTRAS)))
    assert (m.ntendon, m.nu, m.nsensor, m.npair) == (2, 2, 1, 1)
    d = mujoco.MjData(m)
    for q in (0.0, 0.5):
        d.qpos[0] = q
        mujoco.mj_forward(m, d)
        # tip (0.1, 0, 0.05) on the base, arm_tip 0.15 up the arm, which turns about y
        arm_tip = np.array([0.15 * math.sin(q), 0, 0.15 * math.cos(q)])
        assert d.ten_length[0] == pytest.approx(0.5 * q)
        assert d.ten_length[1] == pytest.approx(np.linalg.norm(arm_tip - [0.1, 0, 0.05]))
        assert d.sensordata[:3] == pytest.approx(d.site_xpos[m.site("tip").id])


def test_extras_must_be_mjcf_sections(tmp_path):
    recipe = write_recipe(tmp_path, LOOP + """
mjcf_extras:
  - <tendon><fixed name="t"></tendon>
  - <worldbody/>
""")
    with pytest.raises(RobotkitError) as err:
        build([recipe], tmp_path / "out")
    assert err.value.lines() == [
        f"{recipe}:24: mjcf_extras[0]: not well-formed XML: mismatched tag: line 1, column 26",
        f"{recipe}:25: mjcf_extras[1]: <worldbody> is not an MJCF section the build takes verbatim; one of <size>, "
        "<visual>, <statistic>, <default>, <extension>, <custom>, <asset>, <deformable>, <contact>, <equality>, "
        "<tendon>, <actuator>, <sensor>, <keyframe>"]


def test_extras_mujoco_refuses_fail_the_mjcf(tmp_path):
    recipe = write_recipe(tmp_path, LOOP + """
outputs: [mjcf]
mjcf_extras:
  - <tendon><spatial name="s"><site site="tip"/><site site="elbow"/></spatial></tendon>
""")
    with pytest.raises(RobotkitError) as err:
        build([recipe], tmp_path / "out")
    assert "mjcf_extras: MuJoCo refuses the MJCF with these elements: site 'elbow' not found in wrap 1 " \
           "Element name 'elbow', id 1, line" in "\n".join(err.value.lines())
    assert not (tmp_path / "out" / "loop" / "mjcf" / "loop.xml").exists()


@pytest.mark.slow
def test_extras_are_a_limit_of_urdf_and_sdf(tmp_path):
    recipe = write_recipe(tmp_path, LOOP + EXTRAS)
    build([recipe], tmp_path / "out")
    limits = json.loads((tmp_path / "out" / "loop" / "report.json").read_text())["limits"]
    said = ("mjcf_extras <tendon> (2 elements), <actuator> (1 element), <sensor> (1 element), "
            "<contact> (1 element), <size> are in the MJCF only, not in ")
    assert said + "the URDF" in limits["urdf"] and said + "model.sdf" in limits["sdf"]
    assert not any("mjcf_extras" in x for x in limits["mjcf"])


def test_loops_are_equality_constraints_between_two_sites(tmp_path):
    robot = _robot(tmp_path, LOOP + """
loops:
  close: {link1: arm, origin1: {xyz: [0, 0, 0.15]}, link2: base, origin2: {xyz: [0, 0, 0.15]}}
  hold: {type: weld, link1: arm, link2: base, origin2: {rpy: [0, 0.5, 0]}}
""")
    xml = render_mjcf(robot)
    assert '        <site name="close_1" pos="0 0 0.15" quat="1 0 0 0" group="4"/>\n' in xml
    assert '      <site name="close_2" pos="0 0 0.15" quat="1 0 0 0" group="4"/>\n' in xml
    assert ("  <equality>\n"
            '    <connect name="close" site1="close_1" site2="close_2"/>\n'
            '    <weld name="hold" site1="hold_1" site2="hold_2"/>\n'
            "  </equality>\n") in xml
    mujoco = mj.load()
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)  # the arm upright: the connect's two points coincide
    rows = [i for i in range(d.nefc) if d.efc_type[i] == mujoco.mjtConstraint.mjCNSTR_EQUALITY]
    assert np.abs(d.efc_pos[rows[:3]]).max() < 1e-12
    assert np.abs(d.efc_pos[rows[3:]]).max() == pytest.approx(math.sin(0.25))  # the weld's frames 0.5 rad apart


def test_loop_softness_is_mujocos_solref_solimp_and_torquescale(tmp_path):
    robot = _robot(tmp_path, LOOP + """
loops:
  close: {link1: arm, link2: base, solref: [0.005, 1], solimp: [0.95, 0.99, 0.001]}
  hold: {type: weld, link1: arm, link2: base, torquescale: 2.5}
""")
    xml = render_mjcf(robot)
    assert ('    <connect name="close" site1="close_1" site2="close_2" solref="0.005 1" solimp="0.95 0.99 0.001"/>\n'
            '    <weld name="hold" site1="hold_1" site2="hold_2" torquescale="2.5"/>\n') in xml
    m = mj.load().MjModel.from_xml_string(xml)
    np.testing.assert_array_equal(m.eq_solref, [[0.005, 1], [0.02, 1]])
    np.testing.assert_array_equal(m.eq_solimp[0], [0.95, 0.99, 0.001, 0.5, 2])  # the rest MuJoCo's defaults
    assert m.eq_data[1][10] == 2.5


def test_torquescale_is_a_welds(tmp_path):
    recipe = write_recipe(tmp_path, LOOP + "loops:\n  close: {link1: arm, link2: base, torquescale: 2}\n")
    with pytest.raises(RobotkitError) as err:
        build([recipe], tmp_path / "out")
    assert err.value.lines() == [
        f"{recipe}:23: loops.close: torquescale is a weld's: a connect holds points, not frames"]


def test_loop_names_links_of_the_robot(tmp_path):
    recipe = write_recipe(tmp_path, LOOP + """
loops:
  close: {link1: arm, link2: bse}
  self: {link1: arm, link2: arm}
""")
    with pytest.raises(RobotkitError) as err:
        build([recipe], tmp_path / "out")
    assert err.value.lines() == [
        f"{recipe}:24: loops.close.link2: no link named 'bse' (did you mean 'base'?)",
        f"{recipe}:25: loops.self.link2: a loop cannot close link 'arm' on itself"]


@pytest.mark.slow
def test_loops_are_a_limit_of_urdf_and_sdf(tmp_path):
    recipe = write_recipe(tmp_path, LOOP + "loops:\n  close: {link1: arm, link2: tip}\n")
    build([recipe], tmp_path / "out")
    limits = json.loads((tmp_path / "out" / "loop" / "report.json").read_text())["limits"]
    said = "loop 'close': {} is a tree and leaves it open (the MJCF closes it with an equality constraint)"
    assert said.format("the URDF") in limits["urdf"] and said.format("model.sdf") in limits["sdf"]
