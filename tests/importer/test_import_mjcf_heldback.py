"""The MJCF import on what Menagerie models outside the shared set do (issue 30: the reviewers
import models they keep back): each test a small MJCF written here that holds one such feature,
with its known answer (ledger lines word for word)."""

from __future__ import annotations

import shutil

import pytest
import yaml

from robotkit.commands.import_ import build_mjcf
from robotkit.errors import RobotkitError
from robotkit.importer import import_mjcf
from robotkit.importer.mjcf import convert

INCLUDED_MAIN = """<mujoco model="two">
  <compiler angle="radian"/>
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
        "parts/acts.xml:3: actuator 'grip': all: ctrlrange [-0.5, 0.5] written as the joint's range [-1, 1]",
        "main.xml:7: site 'grip': mjcf: a frame link (in the rebuilt MJCF a body without mass holding a site of its "
        "name): its sphere of size 0.005 is not drawn",
        "parts/acts.xml:6: keyframe 'home': all: ctrl dropped (the MJCF keyframe's ctrl is the pose's position "
        "targets)",
    ]
    assert src.includes() == [tmp_path / "parts" / "acts.xml"]


GRAVCOMP = """<mujoco model="lift">
  <compiler angle="radian"/>
  <worldbody>
    <body name="mast">
      <geom type="box" size="0.05 0.05 0.5" pos="0 0 0.5" mass="5"/>
      <body name="carriage" pos="0.1 0 0.5" gravcomp="1">
        <joint name="lift" type="slide" axis="0 0 1" range="-0.4 0.4" damping="5"/>
        <geom type="box" size="0.05 0.1 0.05" mass="1"/>
        <body name="arm" pos="0.1 0 0">
          <joint name="swing" axis="0 1 0" range="-1 1" damping="0.1" actuatorgravcomp="true"/>
          <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02" mass="0.5"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="lift" joint="lift" kp="300" ctrlrange="-0.4 0.4"/>
    <position name="swing" joint="swing" kp="20" ctrlrange="-1 1"/>
  </actuator>
</mujoco>
"""


def test_gravity_compensation_is_on_the_ledger_and_out_of_the_rollout(tmp_path):
    """Stretch's lift and arm bodies have ``gravcomp="1"``: the recipe has no gravity
    compensation, so each body (and a joint's ``actuatorgravcomp``) is a ledger line, and the
    verification's rollout takes it out of the original as it does every ledger item (without,
    the carriage sinks in the rebuild and the rollout disagrees)."""
    (tmp_path / "lift.xml").write_text(GRAVCOMP)
    result = import_mjcf(tmp_path / "lift.xml", tmp_path / "out" / "lift.yaml", build=build_mjcf)
    assert result.ledger[1:] == [
        "lift.xml:6: body 'carriage': all: gravity compensation dropped (gravcomp 1): the recipe has no gravity "
        "compensation",
        "lift.xml:10: joint 'swing': all: gravity compensation through its actuators dropped (actuatorgravcomp): the "
        "recipe has no gravity compensation",
    ]
    assert result.verdict.ok, result.verdict.lines()
    assert result.verdict.lines()[0] == ("verified in MuJoCo against the original at 21 configurations and 1 rollout: "
                                         "every quantity agrees")


NARROWED = """<mujoco model="leg">
  <compiler angle="radian"/>
  <worldbody>
    <body name="hip">
      <geom type="box" size="0.05 0.05 0.05" mass="3"/>
      <body name="thigh" pos="0 0 -0.1">
        <joint name="haa" axis="1 0 0" range="-0.72 0.49" damping="1"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.03" mass="2"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="haa" joint="haa" kp="100" ctrlrange="-6.28 6.28" forcerange="-80 80"/>
  </actuator>
