"""Every real robot in ../shared/assets/robots imports, builds and loads.

The ten public descriptions of robots.tsv (arms, a dual arm, hands, a quadruped, mobile bases,
a humanoid; URDF and xacro; STL, DAE and OBJ) are imported once per session, with their
collision geometry as given (no CoACD), and built.  For each:

- the build's URDF passes check_urdf;
- the build equals the original (the xacro package's own expansion) at 1e-9 in links, joints,
  limits, masses, centres of mass, tensors and link poses at random configurations, except
  the inertials of the links whose repair the recipe states (``ImportResult.repairs``, each
  with its comment above the link in the recipe);
- every consumer (Gazebo via libsdformat, Drake, Pinocchio, PyBullet, MuJoCo) loads the build
  and agrees with its URDF.
"""

from __future__ import annotations

import csv
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from robotkit.pipeline.runner import build
from robotkit.check.consumers import Build, consumer_findings
from robotkit.check.kinematics import compare, read_urdf
from robotkit.importer import import_file
from tests.conftest import run_cli
from tests.validators import check_urdf, mujoco

pytestmark = [pytest.mark.consumers, pytest.mark.slow]

ROBOTS_DIR = Path(__file__).resolve().parents[2].parent / "shared" / "assets" / "robots"
TOL = 1e-9


def _corpus() -> dict[str, dict]:
    if not (ROBOTS_DIR / "robots.tsv").is_file():
        return {}
    out = {}
    with open(ROBOTS_DIR / "robots.tsv", encoding="utf-8") as f:
        for row in csv.DictReader(f, delimiter="\t"):
            packages = dict(p.split("=", 1) for p in (row["packages"] or "").split())
            args = dict(a.split(":=", 1) for a in (row["xacro_args"] or "").split())
            out[row["name"]] = {"entry": ROBOTS_DIR / row["entry"], "args": args,
                                "packages": {k: str(ROBOTS_DIR / v) for k, v in packages.items()}}
    return out


CORPUS = _corpus()
NAMES = sorted(CORPUS) or ["(assets missing)"]


@pytest.fixture(scope="session")
def corpus(tmp_path_factory):
    """Each robot imported and built once: name -> (ImportResult, build folder of the robot)."""
    if not CORPUS:
        pytest.fail(f"the robot corpus is not at {ROBOTS_DIR} (CI clones the repository next to shared/)")
    mujoco()
    root = tmp_path_factory.mktemp("corpus")
    done = {}
    for name, spec in CORPUS.items():
        result = import_file(spec["entry"], root / name / "recipe" / "robot.yaml", spec["packages"], spec["args"])
        built = build([result.recipe_path], root / name / "build")
        done[name] = (result, root / name / "build" / result.robot, built.errors)
    return done


def _original(name: str, out: Path) -> Path:
    """The original URDF: the xacro package's own expansion (not robotkit's), or the file."""
    spec = CORPUS[name]
    if not spec["entry"].name.endswith(".xacro"):
        return spec["entry"]
    from tests.importer.test_import import xacro_reference

    return xacro_reference(spec["entry"], spec["packages"], spec["args"], out)


def _with_stated_repairs(original: Path, built_urdf: Path, repairs: dict[str, str]) -> str:
    """The original with the inertial of each link the recipe says it repaired taken from the
    build, and PyBullet's <capsule> (read by no URDF parser we compare with) as a sphere."""
    tree = ET.parse(original)
    built = {el.get("name"): el for el in ET.parse(built_urdf).getroot().iter("link")}
    for link in tree.getroot().iter("link"):
        if link.get("name") in repairs:
            old = link.find("inertial")
            if old is not None:
                link.remove(old)
            link.insert(0, built[link.get("name")].find("inertial"))
    text = ET.tostring(tree.getroot(), encoding="unicode")
    return re.sub(r"<capsule\b[^>]*/>", '<sphere radius="0.01"/>', text)


@pytest.mark.parametrize("name", NAMES)
def test_imports_and_builds(corpus, name):
    result, robot_dir, errors = corpus[name]
    assert not errors, errors
    check_urdf(robot_dir / "urdf" / f"{result.robot}.urdf")
    recipe = result.recipe_path.read_text(encoding="utf-8")
    for link, why in result.repairs.items():  # every repair is stated above its link
        first = why.split()[:4]
        assert re.search(r"  # " + re.escape(" ".join(first)), recipe), (link, why)


