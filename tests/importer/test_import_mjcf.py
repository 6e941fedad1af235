"""``robotkit import model.xml``: an MJCF read through MuJoCo into a recipe, each mapping on a
small robot made for it (tests/data/mjcf/features.xml), the ledger word for word, the rebuild
compared with the original in MuJoCo (and a rebuild that differs caught), bad input refused
with MuJoCo's own message at its line, and Menagerie models (a copy of the Skydio X2 here, the
shared set in the slow tier)."""

from __future__ import annotations

import difflib
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

from robotkit.commands.import_ import build_mjcf
from robotkit.errors import RobotkitError
from robotkit.importer import import_mjcf
from robotkit.importer.mjcf import convert
from robotkit.importer.mjcf.verify import verify
from tests.conftest import ASSETS, run_cli

DATA = Path(__file__).resolve().parents[1] / "data"
FEATURES = DATA / "mjcf" / "features.xml"
X2 = DATA / "menagerie" / "skydio_x2" / "x2.xml"


@pytest.fixture(scope="module")
def features(tmp_path_factory):
    out = tmp_path_factory.mktemp("features") / "features.yaml"
    recipe, ledger, src, tree = convert(FEATURES, out)
    return recipe, ledger, src, tree


def test_bodies_are_links_rooted_in_world(features):
    recipe = features[0]
    assert list(recipe["links"]) == ["world", "base", "upper", "fore_elbow", "fore", "wrist_wrist_ball_x",
                                     "wrist_wrist_ball_y", "wrist", "finger_a", "finger_b", "tool", "elbow_mark"]
    base = recipe["joints"]["base_fixed"]
    assert base["type"] == "fixed" and base["parent"] == "world"
    assert base["origin"]["xyz"] == [0, 0, 0.1]
    assert base["origin"]["rpy"] == pytest.approx([0, 0, math.radians(30)], abs=1e-15)


def test_hinge_off_the_origin_moves_the_link_frame_onto_its_axis(features):
    joints = features[0]["joints"]
    assert joints["shoulder"]["origin"] == {"xyz": [0.02, 0, 0.1]}  # the body at 0 0 0.1, the joint at 0.02 0 0
    assert joints["elbow"]["origin"]["xyz"] == [-0.02, 0, 0.3]  # the child written in the shifted frame


def test_joint_ref_is_baked_into_the_origin(features):
    """MuJoCo places a body as the file does at the joint's ``ref`` and moves it by value - ref: the
    origin takes the move back, so joint values (limits, keyframes) stay MuJoCo's."""
    joints = features[0]["joints"]
    assert joints["elbow"]["origin"]["rpy"] == [0, pytest.approx(-math.radians(10)), 0]  # ref="10" (degrees)
    assert joints["elbow"]["limit"]["lower"] == pytest.approx(-math.radians(120))
    assert joints["extend"]["origin"] == {"xyz": [0, 0, -0.02]}  # a slide's ref="0.02"


def test_several_joints_in_one_body_are_a_chain(features):
    recipe = features[0]
    joints = recipe["joints"]
    assert (joints["elbow"]["child"], joints["extend"]["parent"], joints["extend"]["child"]) == (
        "fore_elbow", "fore_elbow", "fore")
    assert joints["extend"]["type"] == "prismatic"
    assert recipe["links"]["fore_elbow"]["inertial"]["mass"] == pytest.approx(0.05 * 1e-6)


def test_ball_joint_is_three_revolute_joints(features):
    joints = features[0]["joints"]
    assert [(joints[f"wrist_ball_{a}"]["type"], joints[f"wrist_ball_{a}"]["axis"]) for a in "xyz"] == [
        ("continuous", [1, 0, 0]), ("continuous", [0, 1, 0]), ("continuous", [0, 0, 1])]
    assert joints["wrist_ball_z"]["child"] == "wrist"


def test_limits_in_radians_and_dynamics(features):
    shoulder = features[0]["joints"]["shoulder"]
    assert shoulder["limit"]["lower"] == pytest.approx(-math.pi / 2)
    assert shoulder["dynamics"] == {"damping": 0.5, "friction": 0.2, "armature": 0.01}


