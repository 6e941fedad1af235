"""Every output loads, weighs and moves the same in the programs people load it into:
Gazebo (libsdformat's URDF conversion, and model.sdf), Drake, Pinocchio, PyBullet, MuJoCo.

Each program is real (installed by scripts/test.sh); under CI a missing one fails.  The
oracle is the robot's own URDF: per-link and total mass to 1e-9 relative, every link frame at
random joint configurations to 1e-9 (PyBullet computes in single precision: 1e-5)."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from conftest import example_robots, run_cli, write_recipe
from robotkit.pipeline.runner import build
from robotkit.check.consumers import CONSUMERS, Build, consumer_findings, read
from robotkit.check.simulation import smoke_test
from validators import IN_CI, ign_sdf_check, require

pytestmark = [pytest.mark.consumers, pytest.mark.slow]

EXAMPLES = example_robots()
CORPUS = Path(__file__).resolve().parents[3] / "shared" / "assets" / "robots"


def consumers_installed():
    import importlib

    for module in ("pydrake", "pinocchio", "pybullet", "mujoco"):
        try:
            importlib.import_module(module)
        except ImportError:
            msg = f"consumer '{module}' is not installed (scripts/test.sh installs it)"
            if IN_CI:
                pytest.fail(msg)
            pytest.skip(msg)
    require("ign")


def build_of(out: Path, name: str, base: str = "fixed") -> Build:
    d = out / name
    return Build(name, d, d / "urdf" / f"{name}.urdf", d / "model.sdf", d / "mjcf" / f"{name}.xml", base)


@pytest.mark.parametrize("name", EXAMPLES)
def test_example_in_every_consumer(examples, name):
    consumers_installed()
    base = "free" if "<freejoint" in (examples / name / "mjcf" / f"{name}.xml").read_text() else "fixed"
    findings, summary = consumer_findings(build_of(examples, name, base))
    assert [str(f) for f in findings] == []
    assert sorted(summary) == sorted(CONSUMERS)
    assert all(s["loaded"] and s["agrees"] for s in summary.values()), summary


@pytest.mark.parametrize("name", EXAMPLES)
def test_example_scene_rests_on_the_floor(examples, name):
    """The scene as a user opens it: its own integrator, contacts on, standing on the floor."""
    consumers_installed()
    notes = []
    assert smoke_test(examples / name / "mjcf" / "scene.xml", notes=notes) == []
    assert notes == []  # free robots start on the floor, not above it


def test_example_urdfs_are_not_emptied_by_gazebo(examples):
    """libsdformat keeps every link with mass (lumped into its moving parent), and the rover's
    camera and sensors (behind massless frames) survive the conversion."""
    require("ign")
    for name, links, sensors in (("turtlebot3_burger", 3, 2), ("ur5", 7, 0), ("rover", 3, 6)):
        out = subprocess.run(["ign", "sdf", "-p", str(examples / name / "urdf" / f"{name}.urdf")],
                             capture_output=True, text=True).stdout
        assert out.count("<link name") == links, name
        assert out.count("<sensor name") == sensors, name
        assert "preserveFixedJoint" not in (examples / name / "urdf" / f"{name}.urdf").read_text()


MASSLESS = """
    robot: frames
    base: free
    links:
      base_footprint: {}
      base_link:
        visual: {box: {size: [0.3, 0.2, 0.1]}, origin: {xyz: [0, 0, 0.05]}}
        inertial: {mass: 2.0}
      arm:
        visual: {cylinder: {radius: 0.02, length: 0.3}, origin: {xyz: [0, 0, 0.15]}}
        inertial: {mass: 0.5}
      flange: {}
      tool0: {}
      marker:
        visual: {sphere: {radius: 0.01}}
        inertial: none
    joints:
      footprint: {type: fixed, parent: base_footprint, child: base_link}
      shoulder:
        type: revolute
        parent: base_link
        child: arm
        origin: {xyz: [0, 0, 0.1]}
        axis: [0, 1, 0]
        limit: {lower: -1, upper: 1, effort: 10, velocity: 1}
      arm_flange: {type: fixed, parent: arm, child: flange, origin: {xyz: [0, 0, 0.3]}}
      flange_tool: {type: fixed, parent: flange, child: tool0, origin: {xyz: [0, 0, 0.02]}}
      tool_marker: {type: fixed, parent: tool0, child: marker, origin: {xyz: [0, 0, 0.01]}}