@pytest.mark.parametrize("name", NAMES)
def test_equals_the_original_except_the_stated_repairs(corpus, name, tmp_path):
    result, robot_dir, errors = corpus[name]
    assert not errors
    original = _original(name, tmp_path / "original.urdf")
    stated = tmp_path / "stated.urdf"
    stated.write_text(_with_stated_repairs(original, robot_dir / "urdf" / f"{result.robot}.urdf", result.repairs),
                      encoding="utf-8")
    a, b = read_urdf(stated), read_urdf(robot_dir / "urdf" / f"{result.robot}.urdf")
    assert compare(a, b, TOL, configs=20) == []


@pytest.mark.parametrize("name", NAMES)
def test_every_consumer_loads_the_build(corpus, name):
    result, robot_dir, errors = corpus[name]
    assert not errors
    mjcf = robot_dir / "mjcf" / f"{result.robot}.xml"
    base = "free" if "<freejoint" in mjcf.read_text(encoding="utf-8") else "fixed"
    build_ = Build(result.robot, robot_dir, robot_dir / "urdf" / f"{result.robot}.urdf", robot_dir / "model.sdf",
                   mjcf, base)
    findings, summary = consumer_findings(build_, configs=5)
    assert [str(f) for f in findings if f.severity == "error"] == []
    assert all(s["loaded"] for s in summary.values()), summary


REPAIRED = {  # what each robot's import must say it changed (the issue's failures, on real files)
    "shadow_hand": {"rh_fftip": "the original's inertia is zero"},
    "pmb2": {"base_antenna_left_link": "the original's inertia is not positive definite"},
    "fanuc_m10ia": {"base_link": "no mass in the original (nor on the links welded to it), and it is (or is "
                                   "welded to) the root"},
    "motoman_sda10f": {"arm_left_link_1_s": "no mass in the original, and it moves (joint 'arm_left_joint_1_s')",
                       "torso_base_link": "no mass in the original (nor on the links welded to it)"},
    "kuka_iiwa_bullet": {"lbr_iiwa_link_0": "no mass in the original (nor on the links welded to it), and it is "
                                            "(or is welded to) the root"},
    "humanoid_bullet": {"link1_2": "no mass in the original, and it moves"},
}


@pytest.mark.parametrize("name", sorted(REPAIRED))
def test_the_repairs_are_the_expected_ones(corpus, name):
    result = corpus[name][0]
    for link, start in REPAIRED[name].items():
        assert result.repairs[link].startswith(start), result.repairs[link]


# ---------------------------------------------------------------- what the corpus lacks: an edited copy


def edited_kuka(folder: Path) -> Path:
    """A copy of the corpus' KUKA iiwa (BSD-2, see LICENSES/) with the traits real files show and the
    corpus lacks: a '/' in a link name, a revolute joint with lower == upper and effort 0 (meant
    free), a prismatic one with lower == upper != 0 (it can only be there), principal moments that break the triangle inequality, an ASCII STL as visual and
    collision, a joint named like a link, a moving link without <inertial>, a mimic chain with a
    multiplier and offset, and a mimic whose leader is a fixed joint."""
    import shutil

    import trimesh

    src = ROBOTS_DIR / "kuka_iiwa"
    shutil.copytree(src / "meshes", folder / "meshes")
    t = (src / "model.urdf").read_text(encoding="utf-8")
    t = t.replace('"lbr_iiwa_link_3"', '"lbr/iiwa_link_3"')
    t = re.sub(r'(<joint name="lbr_iiwa_joint_4"[\s\S]*?)<limit[^>]*/>',
               r'\1<limit effort="0" lower="0" upper="0" velocity="0"/>', t)
    t = re.sub(r'<joint name="lbr_iiwa_joint_6" type="revolute">([\s\S]*?)<limit[^>]*/>',
               r'<joint name="lbr_iiwa_joint_6" type="prismatic">\1<limit effort="0" lower="0.02" upper="0.02" '
               r'velocity="0"/>', t)
    t = re.sub(r'(<link name="lbr_iiwa_link_5">[\s\S]*?)<inertia [^>]*/>',
               r'\1<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.05"/>', t)
    t = re.sub(r'(<link name="lbr_iiwa_link_7">\s*)<inertial>[\s\S]*?</inertial>', r'\1', t)
    t = t.replace('<joint name="lbr_iiwa_joint_5"', '<joint name="lbr_iiwa_link_5"')
    for mesh in ("link_2.stl", "link_1.obj"):
        t = t.replace(f'<mesh filename="meshes/{mesh}"/>', '<mesh filename="meshes/link_2_ascii.stl"/>')
    for joint, mimic in (("lbr_iiwa_joint_2", '<mimic joint="lbr_iiwa_joint_1" multiplier="0.5" offset="0.1"/>'),
                         ("lbr_iiwa_joint_3", '<mimic joint="lbr_iiwa_joint_2" multiplier="-1"/>'),
                         ("lbr_iiwa_joint_7", '<mimic joint="tool_joint"/>')):
        t = re.sub(rf'(<joint name="{joint}"[\s\S]*?)</joint>', rf'\1  {mimic}\n  </joint>', t, count=1)
    t = t.replace("</robot>", '  <link name="tool"/>\n  <joint name="tool_joint" type="fixed">\n'
                  '    <parent link="lbr_iiwa_link_7"/>\n    <child link="tool"/>\n    <origin xyz="0 0 0.1"/>\n'
                  '  </joint>\n</robot>')
    mesh = trimesh.load(src / "meshes" / "link_2.stl")
    (folder / "meshes" / "link_2_ascii.stl").write_text(trimesh.exchange.stl.export_stl_ascii(mesh), encoding="ascii")
    (folder / "model.urdf").write_text(t, encoding="utf-8")
    return folder / "model.urdf"