def test_shapes_capsule_mesh_scale_and_visual_only_geoms(features):
    links = features[0]["links"]
    upper = links["upper"]
    kinds = [next(k for k in ("cylinder", "sphere", "mesh", "box") if k in s) for s in upper["visual"]]
    assert kinds == ["cylinder", "sphere", "sphere", "mesh"]  # the capsule is a cylinder and two spheres
    assert upper["visual"][0]["cylinder"] == {"radius": 0.03, "length": pytest.approx(0.3)}
    mesh = upper["visual"][3]
    assert mesh["scale"] == 0.5 and mesh["material"] == "blue"  # the default class's mesh scale
    assert [next(iter(s)) for s in upper["collision"]] == ["cylinder", "sphere", "sphere"]  # the mesh does not collide
    assert links["wrist"]["visual"]["box"] == {"size": [0.06, 0.04, 0.02]}  # the ellipsoid, stated


def test_mesh_sits_where_mujoco_puts_it(features):
    """MuJoCo reads the file's vertices as scale * refquat^-1 (v - refpos), then moves them to their
    inertial frame: the recipe's origin undoes both, so the file's vertices at that origin are
    MuJoCo's compiled vertices where MuJoCo places them (to float32)."""
    import trimesh

    from robotkit.geometry import rpy_matrix
    from robotkit.importer.mjcf.frames import quat_matrix

    recipe, _, src, tree = features
    m = src.model
    g = m.geom("upper_rotor").id
    d = m.geom_dataid[g]
    compiled = m.mesh_vert[m.mesh_vertadr[d]:m.mesh_vertadr[d] + m.mesh_vertnum[d]].astype(float)
    theirs = compiled @ quat_matrix(m.geom_quat[g]).T + m.geom_pos[g] - tree.offset[m.geom_bodyid[g]]
    shape = recipe["links"]["upper"]["visual"][3]
    raw = trimesh.load(FEATURES.parent / "rotor.stl").vertices * shape["scale"]
    mine = raw @ rpy_matrix(shape["origin"]["rpy"]).T + np.array(shape["origin"]["xyz"])
    assert len(mine) == len(theirs)
    assert np.abs(np.sort(mine, axis=0) - np.sort(theirs, axis=0)).max() < 1e-7


def test_inertials_as_mujoco_computed_them(features):
    _, _, src, _ = features
    upper = features[0]["links"]["upper"]["inertial"]
    m = src.model
    b = m.body("upper").id
    assert upper["mass"] == float(m.body_mass[b])  # the capsule's 1 kg and the mesh's mass at its density
    assert upper["mass"] > 1


def test_actuators_mimic_pose_and_excludes(features):
    recipe = features[0]
    assert recipe["actuators"] == {"shoulder": {"interface": "position", "p": 40, "d": 2},
                                   "elbow": {"interface": "velocity", "p": 3},
                                   "extend": {"interface": "effort"},
                                   "finger_a": {"interface": "position", "p": 10}}
    joints = recipe["joints"]
    assert joints["finger_b"]["mimic"] == {"joint": "finger_a"}
    assert joints["extend"]["limit"]["effort"] == 10  # ctrlrange 5 x gear 2
    assert joints["elbow"]["limit"]["velocity"] == 2  # the velocity servo's ctrlrange
    home = recipe["poses"]["home"]
    assert home["shoulder"] == 0.5 and home["finger_a"] == 0.01 and "finger_b" not in home
    assert home["wrist_ball_y"] == pytest.approx(math.pi / 4, abs=1e-7)
    assert recipe["self_collision"] == {"allow": [["base", "fore", "MJCF <contact><exclude>"]]}


