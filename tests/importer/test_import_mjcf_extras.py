"""``robotkit import model.xml``: what the recipe has no key for kept verbatim in ``mjcf_extras``
(tests/data/mjcf/extras.xml, made for it: a spatial tendon through sites and a pulley, a fixed
tendon, tendon, site and filtered actuators, a loop closed at a joint's ``ref``, a weld, joint and
tendon couplings, sensors, custom data), in the rebuilt model's names, word for word; on the
ledger for URDF and SDF; compared with the original in MuJoCo (and a rebuild that differs
caught); the shared Menagerie models with loops and tendons in the slow tier."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from robotkit import mj
from robotkit.commands.import_ import build_mjcf
from robotkit.importer import import_mjcf
from robotkit.importer.mjcf import convert
from robotkit.importer.mjcf.verify import verify
from tests.conftest import ASSETS

EXTRAS = Path(__file__).resolve().parents[1] / "data" / "mjcf" / "extras.xml"
KEPT = "(kept verbatim in mjcf_extras for the MJCF)"


@pytest.fixture(scope="module")
def converted(tmp_path_factory):
    return convert(EXTRAS, tmp_path_factory.mktemp("extras") / "extras.yaml")


def test_tendons_actuators_equalities_sensors_custom_word_for_word(converted):
    recipe = converted[0]
    assert recipe["mjcf_extras"] == [
        '<tendon>\n'
        '  <spatial name="cable" range="0.1 0.5" stiffness="10" damping="0.5" springlength="0.24682271232582692 '
        '0.24682271232582692">\n'
        '    <site site="anchor"/>\n    <site site="crank_tip"/>\n    <pulley divisor="2"/>\n'
        '    <site site="crank_tip"/>\n    <site site="lever_tip"/>\n'
        '  </spatial>\n'
        '  <fixed name="couple">\n    <joint joint="crank" coef="0.5"/>\n    <joint joint="slide" coef="-1"/>\n'
        '  </fixed>\n'
        '</tendon>',
        '<actuator>\n'
        '  <general name="pull" tendon="couple" dyntype="none" gaintype="fixed" biastype="affine" dynprm="1" '
        'gainprm="2" biasprm="0 -2 -0.1" gear="1" ctrllimited="true" ctrlrange="0 1" forcelimited="false" '
        'actlimited="false"/>\n'
        '  <general name="push" site="crank_tip" dyntype="none" gaintype="fixed" biastype="none" dynprm="1" '
        'gainprm="1" biasprm="0" gear="0 0 1" ctrllimited="true" ctrlrange="-1 1" forcelimited="false" '
        'actlimited="false"/>\n'
        '  <general name="filtered" joint="lever" dyntype="filter" gaintype="fixed" biastype="none" dynprm="0.05" '
        'gainprm="3" biasprm="0" gear="1" ctrllimited="true" ctrlrange="-1 1" forcelimited="false" '
        'actlimited="false"/>\n'
        '</actuator>',
        # the loop (inactive: not the recipe's loops): MuJoCo found its point on the
        # lever with the crank at its ref (20 degrees), where the rebuild's zero configuration is not:
        # two frame links at its two points, as sites;
        # the couplings: from the rebuild's zero configuration (the lever's ref 10 degrees)
        '<equality>\n'
        '  <connect name="loop" site1="loop_anchor1" site2="loop_anchor2" active="false" solref="0.01 1"/>\n'
        '  <joint name="cubic" joint1="slide" joint2="lever" polycoef="-0.0017506458289285372 0.010091385225936013 '
        '-0.0005235987755982989 0.001 0"/>\n'
        '  <weld name="hold" body1="lever" body2="base" anchor="0 0 0" relpose="-0.2 0 -0.15000000000000002 1 0 0 0" '
        'torquescale="2" active="false"/>\n'
        '  <tendon name="tendons" tendon1="couple" polycoef="0.17453292519943295 0 0 0 0"/>\n'
        '</equality>',
        '<sensor>\n'
        '  <tendonpos name="cable_length" tendon="cable"/>\n'
        '  <actuatorfrc name="servo_force" actuator="lever_position"/>\n'
        '  <subtreecom name="com" body="base"/>\n'
        '</sensor>',
        '<custom>\n  <numeric name="gains" data="1 2 3"/>\n  <text name="note" data="hello"/>\n</custom>',
    ]


def test_loop_anchors_are_frame_links(converted):
    recipe, tree = converted[0], converted[3]
    assert recipe["links"]["loop_anchor1"] == {} and recipe["links"]["loop_anchor2"] == {}
    assert recipe["joints"]["loop_anchor1_fixed"] == {"type": "fixed", "parent": "rod", "child": "loop_anchor1",
                                                      "origin": {"xyz": [0, 0, 0.2]}}
    assert recipe["joints"]["loop_anchor2_fixed"]["parent"] == "lever"
    assert tree.notes["loop_anchor1_fixed"] == ("an anchor of MJCF connect constraint 'loop' (a site of the rebuilt "
                                                "MJCF, which mjcf_extras constrains)")


def test_ledger_word_for_word(converted):
    lines = [line for line in converted[1].lines() if ": site '" not in line and "option" not in line]
    assert lines == [
        "extras.xml:55: equality connect 'pin': urdf, sdf: the recipe's loop 'pin': URDF and SDF are trees, which "
        "leave it open",
        "extras.xml:56: equality weld 'glue': urdf, sdf: the recipe's loop 'glue': URDF and SDF are trees, which "
        "leave it open",
        f"extras.xml:41: tendon 'cable': urdf, sdf: dropped: the recipe has no tendons {KEPT}",
        f"extras.xml:48: tendon 'couple': urdf, sdf: dropped: the recipe has no tendons {KEPT}",
        f"extras.xml:62: actuator 'pull': urdf, sdf: dropped: a tendon transmission (the recipe's actuators drive "
        f"joints) {KEPT}",
        f"extras.xml:63: actuator 'push': urdf, sdf: dropped: a site transmission (the recipe's actuators drive "
        f"joints) {KEPT}",
        "extras.xml:65: actuator 'filtered': urdf, sdf: dropped: a gain, bias or dynamics other than a position or "
        f"velocity servo or a motor {KEPT}",
        f"extras.xml:54: equality connect 'loop': urdf, sdf: dropped: the recipe has no loop closures or couplings of "
        f"this kind {KEPT}",
        f"extras.xml:57: equality joint 'cubic': urdf, sdf: dropped: the recipe has no loop closures or couplings of "
        f"this kind {KEPT}",
        f"extras.xml:58: equality weld 'hold': urdf, sdf: dropped: the recipe has no loop closures or couplings of "
        f"this kind {KEPT}",
        f"extras.xml:59: equality tendon 'tendons': urdf, sdf: dropped: the recipe has no loop closures or couplings "
        f"of this kind {KEPT}",
        f"extras.xml:68: sensor 'cable_length': urdf, sdf: dropped: the recipe has no tendonpos sensors {KEPT}",
        "extras.xml:69: sensor 'tip_pos': all: dropped: it reads the axes of body 'base''s inertial frame, which "
        "MuJoCo chooses anew from the rebuilt inertia tensor",
        f"extras.xml:70: sensor 'servo_force': urdf, sdf: dropped: the recipe has no actuatorfrc sensors {KEPT}",
        f"extras.xml:71: sensor 'com': urdf, sdf: dropped: the recipe has no subtreecom sensors {KEPT}",
        "extras.xml:72: sensor 'touch': all: dropped: it reads the contacts of site 'lever_tip''s body, and the "
        "rebuild holds the site on a frame link of its own (a body without geoms)",
        "extras.xml:73: sensor 'time': all: dropped: the recipe has no clock sensors",
        f"extras.xml:76: custom numeric 'gains': urdf, sdf: dropped: the recipe has no custom numerics {KEPT}",
        f"extras.xml:77: custom text 'note': urdf, sdf: dropped: the recipe has no custom texts {KEPT}",
    ]


def test_active_loops_are_the_recipes_loops_softness_and_all(converted):
    """Each end in its link's frame: the pendulum's hinge off its body's origin moves its link frame;
    a softness other than MuJoCo's default is the loop's own (solimp: MuJoCo's default here)."""
    assert converted[0]["loops"] == {
        "pin": {"link1": "pend", "origin1": {"xyz": [0.0, 0.0, -0.12000000000000001]}, "link2": "base",
                "origin2": {"xyz": [-0.1, 0.0, 0.10000000000000003]}},
        "glue": {"type": "weld", "link1": "tray", "origin1": {"xyz": [0.0, -0.1, -0.1]}, "link2": "base",
                 "solref": [0.01, 1.0], "torquescale": 3.0}}


@pytest.fixture(scope="module")
def rebuilt(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rebuilt")

    def build(recipe, out):
        built = build_mjcf(recipe, out)
        shutil.copytree(built.parent.parent, folder / "copy")
        return built

    return import_mjcf(EXTRAS, folder / "extras.yaml", build=build), folder


def test_rebuild_with_its_extras_agrees_with_the_original(rebuilt):
    result, folder = rebuilt
    assert result.verdict.ok, result.verdict.lines()
    assert result.verdict.rollouts == 1  # the tendons, actuators and constraints acting in both
    assert {k for k, v in result.verdict.worst.items() if v[1]} >= {"tendon", "sensor", "equality"}
    m = mj.load().MjModel.from_xml_path(str(folder / "copy" / "mjcf" / "extras.xml"))
    assert (m.ntendon, m.neq, m.nu, m.nsensor, m.nnumeric, m.ntext) == (2, 6, 4, 3, 1, 1)  # the touch dropped
    text = (folder / "copy" / "mjcf" / "extras.xml").read_text()
    assert '<connect name="pin" site1="pin_1" site2="pin_2"/>' in text
    assert '<weld name="glue" site1="glue_1" site2="glue_2" torquescale="3" solref="0.01 1"/>' in text


def _mutated(folder: Path, tmp_path: Path, old: str, new: str) -> Path:
    copy = tmp_path / "copy"
    shutil.copytree(folder / "copy", copy)
    mjcf = copy / "mjcf" / "extras.xml"
    text = mjcf.read_text()
    assert old in text
    mjcf.write_text(text.replace(old, new))
    return mjcf


@pytest.mark.parametrize("old, new, failure", [
    ('<joint joint="crank" coef="0.5"/>', '<joint joint="crank" coef="0.6"/>',
     "tendon 'couple' length at the zero configuration: tendon off by 3.49e-02 (tolerance 1e-09)"),
    ('site2="loop_anchor2"', 'site2="crank_tip"', "equality 'loop' anchors at the zero configuration: pose off by "),
    ('<site name="pin_2" pos="-0.1 0 0.1', '<site name="pin_2" pos="-0.1 0 0.11',
     "equality 'pin' anchors at the zero configuration: pose off by 1.00e-02 (tolerance 1e-09)"),
    ('polycoef="0.17453292519943295 0 0 0 0"', 'polycoef="0.17 0 0 0 0"',
     "equality 'tendons' coupling at the zero configuration: equality off by 4.53e-03 (tolerance 1e-09)"),
    ('gainprm="3"', 'gainprm="4"', "actuator 'filtered' gains, bias, dynamics, gear and ranges: actuator off by "),
    ('torquescale="3" solref="0.01 1"', 'torquescale="3" solref="0.02 1"',
     "equality 'glue' softness: equality off by 3.33e-03 (tolerance 1e-09)"),
    ('torquescale="3" solref="0.01 1"', 'torquescale="2" solref="0.01 1"',
     "equality 'glue' softness: equality off by 3.33e-01 (tolerance 1e-09)"),
    ('<subtreecom name="com" body="base"/>', '<subtreecom name="com" body="lever"/>',
     "sensor 'com' at the zero configuration: sensor off by "),
])
def test_verification_catches_extras_that_differ(rebuilt, converted, tmp_path, old, new, failure):
    _, folder = rebuilt
    verdict = verify(converted[2], converted[3], _mutated(folder, tmp_path, old, new))
    assert any(f.startswith(failure) for f in verdict.failures), verdict.failures[:5]


MENAGERIE = ASSETS / "menagerie"


@pytest.mark.slow
@pytest.mark.parametrize("model, kept", [
    ("agility_cassie/cassie.xml", (0, 4, 8)), ("robotiq_2f85/2f85.xml", (1, 3, 0)),
    ("umi_gripper/umi_gripper.xml", (1, 0, 0)), ("ufactory_xarm7/hand.xml", (1, 3, 0)),
    ("skydio_x2/x2.xml", (0, 0, 1)),
])
def test_shared_loops_and_tendons_reach_the_rebuilt_mjcf(model, kept, tmp_path):
    """(tendons, equality constraints, sensors kept verbatim): all the original's tendons, constraints
    and actuators reach the rebuilt MJCF, and its sensors but the IMU pairs (the recipe's imu) and
    Cassie's on motors whose gear the recipe moves into their control."""
    if not (MENAGERIE / model).is_file():
        pytest.skip("the shared Menagerie set is not here")
    folder = tmp_path / "copy"

    def build(recipe, out):
        built = build_mjcf(recipe, out)
        shutil.copytree(built.parent.parent, folder)
        return built

    result = import_mjcf(MENAGERIE / model, tmp_path / "r.yaml", build=build)
    assert result.verdict.ok, result.verdict.lines()
    mujoco = mj.load()
    original = mujoco.MjModel.from_xml_path(str(MENAGERIE / model))
    rebuilt = mujoco.MjModel.from_xml_path(str(next((folder / "mjcf").glob("*.xml"))))
    assert (rebuilt.ntendon, rebuilt.neq) == (original.ntendon, original.neq) == kept[:2]
    assert rebuilt.nu == original.nu
    assert sum("sensor" in line and KEPT in line for line in result.ledger) == kept[2]