"""


def test_massless_links_weigh_nothing_in_every_consumer(tmp_path):
    """A massless root, a chain of massless frames and a display-only link: no phantom 1 kg
    (PyBullet, SDF's default), no NaN lumping (libsdformat), frames in model.sdf."""
    consumers_installed()
    recipe = write_recipe(tmp_path, MASSLESS)
    build([recipe], tmp_path / "out")
    b = build_of(tmp_path / "out", "frames", "free")
    findings, summary = consumer_findings(b)
    assert [str(f) for f in findings] == []
    assert {k: round(v["mass"], 12) for k, v in summary.items()} == {k: 2.5 for k in CONSUMERS}
    sdf = b.sdf.read_text()
    assert re.findall(r'<link name="(\w+)"', sdf) == ["base_link", "arm"]
    assert re.findall(r'<frame name="(\w+)" attached_to="(\w+)"', sdf) == [
        ("base_footprint", "base_link"), ("flange", "arm"), ("tool0", "flange"), ("marker", "tool0")]
    assert sdf.count("<visual ") == 3  # the marker's sphere moved into 'arm'
    ign_sdf_check(b.sdf)
    urdf = b.urdf.read_text()
    assert urdf.count('<mass value="1e-300"/>') == 4  # every massless link but nothing else
    view = read("PyBullet (URDF)", b)
    assert view.masses["tool0"] < 1e-200 and view.masses["base_footprint"] < 1e-200


def test_a_link_and_a_joint_with_the_same_name(tmp_path):
    """ROS accepts it (ANYmal's LF_HAA); an SDF model needs the names apart."""
    consumers_installed()
    recipe = write_recipe(tmp_path, """
        robot: clash
        links:
          base: {visual: {box: {size: [0.2, 0.2, 0.1]}}, inertial: {mass: 1}}
          LF_HAA: {visual: {box: {size: [0.05, 0.05, 0.1]}}, inertial: {mass: 0.2}}
        joints:
          LF_HAA:
            type: revolute
            parent: base
            child: LF_HAA
            origin: {xyz: [0.1, 0.1, 0]}
            axis: [1, 0, 0]
            limit: {lower: -0.5, upper: 0.5, effort: 5, velocity: 2}
    """)
    result = build([recipe], tmp_path / "out")
    assert ("clash: SDF: joint 'LF_HAA' is named 'LF_HAA_joint' in model.sdf: SDF needs link, joint and "
            "frame names unique within a model") in result.warnings
    b = build_of(tmp_path / "out", "clash")
    ign_sdf_check(b.sdf)
    findings, _ = consumer_findings(b)
    assert [str(f) for f in findings] == []


def test_a_robot_a_consumer_refuses_fails_the_build_naming_the_link(tmp_path):
    recipe = write_recipe(tmp_path, """
        robot: arm
        links:
          world: {}
          base: {visual: {box: {size: [0.2, 0.2, 0.1]}}, inertial: {mass: 1}}
          forearm: {}
          hand: {visual: {box: {size: [0.05, 0.05, 0.05]}}, inertial: none}
        joints:
          mount: {type: fixed, parent: world, child: base}
          elbow:
            type: revolute
            parent: base
            child: forearm
            axis: [0, 1, 0]
            limit: {lower: -1, upper: 1, effort: 5, velocity: 2}
          wrist: {type: fixed, parent: forearm, child: hand, origin: {xyz: [0, 0, 0.2]}}
    """)
    proc = run_cli("build", recipe, "--out", tmp_path / "out", cwd=tmp_path)
    assert proc.returncode == 1
    assert proc.stderr.splitlines() == [
        "robot.yaml:5: links.forearm: link 'forearm' moves (joint 'elbow') but has no mass: MuJoCo refuses to "
        "load it and Gazebo drops it with everything below it; give it an inertial (links.forearm.inertial: "
        "{mass: ...}, or geometry and a density)",
        "robot.yaml: arm: left out (refused by a consumer, or naming a file that is): " + ", ".join(
            f"arm/{f}" for f in ("urdf/arm.urdf", "urdf/arm.urdf.xacro", "model.sdf", "mjcf/arm.xml", "mjcf/scene.xml",
                                 "srdf/arm.srdf", "model.config", "package.xml", "CMakeLists.txt", "hooks/arm.dsv.in",
                                 "launch/display.launch.py", "launch/gazebo.launch.py", "rviz/arm.rviz",
                                 "report/report.html"))]
    for rel in ("urdf/arm.urdf", "model.sdf", "mjcf/arm.xml"):
        assert not (tmp_path / "out" / "arm" / rel).exists(), rel


def test_a_chain_of_1000_links(tmp_path):
    """URDF and SDF of a 1000-link chain load in Gazebo and Drake with the right masses and
    frames; the programs that cannot hold it say why (measured limits), and the MJCF, which
    MuJoCo's XML reader could not load (496 nested bodies at most), is not written: a stated loss,
    the build succeeds."""
    consumers_installed()
    n = 1000
    lines = ["robot: chain", "links:"]
    lines += [f"  l{i}: {{visual: {{box: {{size: [0.02, 0.02, 0.1]}}, origin: {{xyz: [0, 0, 0.05]}}}}, "
              "inertial: {mass: 0.1}}" for i in range(n)]
    lines.append("joints:")
    lines += [f"  j{i}: {{type: revolute, parent: l{i - 1}, child: l{i}, origin: {{xyz: [0, 0, 0.1]}}, "
              "axis: [0, 1, 0], limit: {lower: -0.01, upper: 0.01, effort: 1, velocity: 1}}" for i in range(1, n)]
    recipe = tmp_path / "chain.yaml"
    recipe.write_text("\n".join(lines) + "\n")
    proc = run_cli("build", recipe, "--out", tmp_path / "out", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr  # a limit of the format, not of the robot (issue 33)
    assert [line for line in proc.stderr.splitlines() if "not written" in line] == [
        "chain.yaml:1: warning: chain: not written, a limit of the format: MJCF: link 'l999' sits 1000 links deep "
        "and MuJoCo's XML reader stops at 496 nested bodies (a body per link); left out: chain/mjcf/chain.xml, "
        "chain/mjcf/scene.xml, chain/report/report.html (list it under outputs: to make this an error)"]
    b = build_of(tmp_path / "out", "chain")
    assert b.urdf.is_file() and b.sdf.is_file() and not b.mjcf.exists() and not b.dir.joinpath("mjcf").exists()
    findings, summary = consumer_findings(b, ["Gazebo (URDF)", "Gazebo (model.sdf)", "Drake (URDF)",
                                              "Drake (model.sdf)", "Pinocchio (URDF)", "PyBullet (URDF)"], configs=3)
    assert {k for k, s in summary.items() if s["loaded"] and s["agrees"]} == {
        "Gazebo (URDF)", "Gazebo (model.sdf)", "Drake (URDF)", "Drake (model.sdf)"}
    assert [(f.severity, f.message) for f in findings] == [  # the programs' own limits: warnings (issue 33)
        ("warning", "Pinocchio (URDF): not checked, a limit of the program: Pinocchio's model data for 999 degrees "
         "of freedom needs about 64.8 GB (it grows with the cube of the count), more than half of this machine's "
         "free memory"),
        ("warning", "PyBullet (URDF): not checked, a limit of the program: loadURDF made a body of 1000 links that "
         "PyBullet cannot place (one PyBullet body holds at most 128 links)")]
    assert abs(summary["Drake (model.sdf)"]["mass"] - 100.0) < 1e-9


@pytest.mark.parametrize("name, entry, packages, args", [
    ("aliengo", "aliengo_description/xacro/robot.xacro", ["aliengo_description"], ["DEBUG:=false"]),
    ("open_manipulator_x", "open_manipulator_description/urdf/open_manipulator_x/open_manipulator_x.urdf.xacro",
     ["open_manipulator_description", "open_manipulator_bringup"], []),
])
def test_public_robot_imported_built_and_loaded_everywhere(tmp_path, name, entry, packages, args):
    """Real robots (../shared/assets/robots): a quadruped with DAE meshes in inches and
    textures, an arm with a mimic gripper and STL in millimetres."""
    consumers_installed()
    if not CORPUS.is_dir():
        pytest.fail(f"robot corpus not found at {CORPUS}")
    cmd = ["import", CORPUS / entry, "-o", tmp_path / f"{name}.yaml"]
    for p in packages:
        cmd += ["--package-path", f"{p}={CORPUS / p}"]
    for a in args:
        cmd += ["--arg", a]
    assert run_cli(*cmd).returncode == 0
    result = build([tmp_path / f"{name}.yaml"], tmp_path / "out")
    assert not result.errors
    robot = result.robots[0]
    b = build_of(tmp_path / "out", robot)
    findings, summary = consumer_findings(b)
    assert [str(f) for f in findings] == []
    assert smoke_test(b.dir / "mjcf" / "scene.xml") == []
    if name == "aliengo":
        # the trunk's texture travels with its DAE; calf.dae is in inches (<unit meter="0.0254">):
        # MuJoCo's OBJ copy is in metres, as RViz and Gazebo show the DAE
        assert (b.dir / "meshes" / "visual" / "trunk_uv_base_final.png").is_file()
        import trimesh

        calf = trimesh.load(b.dir / "meshes" / "mjcf" / "calf.obj")
        assert 0.3 < max(calf.extents) < 0.35, calf.extents


def test_check_names_what_each_consumer_sees_on_a_foreign_urdf(assets):
    """PyBullet's KUKA iiwa: a massless root with only moving joints below it, which Gazebo's
    conversion empties, and STL collision meshes, which Drake reads only as OBJ: `robotkit check`
    gives them to it converted, says so, and Drake's reading shows the 1 kg it gives the root
    (and every stage runs after a lint error)."""
    consumers_installed()
    robots = assets / "robots"
    proc = run_cli("check", robots / "kuka_iiwa" / "model.urdf", "--format", "json")
    import json

    data = json.loads(proc.stdout)
    messages = [f["message"] for f in data["findings"]]
    assert proc.returncode == 1
    assert "mass is 0.0" in messages  # the lints ran ...
    assert ("Gazebo (URDF) refuses the robot: libsdformat's reading has no link at all (an empty model)"
            in messages)  # ... and so did the consumers
    assert "Drake (URDF): link 'lbr_iiwa_link_0' weighs 1 kg, the description says 0 kg" in messages
    assert ("Drake (URDF): reads meshes only as OBJ, VTK or glTF: 'meshes/link_0.stl', 'meshes/link_1.stl', "
            "'meshes/link_2.stl' and 5 more given to it as OBJ here (a build converts them)") in messages


def test_check_names_the_1_kg_default_of_an_sdf_link(tmp_path):
    sdf = tmp_path / "m.sdf"
    sdf.write_text('<?xml version="1.0"?>\n<sdf version="1.9"><model name="m"><link name="a"/>'
                   "<link name=\"b\"><inertial><mass>2</mass><inertia><ixx>1</ixx><iyy>1</iyy><izz>1</izz>"
                   "</inertia></inertial></link><joint name=\"j\" type=\"fixed\"><parent>a</parent><child>b</child>"
                   "</joint></model></sdf>\n")
    proc = run_cli("check", "m.sdf", cwd=tmp_path)
    assert proc.returncode == 1
    lines = proc.stdout.splitlines()
    assert lines[:-1] == [
        "  ok       ign sdf -k",
        "  1 error  consumers",
        "link 'a' (m.sdf:2)",
        "  error: has no <inertial>: Gazebo and Drake give it a mass of 1 kg and a unit inertia [consumer]",
        "    hint: give it an <inertial>, or make a massless thing a <frame>"]
    assert re.fullmatch(r"m\.sdf: 1 stage passed, 1 error, 0 warnings \(\d+\.\d s\)", lines[-1])