def test_ledger_word_for_word(features):
    assert features[1].lines() == [
        "features.xml:33: geom 'wrist_ellipsoid' (ellipsoid): all: approximated: the box of its half-axes "
        "0.03 0.02 0.01",
        "features.xml:27: body 'fore' (joint chain): all: approximated: chain link 'fore_elbow' carries an added point "
        "mass of 5e-08 kg (a millionth of the lightest body), not taken from the body: joint 'extend' after it is not "
        "a hinge, so no point of the link stays fixed in the body; Gazebo (libsdformat's URDF reader) drops a link of "
        "1e-06 kg or less with everything below it",
        "features.xml: option integrator: all: Euler dropped: the rebuilt MJCF has implicitfast (the recipe has no "
        "simulation options)",
        "features.xml:59: actuator 'shoulder_servo': all: ctrlrange [-1.2, 1.2] written as the joint's range "
        "[-1.5708, 1.5708]",
        "features.xml:61: actuator 'extend_motor': all: gear 2: the recipe's motor takes the joint's force (ctrl x 2)",
        "features.xml:21: site 'tool': mjcf: a frame link (in the rebuilt MJCF a body without mass holding a site "
        "of its name): its sphere of size 0.005 is not drawn",
        "features.xml:26: site 'elbow_mark': mjcf: a frame link (in the rebuilt MJCF a body without mass holding a "
        "site of its name): its box of size 0.01 0.02 0.03 is not drawn",
        "features.xml:54: tendon 'fingers': urdf, sdf: dropped: the recipe has no tendons (kept verbatim in "
        "mjcf_extras for the MJCF)",
        "features.xml:65: sensor 'shoulder_angle': urdf, sdf: dropped: the recipe has no jointpos sensors (kept "
        "verbatim in mjcf_extras for the MJCF)",
        "features.xml:32: joint 'wrist_ball' (ball): all: approximated: three revolute joints about the body's x, y, z "
        "through two links, each a point mass taken from the body at the ball's centre (the dynamics unchanged); its "
        "armature, damping and friction act on each angle, not on the angular velocity",
    ]


def test_sites_are_frame_links_at_their_pose(features):
    """A site is a link without mass or shape, fixed to its body's link where MuJoCo puts it: on a
    body whose link frame sits on its hinge's axis (0.02 m off), 0.01 m from that frame."""
    recipe = features[0]
    assert recipe["links"]["tool"] == {} and recipe["links"]["elbow_mark"] == {}
    assert recipe["joints"]["tool_fixed"] == {"type": "fixed", "parent": "base", "child": "tool",
                                              "origin": {"xyz": [0, 0, 0.2]}}
    mark = recipe["joints"]["elbow_mark_fixed"]
    assert (mark["type"], mark["parent"], mark["child"]) == ("fixed", "upper", "elbow_mark")
    assert mark["origin"]["xyz"] == pytest.approx([0.01, 0, 0.3], abs=1e-15)
    assert mark["origin"]["rpy"] == pytest.approx([0, math.pi / 2, 0], abs=1e-7)


def test_constraint_softness_the_rebuild_lacks_is_on_the_ledger(tmp_path):
    """MuJoCo's limit, friction-loss and equality softness: the rebuilt MJCF has its defaults."""
    (tmp_path / "soft.xml").write_text(
        '<mujoco>\n<worldbody>\n<body name="a">\n<geom size="0.1"/>\n'
        '<joint name="j" range="-1 1" solreflimit="0.005 1" frictionloss="0.1" solimpfriction="0.8 0.9 0.01 0.5 2"/>\n'
        '<body name="b"><geom size="0.1"/><joint name="k" range="-1 1"/></body>\n</body>\n</worldbody>\n'
        '<equality><joint joint1="k" joint2="j" solref="0.01 1"/></equality>\n</mujoco>\n')
    ledger = convert(tmp_path / "soft.xml", tmp_path / "soft.yaml")[1].lines()
    assert ledger[0].startswith("soft.xml: option integrator: all: Euler dropped")
    assert ledger[1:] == [
        "soft.xml:9: equality joint #0: all: a mimic joint: solref 0.01 1, solimp 0.9 0.95 0.001 0.5 2 dropped: the "
        "rebuilt MJCF has MuJoCo's defaults (the recipe has no constraint softness)",
        "soft.xml:5: joint 'j': all: solreflimit 0.005 1, solimplimit 0.9 0.95 0.001 0.5 2; solreffriction 0.02 1, "
        "solimpfriction 0.8 0.9 0.01 0.5 2 dropped: the rebuilt MJCF has MuJoCo's defaults (the recipe has no "
        "constraint softness)",
    ]