</mujoco>
"""


def test_rollout_drives_within_the_ctrlrange_the_rebuild_has(tmp_path):
    """ANYmal C's position actuators take controls of +-6.28 rad on joints of narrower range: the
    recipe writes the joint's range as the control range (on the ledger), so the verification's
    rollout draws its controls within both (drawn within the original's alone, the original
    pushes into its limit with its full 80 N and the rollout disagreed by 0.9 m)."""
    (tmp_path / "leg.xml").write_text(NARROWED)
    result = import_mjcf(tmp_path / "leg.xml", tmp_path / "out" / "leg.yaml", build=build_mjcf)
    assert result.ledger[1:] == [
        "leg.xml:13: actuator 'haa': all: ctrlrange [-6.28, 6.28] written as the joint's range [-0.72, 0.49]"]
    assert result.verdict.ok, result.verdict.lines()


MOCAP = """<mujoco model="reach">
  <worldbody>
    <body name="arm">
      <joint name="j" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02" mass="1"/>
    </body>
    <body name="target" mocap="true" pos="0.3 0 0.2">
      <geom type="sphere" size="0.02" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_mocap_body_is_on_the_ledger(tmp_path):
    """A mocap body (ALOHA's and the arms' teleoperation targets): the recipe's link is fixed
    where the file puts it, and the ledger says the mocap is dropped."""
    (tmp_path / "reach.xml").write_text(MOCAP)
    recipe, ledger, _, _ = convert(tmp_path / "reach.xml", tmp_path / "out" / "reach.yaml")
    assert recipe["joints"]["target_fixed"] == {"type": "fixed", "parent": "world", "child": "target",
                                                "origin": {"xyz": [0.3, 0, 0.2]}}
    assert ledger.lines()[1:] == ["reach.xml:7: body 'target' (mocap): all: mocap dropped: a link fixed where the "
                                  "file puts it (the recipe has no mocap bodies)"]


SITE_LOOP = """<mujoco model="linkage">
  <compiler angle="radian"/>
  <worldbody>
    <site name="anchor" pos="0.4 0 0"/>
    <body name="crank">
      <joint name="c" axis="0 1 0" range="-1 1"/>
      <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.01" mass="0.2"/>
      <body name="rod" pos="0.2 0 0">
        <joint name="r" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.01" mass="0.2"/>
        <site name="rod_end" pos="0.2 0 0"/>
      </body>
    </body>
  </worldbody>
  <equality>
    <connect site1="rod_end" site2="anchor"/>
  </equality>
  <actuator>
    <position name="c" joint="c" kp="20" ctrlrange="-1 1"/>
  </actuator>
</mujoco>
"""


def test_loop_between_sites_closes_on_the_sites_bodies(tmp_path):
    """A connect between two sites (MuJoCo 3's form, as in newer Menagerie linkages): the recipe's
    loop closes on the links of the sites' bodies at the sites' points, not on the sites' frame
    links, which are massless: MuJoCo's constraint softness weighs the constrained bodies, and the
    loop on massless links moved otherwise (the rollout disagreed by 0.2 m)."""
    (tmp_path / "linkage.xml").write_text(SITE_LOOP)
    result = import_mjcf(tmp_path / "linkage.xml", tmp_path / "out" / "linkage.yaml", build=build_mjcf)
    recipe = yaml.safe_load(result.recipe_path.read_text())
    assert recipe["loops"] == {"loop0": {"link1": "rod", "origin1": {"xyz": [0.2, 0, 0]},
                                         "link2": "world", "origin2": {"xyz": [0.4, 0, 0]}}}
    assert result.verdict.ok, result.verdict.lines()


BODY_SENSORS = """<mujoco model="leg">
  <compiler angle="radian"/>
  <worldbody>
    <body name="thigh">
      <joint name="hip" axis="0 1 0" range="-1 1"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="1"/>
      <body name="shin" pos="0 0 -0.3">
        <joint name="knee" axis="0 1 0" range="-1 1"/>
        <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.5"/>
        <site name="knee_site"/>
        <site name="foot" pos="0 0 -0.3" size="0.03"/>
      </body>
    </body>
  </worldbody>
  <sensor>
    <force name="knee_force" site="knee_site"/>
    <torque name="knee_torque" site="knee_site"/>
    <touch name="foot_touch" site="foot"/>
    <gyro name="shin_gyro" site="knee_site"/>
  </sensor>
</mujoco>
"""


def test_force_torque_and_touch_sensors_on_a_site_are_dropped_saying_why(tmp_path):
    """The fruit fly's tarsus force sensors and its claws' touch sensors read the site's body (the
    force from its parent, its geoms' contacts); the rebuild holds each site on a frame link of
    its own (a massless body without geoms), where they read nothing: dropped, on the ledger (kept
    verbatim, the force sensor disagreed by 4e-2 and the touch sensor would read no contact); a
    gyro, which reads the site's motion, is kept."""
    (tmp_path / "leg.xml").write_text(BODY_SENSORS)
    result = import_mjcf(tmp_path / "leg.xml", tmp_path / "out" / "leg.yaml", build=build_mjcf)
    assert [line for line in result.ledger if "sensor" in line] == [
        "leg.xml:16: sensor 'knee_force': all: dropped: it reads the force between site 'knee_site''s body and its "
        "parent, and the rebuild holds the site on a frame link of its own (a massless body)",
        "leg.xml:17: sensor 'knee_torque': all: dropped: it reads the force between site 'knee_site''s body and its "
        "parent, and the rebuild holds the site on a frame link of its own (a massless body)",
        "leg.xml:18: sensor 'foot_touch': all: dropped: it reads the contacts of site 'foot''s body, and the rebuild "
        "holds the site on a frame link of its own (a body without geoms)",
        "leg.xml:19: sensor 'shin_gyro': urdf, sdf: dropped: the recipe has no gyro sensors (kept verbatim in "
        "mjcf_extras for the MJCF)",
    ]
    assert result.verdict.ok, result.verdict.lines()