def _with_stated_joint_changes(text: str, notes: dict[str, str]) -> str:
    import numpy as np
    from scipy.spatial.transform import Rotation

    root = ET.fromstring(text)
    renamed = {re.match(r"named '([^']+)' in the original, like a link", note)[1]: name
               for name, note in notes.items() if re.match(r"named '([^']+)' in the original, like a link", note)}
    for el in root.iter("joint"):
        el.set("name", renamed.get(el.get("name"), el.get("name")))
        note = notes.get(el.get("name"), "")
        if note.startswith("mimicked fixed joint"):
            el.remove(el.find("mimic"))
        elif "so it is fixed there" in note:  # a prismatic joint at its only position
            at = float(el.find("limit").get("lower"))
            origin = el.find("origin")
            xyz = np.array([float(v) for v in origin.get("xyz").split()])
            rotation = Rotation.from_euler("xyz", [float(v) for v in origin.get("rpy").split()])
            axis = np.array([float(v) for v in el.find("axis").get("xyz").split()])
            origin.set("xyz", " ".join(repr(float(v)) for v in xyz + rotation.apply(axis / np.linalg.norm(axis)) * at))
            el.set("type", "fixed")
            for tag in ("limit", "axis"):
                el.remove(el.find(tag))
        elif "lower == upper" in note:
            el.set("type", "continuous")
            for key in ("lower", "upper"):
                el.find("limit").attrib.pop(key)
    return ET.tostring(root, encoding="unicode")