@pytest.fixture(scope="module")
def rebuilt(tmp_path_factory):
    """The features robot imported with its verification, and a copy of its rebuilt MJCF."""
    folder = tmp_path_factory.mktemp("rebuilt")

    def build(recipe, out):
        built = build_mjcf(recipe, out)
        shutil.copytree(built.parent.parent, folder / "copy")  # the robot's build folder, meshes and all
        return built

    result = import_mjcf(FEATURES, folder / "features.yaml", build=build)
    return result, folder


def test_rebuild_agrees_with_the_original_in_mujoco(rebuilt):
    result, folder = rebuilt
    assert result.verdict.ok, result.verdict.lines()
    assert result.verdict.configurations == 22  # the keyframe, the zero configuration, 20 random ones
    assert result.verdict.rollouts == 0
    text = (folder / "features.yaml").read_text()
    assert "# verified in MuJoCo against the original at 22 configurations and 0 rollouts: every quantity agrees" in text
    assert ("#   note: no rollout: ball joint 'wrist_ball' is three revolute joints through chain links in the "
            "rebuild (approximated, on the ledger), whose motion parts from the ball's") in text
    assert ("#   features.xml:54: tendon 'fingers': urdf, sdf: dropped: the recipe has no tendons (kept verbatim in mjcf_extras\n"
            "#   for the MJCF)") in text
    assert yaml.safe_load(text)["mjcf_extras"] == [
        '<tendon>\n  <fixed name="fingers">\n    <joint joint="finger_a" coef="1"/>\n  </fixed>\n</tendon>',
        '<sensor>\n  <jointpos name="shoulder_angle" joint="shoulder"/>\n</sensor>']
    assert yaml.safe_load(text)["robot"] == "features"
    assert ("  # MJCF ref 0.02: the origin takes the body back to the joint's zero, so joint values (limits,\n"
            "  # poses) are MuJoCo's; driven, with no velocity limit in the MJCF (unlimited): 1e+09\n  extend:\n") in text
    assert "  # one of the three revolute joints ball joint 'wrist_ball' becomes (x, y, z of its body)\n" in text


def test_verification_builds_everything_but_the_self_collision_matrix(rebuilt, tmp_path, monkeypatch):
    """No comparison reads contacts (the rollouts run without them), so the verification's
    build computes no self-collision matrix: its MJCF is the recipe's own build's but for the
    contact filters (MuJoCo's <exclude> pairs, and no self-contacts without a matrix)."""
    from robotkit.emit.layout import robot_layout
    from robotkit.pipeline.runner import build

    _, folder = rebuilt
    monkeypatch.setenv("ROBOTKIT_ROOT", str(FEATURES.parent))
    full = build([folder / "features.yaml"], tmp_path, report=False)
    assert (tmp_path / ".robotkit" / "features" / "self_collision.json").is_file()
    theirs = robot_layout(tmp_path / full.robots[0]).mjcf.read_text().splitlines()
    mine = (folder / "copy" / "mjcf" / "features.xml").read_text().splitlines()
    diff = [f"{line[0]} {line[2:].strip()}" for line in difflib.ndiff(mine, theirs) if line[:1] in "+-"]
    assert [line for line in diff if line.startswith("-")] == [
        "- <!-- self_collide: false: robot geoms collide with the world, not each other -->",
        '- <geom group="3" density="0" rgba="0.6 0.6 0.6 0.4" contype="2" conaffinity="1"/>']
    added = [line for line in diff if line.startswith("+")]
    assert added[0] == '+ <geom group="3" density="0" rgba="0.6 0.6 0.6 0.4"/>'
    assert added[1] == "+ <contact>" and added[-1] == "+ </contact>"
    assert len(added) == 14 and all(line.startswith("+ <exclude body1=") for line in added[2:-1])


def test_verification_catches_a_rebuild_that_differs(rebuilt, features, tmp_path):
    _, folder = rebuilt
    mjcf = _mutated(folder, tmp_path, "mjcf/features.xml", 'mass="0.5"', 'mass="0.6"')
    _, _, src, tree = features
    verdict = verify(src, tree, mjcf)
    assert not verdict.ok
    assert verdict.failures[:2] == ["total mass: mass off by 2.49e-02 (tolerance 1e-09)",
                                    "body 'fore' at keyframe 'home': mass off by 2.00e-01 (tolerance 1e-09)"]