WING = """<mujoco model="wing">
  <compiler angle="radian"/>
  <worldbody>
    <body name="thorax">
      <geom type="box" size="0.01 0.01 0.01" mass="0.001"/>
      <body name="wing" pos="0.01 0 0">
        <joint name="yaw" axis="0 0 1" range="-1 1"/>
        <joint name="roll" axis="1 0 0" range="-1 1"/>
        <geom type="box" size="0.0005 0.02 0.005" pos="0 0.02 0" mass="8e-6"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_chain_link_of_a_body_of_micrograms_gets_the_least_mass_a_recipe_takes(tmp_path):
    """The fruit fly's wing (8e-6 kg, three hinges) is too light to give its chain links their
    point mass, and a millionth of the lightest body (8e-12 kg) is below the least mass a recipe
    takes: the link gets that least mass, 1e-9 kg, added and stated (it was a refusal: 'the
    imported recipe would be invalid')."""
    (tmp_path / "wing.xml").write_text(WING)
    result = import_mjcf(tmp_path / "wing.xml", tmp_path / "out" / "wing.yaml")
    assert result.ledger[0] == (
        "wing.xml:6: body 'wing' (joint chain): all: approximated: chain link 'wing_yaw' carries an added point mass "
        "of 1e-09 kg (the least mass a recipe takes), not taken from the body: the body is too light to give it (what "
        "would be left is not a physical body); Gazebo (libsdformat's URDF reader) drops a link of 1e-06 kg or less "
        "with everything below it")
    assert yaml.safe_load(result.recipe_path.read_text())["links"]["wing_yaw"]["inertial"]["mass"] == 1e-9


CM_UNITS = """<mujoco model="pendulum_cm">
  <compiler angle="radian"/>
  <option gravity="0 0 -981"/>
  <worldbody>
    <body name="arm">
      <joint name="swing" axis="0 1 0" range="-1 1" damping="0.1"/>
      <geom type="capsule" fromto="0 0 0 10 0 0" size="1" mass="2"/>
    </body>
  </worldbody>
  <actuator>
    <position name="swing" joint="swing" kp="3000" ctrlrange="-1 1"/>
  </actuator>
</mujoco>
"""


def test_verification_compares_under_the_original_gravity(tmp_path):
    """A model in centimetres (the fruit fly's gravity is -981): the rebuilt MJCF has the standard
    gravity (on the ledger), and the verification compares the gravity forces under the original's,
    as its rollout runs with all the original's options (they disagreed by 99 %)."""
    (tmp_path / "pendulum.xml").write_text(CM_UNITS)
    result = import_mjcf(tmp_path / "pendulum.xml", tmp_path / "out" / "pendulum.yaml", build=build_mjcf)
    assert result.ledger[0] == ("pendulum.xml:3: option gravity: all: 0 0 -981 dropped: the rebuilt MJCF has 0 0 -9.81 "
                                "(the recipe has no simulation options)")
    assert result.verdict.ok, result.verdict.lines()


MEDIUM = """<mujoco model="swimmer">
  <compiler angle="radian"/>
  <option density="1000" viscosity="0.001"/>
  <worldbody>
    <body name="hull">
      <freejoint/>
      <geom type="box" size="0.1 0.05 0.05" mass="2"/>
      <body name="fin" pos="0.1 0 0">
        <joint name="yaw" axis="0 0 1" range="-1 1"/>
        <joint name="reach" type="slide" axis="1 0 0" range="-0.05 0.05"/>
        <geom type="box" size="0.1 0.002 0.05" pos="0.1 0 0" mass="0.01"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="yaw" joint="yaw" kp="2" ctrlrange="-1 1"/>
  </actuator>
</mujoco>
"""


def test_rollout_runs_without_the_medium_the_rebuild_lacks(tmp_path):
    """The fruit fly flies in air (fluid density and viscosity): the rebuild has no medium (on the
    ledger), and its forces act on each body's equivalent inertia box, which a body's joint chain
    splits; the rollout takes the medium out of both, as it does contacts (with it, the fin's chain
    link, an added point mass of 1e-8 kg with the least tensor, felt the drag of a 2.4 cm box and
    the rollout disagreed by 5 cm)."""
    (tmp_path / "swimmer.xml").write_text(MEDIUM)
    result = import_mjcf(tmp_path / "swimmer.xml", tmp_path / "out" / "swimmer.yaml", build=build_mjcf)
    assert [line.split(": all: ")[0] for line in result.ledger if "option" in line] == [
        "swimmer.xml:3: option density", "swimmer.xml:3: option viscosity", "swimmer.xml:3: option integrator"]
    assert result.verdict.ok, result.verdict.lines()


IMU_CUTOFF = """<mujoco model="torso">
  <worldbody>
    <body name="torso">
      <freejoint/>
      <geom type="box" size="0.1 0.1 0.2" mass="10"/>
      <site name="imu" pos="0.03 0 0.1"/>
    </body>
  </worldbody>
  <sensor>
    <gyro name="imu_gyro" site="imu" noise="5e-4" cutoff="54.9"/>
    <accelerometer name="imu_accel" site="imu" noise="1e-4" cutoff="157"/>
  </sensor>
</mujoco>
"""


def test_imu_cutoff_is_on_the_ledger(tmp_path):
    """Apptronik Apollo's IMU: a gyro and an accelerometer with noise and a cutoff; the recipe's
    imu sensor keeps the noise and has no cutoff: each cutoff is a ledger line (it went unsaid)."""
    (tmp_path / "torso.xml").write_text(IMU_CUTOFF)
    recipe, ledger, _, _ = convert(tmp_path / "torso.xml", tmp_path / "out" / "torso.yaml")
    assert recipe["sensors"]["imu"]["imu"] == {"gyro_noise": 5e-4, "accel_noise": 1e-4}
    assert [line for line in ledger.lines() if "cutoff" in line] == [
        "torso.xml:10: sensor 'imu_gyro' (gyro): all: cutoff 54.9 dropped: the recipe's imu sensor has no cutoff",
        "torso.xml:11: sensor 'imu_accel' (accel): all: cutoff 157 dropped: the recipe's imu sensor has no cutoff",
    ]


TELESCOPE = """<mujoco model="telescope">
  <worldbody>
    <body name="l3">
      <joint name="j3" type="slide" axis="1 0 0" range="0 0.1"/>
      <geom type="box" size="0.1 0.02 0.02" mass="0.2"/>
      <body name="l2" pos="0.01 0 0">
        <joint name="j2" type="slide" axis="1 0 0" range="0 0.1"/>
        <geom type="box" size="0.1 0.015 0.015" mass="0.15"/>
        <body name="l1" pos="0.01 0 0">
          <joint name="j1" type="slide" axis="1 0 0" range="0 0.1"/>
          <geom type="box" size="0.1 0.01 0.01" mass="0.1"/>
        </body>
      </body>
    </body>
  </worldbody>
  <equality>
    <joint joint1="j1" joint2="j2"/>
    <joint joint1="j2" joint2="j3"/>
  </equality>
  <actuator>
    <position name="extend" joint="j3" kp="100" ctrlrange="0 0.1"/>
  </actuator>
</mujoco>
"""


def test_mimic_of_a_mimic_is_kept_and_the_urdf_follows_the_chain(tmp_path):
    """Stretch's telescoping arm: each segment follows the next (joint equalities in a chain), so
    a mimic joint's leader is itself a mimic; the recipe and the MJCF keep the chain (the rebuild
    agrees in MuJoCo), the URDF composes it (its readers, Drake's and libsdformat's, follow one
    mimic, not a chain): every segment where the chain puts it in every program."""
    from robotkit.check.consumers import Build, consumer_findings

    (tmp_path / "telescope.xml").write_text(TELESCOPE)
    folder = tmp_path / "rebuilt"

    def build(recipe, out):
        built = build_mjcf(recipe, out)
        shutil.copytree(built.parent.parent, folder)
        return built

    result = import_mjcf(tmp_path / "telescope.xml", tmp_path / "out" / "telescope.yaml", build=build)
    recipe = yaml.safe_load(result.recipe_path.read_text())
    assert (recipe["joints"]["j1"]["mimic"], recipe["joints"]["j2"]["mimic"]) == ({"joint": "j2"}, {"joint": "j3"})
    assert result.ledger[1:] == []
    assert result.verdict.ok, result.verdict.lines()
    urdf = (folder / "urdf" / "telescope.urdf").read_text()
    assert urdf.count('<mimic joint="j3" multiplier="1" offset="0"/>') == 2
    build_ = Build("telescope", folder, folder / "urdf" / "telescope.urdf", None, None)
    errors = [f.message for f in consumer_findings(build_)[0] if f.severity == "error"]
    assert not [e for e in errors if "Drake" in e or "Pinocchio" in e or "PyBullet" in e], errors


UNSTABLE = """<mujoco model="twitchy">
  <compiler angle="radian"/>
  <worldbody>
    <body name="finger">
      <joint name="j" axis="0 1 0" range="-1 1"/>
      <geom type="capsule" fromto="0 0 0 0.05 0 0" size="0.005" mass="0.001"/>
    </body>
  </worldbody>
  <actuator>
    <position name="j" joint="j" kp="1" kv="10" ctrlrange="-1 1"/>
  </actuator>
</mujoco>
"""


def test_rollout_stops_where_the_original_turns_unstable(tmp_path):
    """Boston Dynamics Spot's arm, driven by the rollout's random controls in free fall, makes the
    original itself unstable (MuJoCo resets it, and what follows compared a restart with a rebuild
    that had not: 'disagreed' by 6 cm): the rollout compares until then and the verdict says so.
    Here a servo's damping far beyond what Euler integrates (kv dt / I = 2e4) on a gram's finger."""
    (tmp_path / "twitchy.xml").write_text(UNSTABLE)
    result = import_mjcf(tmp_path / "twitchy.xml", tmp_path / "out" / "twitchy.yaml", build=build_mjcf)
    assert result.verdict.ok, result.verdict.lines()
    assert result.verdict.notes == ["rollout from the zero configuration: the original turns unstable at 0.004 s under "
                                    "this control sequence (MuJoCo resets it): compared until the hold before"]


BEYOND = """<mujoco model="arm">
  <compiler angle="radian"/>
  <worldbody>
    <body name="upper">
      <joint name="shoulder" axis="0 1 0" range="-1.5 1.5"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02" mass="1"/>
    </body>
  </worldbody>
  <keyframe>
    <key name="home" qpos="1.5708"/>
  </keyframe>
</mujoco>
"""


def test_keyframe_beyond_its_joint_range_is_written_at_the_limit(tmp_path):
    """MuJoCo takes a keyframe outside a joint's range (a Menagerie 'home' a rounding past its
    limit); a recipe's pose lies within the limits: the nearest limit, on the ledger (it was a
    refusal: 'poses.home.shoulder: 1.5708 is outside the limits')."""
    (tmp_path / "arm.xml").write_text(BEYOND)
    result = import_mjcf(tmp_path / "arm.xml", tmp_path / "out" / "arm.yaml")
    assert yaml.safe_load(result.recipe_path.read_text())["poses"] == {"home": {"shoulder": 1.5}}
    assert result.ledger[1:] == ["arm.xml:10: keyframe 'home': all: joint 'shoulder' at 1.5708, outside its range "
                                 "[-1.5, 1.5]: written as 1.5"]


def test_include_outside_the_project_is_refused_at_its_line(tmp_path, monkeypatch):
    """The read rules of the URDF import (its xacro includes'): an ``<include>`` outside the
    input's project and the roots widened on purpose is one line at the include, exit 2, that
    file not read and nothing written (MuJoCo read it); ROBOTKIT_ROOT widens them."""
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)  # conftest widens the read rules
    (tmp_path / "project").mkdir()
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "project" / "main.xml").write_text(INCLUDED_MAIN.replace("parts/acts.xml", "../elsewhere/acts.xml"))
    (tmp_path / "elsewhere" / "acts.xml").write_text(INCLUDED_ACTS)
    with pytest.raises(RobotkitError) as exc:
        import_mjcf(tmp_path / "project" / "main.xml", tmp_path / "project" / "out" / "two.yaml")
    assert [str(p) for p in exc.value.problems] == [
        f"{tmp_path}/project/main.xml:10: {tmp_path}/elsewhere/acts.xml is outside the project {tmp_path}/project/: "
        "robotkit reads only the project and declared package paths (widen on purpose with --root DIR or "
        "ROBOTKIT_ROOT)"]
    assert not (tmp_path / "project" / "out").exists()
    monkeypatch.setenv("ROBOTKIT_ROOT", str(tmp_path / "elsewhere"))
    assert import_mjcf(tmp_path / "project" / "main.xml", tmp_path / "project" / "out" / "two.yaml").ledger