def test_an_edited_copy_imports_builds_and_loads(tmp_path):
    from robotkit.check import check_urdf_file

    mujoco()
    source = edited_kuka(tmp_path / "kuka")
    result = import_file(source, tmp_path / "recipe" / "robot.yaml", {}, {})
    built = build([result.recipe_path], tmp_path / "build")
    assert not built.errors, built.errors
    robot_dir = tmp_path / "build" / result.robot
    urdf = robot_dir / "urdf" / f"{result.robot}.urdf"
    check_urdf(urdf)
    assert result.joint_notes == {
        "lbr_iiwa_joint_4": "limit lower == upper (0.0) in the original: read as no position limit (lower and "
                            "upper default to 0 in URDF), the joint is continuous",
        "lbr_iiwa_joint_6": "limit lower == upper (0.02) in the original: the joint can only be at that position, "
                            "so it is fixed there, its origin moved 0.02 along the axis; MuJoCo would ignore the "
                            "equal limits and let it slide freely",
        "lbr_iiwa_joint_7": "mimicked fixed joint 'tool_joint' in the original: a fixed joint has no position to "
                            "follow, so the mimic is dropped and the joint moves on its own",
        "lbr_iiwa_link_5_joint": "named 'lbr_iiwa_link_5' in the original, like a link: links and joints share one "
                                 "namespace in SDF, where libsdformat (Gazebo) reads the URDF, so it is renamed here "
                                 "and where mimics and transmissions name it"}
    assert '<joint name="lbr_iiwa_link_5_joint" type="revolute">' in (robot_dir / "model.sdf").read_text()
    assert result.repairs["lbr_iiwa_link_5"] == (
        "the original's principal moments 0.01, 0.01, 0.05 violate the triangle inequality: repaired (principal "
        "moments 0.01, 0.01, 0.05 moved to 0.02, 0.02, 0.04 to meet the triangle inequality)")
    assert result.repairs["lbr_iiwa_link_7"].startswith("no mass in the original, and it moves (joint "
                                                        "'lbr_iiwa_joint_7')")
    recipe = result.recipe_path.read_text(encoding="utf-8")
    assert "  # limit lower == upper (0.0) in the original" in recipe and "  lbr/iiwa_link_3:" in recipe
    unwrapped = re.sub(r"\n  # ", " ", recipe)  # the comments above the joints, each on one line
    assert f" {result.joint_notes['lbr_iiwa_joint_6']}\n  lbr_iiwa_joint_6:\n    type: fixed\n" in unwrapped
    # equal to the original except what the recipe states
    stated = _with_stated_repairs(source, urdf, result.repairs)
    (tmp_path / "stated.urdf").write_text(_with_stated_joint_changes(stated, result.joint_notes), encoding="utf-8")
    assert compare(read_urdf(tmp_path / "stated.urdf"), read_urdf(urdf), TOL, configs=20) == []
    # MuJoCo reads only binary STL: the MJCF references a binary copy of the ASCII visual
    mjcf = robot_dir / "mjcf" / f"{result.robot}.xml"
    assert 'file="mjcf/link_2_ascii.stl"' in mjcf.read_text(encoding="utf-8")
    findings, summary = consumer_findings(Build(result.robot, robot_dir, urdf, robot_dir / "model.sdf", mjcf),
                                          configs=5)
    assert [str(f) for f in findings if f.severity == "error"] == []
    assert all(s["loaded"] for s in summary.values()), summary
    # check names the real defects on the original
    found = {(f.check, f.subject) for f in check_urdf_file(source, {}) if f.severity == "error"}
    assert {("triangle-inequality", "link 'lbr_iiwa_link_5'"), ("massless-moving", "link 'lbr_iiwa_link_7'")} <= found


def test_check_takes_xacro_and_names_moving_links_without_mass(tmp_path):
    """The Motoman SDA10F has no <inertial> at all: MuJoCo refuses it, and check says so."""
    spec = CORPUS["motoman_sda10f"]
    proc = run_cli("check", spec["entry"], *[x for k, v in spec["packages"].items() for x in ("--package-path",
                                                                                             f"{k}={v}")])
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "  error: moves (joint 'arm_left_joint_1_s') but has no mass: MuJoCo refuses to load the robot and " \
           "Gazebo drops the link with everything below it [massless-moving]" in proc.stdout.splitlines()