def test_verification_compares_each_site_with_its_frame_link(rebuilt, features, tmp_path):
    _, folder = rebuilt
    # 1 mm along the frame link's x, which the keyframe turns: 0.76 mm in the largest world coordinate
    mjcf = _mutated(folder, tmp_path, "mjcf/features.xml", '<body name="elbow_mark" pos="0.01 0 0.3"',
                    '<body name="elbow_mark" pos="0.011 0 0.3"')
    verdict = verify(features[2], features[3], mjcf)
    assert verdict.failures[0] == "site 'elbow_mark' at keyframe 'home': pose off by 7.60e-04 (tolerance 1e-09)"
    assert all(f.startswith("site 'elbow_mark' at ") for f in verdict.failures)


def _mutated(folder: Path, tmp_path: Path, name: str, old: str, new: str) -> Path:
    """A copy of the rebuilt robot's folder with ``old`` replaced by ``new`` in its file ``name``
    (mjcf/features.xml, urdf/features.urdf); the copy's MJCF."""
    copy = tmp_path / "copy"
    shutil.copytree(folder / "copy", copy)
    text = (copy / name).read_text()
    assert old in text
    (copy / name).write_text(text.replace(old, new))
    return copy / "mjcf" / "features.xml"


def test_verification_loads_the_rebuilt_urdf_in_pinocchio(rebuilt, features, tmp_path):
    """Only the URDF differs (its forearm heavier): Pinocchio's mass matrix and gravity forces,
    matched to MuJoCo's by joint name, catch it."""
    _, folder = rebuilt
    mjcf = _mutated(folder, tmp_path, "urdf/features.urdf", '<mass value="0.5"/>', '<mass value="0.6"/>')
    verdict = verify(features[2], features[3], mjcf)
    assert verdict.failures and all(f.startswith("URDF ") and "in Pinocchio at" in f for f in verdict.failures)
    assert verdict.failures[0].startswith("URDF mass matrix in Pinocchio at keyframe 'home': pinocchio off by ")
    assert verdict.worst["matrix"][0] < 1e-6  # the MJCF still agrees


@pytest.fixture(scope="module")
def hinged(tmp_path_factory):
    """The features robot with its ball joint a hinge (a model with a ball joint has no rollout),
    imported with its verification, and a copy of its rebuilt folder."""
    folder = tmp_path_factory.mktemp("hinged")
    shutil.copy(FEATURES.parent / "rotor.stl", folder)
    text = FEATURES.read_text().replace('type="ball"', 'axis="1 0 0"')
    text = text.replace('qpos="0.5 0.75 0.05 0.9238795 0 0.3826834 0 0.01 0.01"', 'qpos="0.5 0.75 0.05 0.3 0.01 0.01"')
    (folder / "features.xml").write_text(text)

    def build(recipe, out):
        built = build_mjcf(recipe, out)
        shutil.copytree(built.parent.parent, folder / "copy")
        return built

    return import_mjcf(folder / "features.xml", folder / "features.yaml", build=build), folder


def test_rollout_from_each_keyframe_agrees(hinged):
    result, _ = hinged
    assert result.verdict.ok, result.verdict.lines()
    assert result.verdict.rollouts == 1
    assert result.verdict.lines()[0] == ("verified in MuJoCo against the original at 22 configurations and 1 rollout: "
                                         "every quantity agrees")
    assert 0 < result.verdict.worst["rollout"][0] < 1e-4


def test_verification_rollout_catches_what_the_configurations_do_not(hinged, tmp_path):
    """Damping moves nothing at rest: only the 0.5 s rollout from the keyframe sees it."""
    result, folder = hinged
    mjcf = _mutated(folder, tmp_path, "mjcf/features.xml", 'damping="0.5"', 'damping="0.6"')
    _, _, src, tree = convert(folder / "features.xml", tmp_path / "r.yaml")
    verdict = verify(src, tree, mjcf)
    assert verdict.rollouts == 1
    assert len(verdict.failures) == 1 and verdict.failures[0].startswith("rollout from keyframe 'home': body ")


def test_verification_checks_equalities_and_actuators(rebuilt, features, tmp_path):
    _, folder = rebuilt
    text = (folder / "copy" / "mjcf" / "features.xml").read_text()
    equality = text[text.index("<equality>"):text.index("</equality>") + len("</equality>")]
    mjcf = _mutated(folder, tmp_path, "mjcf/features.xml", equality, "")
    text = mjcf.read_text()
    mjcf.write_text(text.replace('kp="10"', 'kp="11"', 1))
    verdict = verify(features[2], features[3], mjcf)
    assert "equality #0 missing from the rebuild: equality off by 1.00e+00 (tolerance 1e-09)" in verdict.failures
    assert ("equality count: 0 rebuilt, 1 kept of the original's 1: equality off by 1.00e+00 (tolerance 1e-09)"
            in verdict.failures)
    assert any(f.startswith("actuator 'grip' gain, bias and gear: actuator off by ") for f in verdict.failures)


def test_refused_mjcf_is_one_line_at_its_line_and_nothing_written(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text('<mujoco>\n<worldbody>\n<body name="a">\n<geom size="0.1" colour="red"/>\n</body>\n'
                   '</worldbody>\n</mujoco>\n')
    proc = run_cli("import", bad, "-o", tmp_path / "out" / "bad.yaml", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines()[-1].endswith(
        "bad.xml:4: MuJoCo refuses the file: Schema violation: unrecognized attribute: 'colour'")
    assert "Traceback" not in proc.stderr
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


@pytest.mark.parametrize("name, text, expected", [
    ("loop.xml", '<mujoco>\n<include file="loop.xml"/>\n</mujoco>\n',
     "loop.xml:2: MuJoCo refuses the file: File 'loop.xml' already included"),
    ("broken.xml", "<mujoco>\n<worldbody>\n<body>\n</worldbody>\n</mujoco>\n",
     "broken.xml:3: MuJoCo refuses the file: XML parse error 14: XML_ERROR_MISMATCHED_ELEMENT XMLElement name=body"),
    ("truncated.xml", '<mujoco>\n<asset><mesh file="cut.stl"/></asset>\n'
     '<worldbody><body><geom type="mesh" mesh="cut"/></body></worldbody>\n</mujoco>\n',
     "truncated.xml:2: MuJoCo refuses the file: stl_decoder: STL file '{dir}/cut.stl' has wrong size; perhaps this "
     "is an ASCII file?"),
])
def test_bad_input_is_one_line_and_nothing_written(tmp_path, name, text, expected):
    (tmp_path / "cut.stl").write_bytes((FEATURES.parent / "rotor.stl").read_bytes()[:300])
    (tmp_path / name).write_text(text)
    with pytest.raises(RobotkitError) as exc:
        import_mjcf(tmp_path / name, tmp_path / "out" / "r.yaml")
    assert [str(p) for p in exc.value.problems] == [str(tmp_path / expected.format(dir=tmp_path))]
    assert not (tmp_path / "out").exists()


def test_missing_file_is_refused(tmp_path):
    with pytest.raises(RobotkitError) as exc:
        import_mjcf(tmp_path / "none.xml", tmp_path / "r.yaml")
    assert str(exc.value).endswith("none.xml: file not found")


def test_skydio_x2_on_the_command_line(tmp_path, monkeypatch):
    """A free-flying Menagerie model: ``base: free``, its site actuators on the ledger (stderr),
    the verdict and the build command on stdout (with the read rules as a user has them: its
    meshes stay outside the project, and the command that builds it widens the build to them)."""
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)  # conftest widens the read rules
    proc = run_cli("import", X2, "-o", "x2.yaml", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout.splitlines()
    assert out[0] == "verified in MuJoCo against the original at 22 configurations and 1 rollout: every quantity agrees"
    # the model's name 'Skydio X2' as a ROS package's (the build names the package after the robot)
    assert ("note: robot 'Skydio X2' (the MJCF's model name) named 'skydio_x2': the robot's name is its ROS "
            "package's, which holds lower case letters, digits and '_', a letter first (REP 144)"
            ) in proc.stderr.splitlines()
    assert out[-2:] == ["wrote x2.yaml (robot skydio_x2); build it with:",
                        f"robotkit build --root {X2.parent / 'assets'} x2.yaml"]
    built = run_cli("build", "--root", X2.parent / "assets", "x2.yaml", "--no-report", cwd=tmp_path)
    assert built.returncode == 0, built.stderr
    assert ("ledger: x2.xml:56: actuator 'thrust1': urdf, sdf: dropped: a site transmission (the recipe's actuators "
            "drive joints) (kept verbatim in mjcf_extras for the MJCF)") in proc.stderr.splitlines()
    assert ("ledger: x2.xml:26: material 'phong3SG': all: texture dropped: the recipe's material is a colour "
            "(its rgba kept)") in proc.stderr.splitlines()
    recipe = yaml.safe_load((tmp_path / "x2.yaml").read_text())
    ledger = [line.removeprefix("ledger: ") for line in proc.stderr.splitlines() if line.startswith("ledger: ")]
    assert recipe["metadata"]["ledger"] == ledger  # and the build's report.json carries it
    assert json.loads((tmp_path / "build" / "skydio_x2" / "report.json").read_text())["ledger"] == ledger
    assert recipe["base"] == "free" and list(recipe["links"]) == ["x2", "thrust1", "thrust2", "thrust3",
                                                                     "thrust4"]  # its sites as frames
    # its gyro and accelerometer on site 'imu': the recipe's imu sensor, whose frame is the site
    assert recipe["sensors"] == {"imu": {"type": "imu", "parent": "x2", "frame": "imu",
                                         "origin": {"xyz": [0, 0, 0.02]}}}
    assert ("ledger: x2.xml:63: sensor 'body_gyro' (gyro): mjcf: the recipe's imu sensor 'imu': written as "
            "'imu_gyro' on site 'imu_site'") in proc.stderr.splitlines()
    mjcf = (tmp_path / "build" / "skydio_x2" / "mjcf" / "skydio_x2.xml").read_text()
    assert '<gyro name="imu_gyro" site="imu_site"/>' in mjcf
    mesh = next(s for s in recipe["links"]["x2"]["visual"] if "mesh" in s)
    assert mesh["scale"] == 0.01  # set in the default class


MENAGERIE = ASSETS / "menagerie"
SHARED = ["dynamixel_2r/dynamixel_2r.xml", "low_cost_robot_arm/low_cost_robot_arm.xml", "trs_so_arm100/so_arm100.xml",
          "ufactory_xarm7/xarm7.xml", "ufactory_xarm7/xarm7_nohand.xml", "ufactory_xarm7/hand.xml",
          "trossen_vx300s/vx300s.xml", "kinova_gen3/gen3.xml", "robotiq_2f85/2f85.xml", "bitcraze_crazyflie_2/cf2.xml",
          "agility_cassie/cassie.xml", "umi_gripper/umi_gripper.xml", "google_barkour_vb/barkour_vb.xml",
          "google_barkour_vb/barkour_vb_mjx.xml", "pal_tiago/tiago.xml", "pal_tiago/tiago_position.xml",
          "pal_tiago/tiago_velocity.xml", "pal_tiago/tiago_motor.xml", "wonik_allegro/left_hand.xml",
          "wonik_allegro/right_hand.xml"]
"""Every entry file of the shared set (skydio_x2 is in tests/data)."""


@pytest.mark.slow
@pytest.mark.parametrize("model", SHARED)
def test_shared_menagerie_model_imports_and_agrees(model, tmp_path):
    if not (MENAGERIE / model).is_file():
        pytest.skip("the shared Menagerie set is not here")
    result = import_mjcf(MENAGERIE / model, tmp_path / "r.yaml", build=build_mjcf)
    assert result.verdict.ok, result.verdict.lines()
    assert (result.verdict.rollouts == 0) == (model == "agility_cassie/cassie.xml")  # its ball joints: no rollout
    worst = result.verdict.worst
    assert np.isfinite([v[0] for v in worst.values()]).all()