@pytest.mark.parametrize("policy", ["recompute", "estimate"])
def test_pmb2_with_an_inertia_policy_builds_and_loads(tmp_path, policy):
    """PMB-2's antennas have tensors that are not positive definite; with ``--inertia-policy
    recompute`` (or ``estimate``) they get their collision cylinder's (r 5 mm, 170 mm long, which
    is its own bounding primitive) at the given 1 g, stated in the recipe; the rest equals the
    original, and every consumer loads the build."""
    import numpy as np

    mujoco()
    spec = CORPUS["pmb2"]
    proc = run_cli("import", spec["entry"], "-o", tmp_path / "recipe" / "robot.yaml", "--inertia-policy", policy,
                   *[x for k, v in spec["packages"].items() for x in ("--package-path", f"{k}={v}")])
    assert proc.returncode == 0, proc.stderr
    written = (tmp_path / "recipe" / "robot.yaml").read_text(encoding="utf-8")
    result = import_file(spec["entry"], tmp_path / "recipe" / "robot.yaml", spec["packages"], spec["args"],
                         inertia_policy=policy)
    assert result.recipe_path.read_text(encoding="utf-8") == written  # the command and the API agree
    assert sorted(result.repairs) == ["base_antenna_left_link", "base_antenna_right_link"]
    assert result.repairs["base_antenna_left_link"].startswith(
        "the original's inertia is not positive definite (principal moments -3.53486e-08, 3.50085e-08, "
        f"9.08701e-08): {'recomputed from' if policy == 'recompute' else 'estimated as the bounding primitive of'} "
        f"its collision geometry, keeping the mass (policy: {policy};")
    built = build([result.recipe_path], tmp_path / "build")
    assert not built.errors, built.errors
    robot_dir = tmp_path / "build" / result.robot
    urdf = robot_dir / "urdf" / f"{result.robot}.urdf"
    check_urdf(urdf)
    m, r, h = 1e-6, 0.005, 0.17
    for name in result.repairs:
        link = read_urdf(urdf).links[name]
        assert link.mass == m and np.allclose(link.com, [0, 0, 0.085], rtol=0, atol=1e-12)
        side = m * (3 * r * r + h * h) / 12
        assert np.allclose(np.linalg.eigvalsh(link.inertia), [m * r * r / 2, side, side], rtol=1e-12, atol=0)
    stated = tmp_path / "stated.urdf"
    stated.write_text(_with_stated_repairs(_original("pmb2", tmp_path / "original.urdf"), urdf, result.repairs),
                      encoding="utf-8")
    assert compare(read_urdf(stated), read_urdf(urdf), TOL, configs=20) == []
    mjcf = robot_dir / "mjcf" / f"{result.robot}.xml"
    base = "free" if "<freejoint" in mjcf.read_text(encoding="utf-8") else "fixed"
    findings, summary = consumer_findings(Build(result.robot, robot_dir, urdf, robot_dir / "model.sdf", mjcf, base),
                                          configs=5)
    assert [str(f) for f in findings if f.severity == "error"] == []
    assert all(s["loaded"] for s in summary.values()), summary


@pytest.mark.parametrize("name", NAMES)
def test_defaults_change_no_value(corpus, name, tmp_path, monkeypatch):
    """The values moved to the recipe's ``defaults`` (and the exceptions written per joint or
    link) give, once merged, the recipe written without them: field for field."""
    import robotkit.importer
    from robotkit.recipe.load import load_recipes

    result = corpus[name][0]
    spec = CORPUS[name]
    monkeypatch.setattr(robotkit.importer, "factor_defaults", lambda recipe: {})  # the name import_file calls
    plain = import_file(spec["entry"], result.recipe_path.parent / "plain.yaml", spec["packages"], spec["args"])
    assert "\ndefaults:" not in plain.recipe_path.read_text(encoding="utf-8")
    (factored,), (unfactored,) = load_recipes(result.recipe_path), load_recipes(plain.recipe_path)
    assert factored.problems == [] and unfactored.problems == []
    assert factored.recipe.model_dump(exclude={"defaults"}) == unfactored.recipe.model_dump(exclude={"defaults"})


# ---------------------------------------------------------------- check on the originals

DEFECTS = {  # every error `robotkit check` names on each original; why each is real is said beside it
    # inertia-box: tensors that do not fit the parts (the fingers' is a 3 cm rod along y; the wrist
    # links' moments are a twelfth of their geometry's); PyBullet's 1 kg for its links without
    # <inertial> (frames to urdfdom) is a warning: its default, not the robot's
    "kinova_j2n6s300": {
        "inertia-box": ["j2n6s300_link_4", "j2n6s300_link_5", "j2n6s300_link_6", "j2n6s300_link_finger_1",
                        "j2n6s300_link_finger_tip_1", "j2n6s300_link_finger_2", "j2n6s300_link_finger_tip_2",
                        "j2n6s300_link_finger_3", "j2n6s300_link_finger_tip_3"]},
    # the calf rotors' transverse moments exceed their axial one: a disc's are half of it
    "aliengo": {
        "inertia-box": ["FR_calf_rotor", "FL_calf_rotor", "RR_calf_rotor", "RL_calf_rotor"]},
    # no <inertial> anywhere (ROS-Industrial's kinematics-only files; their effort 0 on every joint,
    # which nothing drives, is a passive joint: a warning)
    "motoman_sda10f": {
        # torso_base_link: massless, welded above the torso joint (libsdformat drops what moves below it)
        "massless-moving": ["torso_link_b1", "torso_link_b2"] + [f"arm_{side}_link_{j}" for side in ("left", "right")
                                                                 for j in ("1_s", "2_l", "3_e", "4_u", "5_r", "6_b",
                                                                           "7_t")] + ["torso_base_link"],
        "consumer": ["Gazebo (URDF) refuses the robot: libsdformat's reading has no link at all (an empty model)"]},
    "fanuc_m10ia": {
        "massless-moving": [f"link_{i}" for i in range(1, 7)],
        "consumer": ["Gazebo (URDF) refuses the robot: libsdformat's reading has no link at all (an empty model)"]},
    # the gripper links' tensor is a placeholder (the same moments on every axis: a 7.75 cm cube)
    "open_manipulator_x": {
        "inertia-box": ["gripper_left_link", "gripper_right_link"]},
    "shadow_hand": {
        "inertia": ["rh_fftip", "rh_mftip", "rh_rftip", "rh_lftip", "rh_thtip"]},  # zero tensors
    # the sonars' tensor is a placeholder cube; the antennas' has a negative moment
    "pmb2": {
        "inertia-box": ["base_sonar_03_link", "base_sonar_02_link", "base_sonar_01_link", "base_cover_link"],
        "inertia": ["base_antenna_left_link", "base_antenna_right_link"]},
    # PyBullet's static base (mass 0), which Gazebo drops with everything below it and Drake gives 1 kg
    "kuka_iiwa_bullet": {
        "mass": ["lbr_iiwa_link_0"],
        "consumer": ["Gazebo (URDF) refuses the robot: libsdformat's reading has no link at all (an empty model)",
                     "Drake (URDF): total mass 18.5 kg, the description's is 17.5 kg",
                     "Drake (URDF): link 'lbr_iiwa_link_0' weighs 1 kg, the description says 0 kg"]},
    # hand-typed chassis tensor; the camera's 10 mg with a 0.78 m cube's tensor (its density, 0.058 kg/m^3, is a
    # warning: the rigid body it is welded to, the chassis's, is 845 kg/m^3)
    "racecar_bullet": {"inertia-box": ["chassis", "zed_camera_link"]},
    # PyBullet's own dialect: <capsule>, massless links between the three joints of a ball joint, no name
    "humanoid_bullet": {
        "check_urdf": ["Error:   Unknown geometry type 'capsule'"],
        "massless-moving": ["link1_2", "link1_7", "link1_8", "link1_13", "link1_16", "link1_17", "link1_22",
                            "link1_25", "link1_30"],
        "consumer": ["Gazebo (URDF) refuses the robot: Error:   Unknown geometry type 'capsule'",
                     'Drake (URDF) refuses the robot: the robot has no name (<robot name="">): Drake stops the whole '
                     "program on it (model_instance.cc: condition '!name.empty()' failed)"]},
}


@pytest.mark.parametrize("name", NAMES)
def test_check_names_the_real_defects_of_each_original(name):
    """`robotkit check` on each original (the xacro with its package paths, or the URDF): the
    errors are exactly the robot's real defects (a consumer's own limit, such as Drake reading
    no STL collision mesh, is a warning)."""
    from robotkit.commands.check import check

    spec = CORPUS[name]
    found: dict[str, list[str]] = {}
    for f in check(str(spec["entry"]), package_paths=spec["packages"], args=spec["args"]):
        if f.severity == "error":
            what = f.message if f.check in ("consumer", "check_urdf") else f.subject.split("'")[1]
            found.setdefault(f.check, []).append(what)
    assert found == DEFECTS[name]


def test_check_passes_a_clean_original():
    """The turret bot's URDF (a ROS package beside the corpus) has no defect: exit 0, with
    Drake's own limit (meshes only as OBJ, VTK or glTF: given to it converted) as a warning."""
    turret = ROBOTS_DIR.parent / "turret_bot"
    proc = run_cli("check", turret / "urdf" / "turret_bot.urdf", "--package-path", f"turret_bot={turret}")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert re.fullmatch(re.escape(f"{turret / 'urdf' / 'turret_bot.urdf'}: 1 stage passed, 0 errors, 2 warnings")
                        + r" \(\d+\.\d s\)", proc.stdout.splitlines()[-1]), proc.stdout
    assert "  warning: Drake (URDF): reads meshes only as OBJ, VTK or glTF: 'package://turret_bot/meshes/base.stl', " \
           "'package://turret_bot/meshes/slider.stl', 'package://turret_bot/meshes/rotor.stl' given to it as OBJ here " \
           "(a build converts them) [consumer]" in proc.stdout.splitlines()
