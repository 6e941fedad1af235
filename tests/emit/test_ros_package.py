"""The ROS package files, checked without running ROS: ROS 2 is not packaged for Debian 12, so
its packages are checked statically (catkin_pkg validates package.xml, every launch file
compiles, every package a launch file starts is an exec_depend); golden files; bad input."""

from __future__ import annotations

import ast
import py_compile
import re
import shutil
import textwrap
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import yaml

from conftest import GOLDEN, RECIPES, assert_golden, run_cli, write_recipe

EXAMPLES = ["turret_bot", "lidar_mast", "rover", "turtlebot3_burger", "ur5"]


@pytest.fixture(scope="session")
def ros2_packages(tmp_path_factory) -> Path:
    from robotkit.pipeline.runner import build

    out = tmp_path_factory.mktemp("ros2-build")
    # one process: a doit worker forked from the test process, which holds other libraries'
    # threads (Drake, rendering), could deadlock; the session's mesh cache makes this quick
    build([RECIPES / f"{name}.yaml" for name in EXAMPLES], out, ros="ros2")
    return out


@pytest.fixture(scope="session")
def ros1_small(tmp_path_factory) -> Path:
    """The ROS 1 packages of the examples that build in a second."""
    from robotkit.pipeline.runner import build

    out = tmp_path_factory.mktemp("ros1-small")
    build([RECIPES / f"{name}.yaml" for name in ("turret_bot", "rover")], out, ros="ros1")
    return out


def _parse_package(folder: Path):
    from catkin_pkg.package import parse_package

    return parse_package(str(folder / "package.xml"))  # validates (raises InvalidPackage)


def _launch_packages(path: Path) -> set[str]:
    """Packages a ROS 2 launch file starts or reads: Node(package=...), get_package_share_directory(...)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Call):
            for kw in node.keywords:
                if kw.arg == "package" and isinstance(kw.value, ast.Constant):
                    out.add(kw.value.value)
            name = getattr(node.func, "id", getattr(node.func, "attr", ""))
            if name == "get_package_share_directory" and isinstance(node.args[0], ast.Constant):
                out.add(node.args[0].value)
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            module = node.module if isinstance(node, ast.ImportFrom) else node.names[0].name
            out.add(module.split(".")[0])
    return out - {"os", "__future__"}


def _installed_folders(cmake: str) -> set[str]:
    return set(re.search(r"install\(DIRECTORY ([^\n]+)", cmake).group(1).split())


# ---------------------------------------------------------------- ROS 2, statically


@pytest.mark.slow
@pytest.mark.parametrize("name", EXAMPLES)
def test_ros2_package_xml_is_valid(ros2_packages, name):
    pkg = _parse_package(ros2_packages / name)
    assert pkg.package_format == 3 and pkg.name == name
    assert [d.name for d in pkg.buildtool_depends] == ["ament_cmake"]
    assert [e.content for e in pkg.exports if e.tagname == "build_type"] == ["ament_cmake"]
    assert pkg.maintainers and all(m.email for m in pkg.maintainers)


@pytest.mark.slow
@pytest.mark.parametrize("name", EXAMPLES)
def test_ros2_launch_files_compile_and_depend(ros2_packages, name):
    folder = ros2_packages / name
    depends = {d.name for d in _parse_package(folder).exec_depends}
    files = sorted((folder / "launch").glob("*.launch.py"))
    assert [f.name for f in files] == ["display.launch.py", "gazebo.launch.py"]
    for f in files:
        py_compile.compile(str(f), doraise=True)
        started = _launch_packages(f) - {name}
        assert started <= depends, f"{f.name} uses {sorted(started - depends)}, not exec_depends"
    display = _launch_packages(folder / "launch" / "display.launch.py")
    assert {"robot_state_publisher", "joint_state_publisher", "joint_state_publisher_gui", "rviz2"} <= display


@pytest.mark.slow
@pytest.mark.parametrize("name", EXAMPLES)
def test_cmakelists_installs_every_folder(ros2_packages, ros1_small, name):
    for folder in [ros2_packages / name] + ([ros1_small / name] if (ros1_small / name).is_dir() else []):
        cmake = (folder / "CMakeLists.txt").read_text()
        dirs = {p.name for p in folder.iterdir() if p.is_dir()} - {"hooks", "env-hooks"}
        assert _installed_folders(cmake) == dirs
        assert "install(FILES model.sdf model.config" in cmake


@pytest.mark.slow
def test_ros2_rover_sensors_in_rviz_and_bridge(ros2_packages):
    folder = ros2_packages / "rover"
    rviz = yaml.safe_load((folder / "rviz" / "rover.rviz").read_text())
    manager = rviz["Visualization Manager"]
    assert manager["Global Options"]["Fixed Frame"] == "base_link"
    shown = {d["Class"]: d for d in manager["Displays"]}
    assert shown["rviz_default_plugins/RobotModel"]["Description Topic"]["Value"] == "/robot_description"
    topics = sorted(d["Topic"]["Value"] for d in manager["Displays"] if "Topic" in d)
    # Gazebo Sim writes the sonar as a gpu_lidar cone: a LaserScan
    assert topics == ["/camera/color", "/camera/depth", "/scan", "/sonar"]
    launch = (folder / "launch" / "gazebo.launch.py").read_text()
    bridge = ast.literal_eval(re.search(r"^BRIDGE = (.*)$", launch, re.M).group(1))
    assert bridge[0] == "/clock@rosgraph_msgs/msg/Clock[gz.msgs.Clock"
    assert "/scan@sensor_msgs/msg/LaserScan[gz.msgs.LaserScan" in bridge
    assert "/imu@sensor_msgs/msg/Imu[gz.msgs.IMU" in bridge
    controllers = yaml.safe_load((folder / "config" / "controllers.yaml").read_text())
    spawned = ast.literal_eval(re.search(r"^CONTROLLERS = (.*?)  #", launch, re.M).group(1))
    assert spawned == [k for k in controllers["controller_manager"]["ros__parameters"] if k != "update_rate"]
    urdf = ET.parse(folder / "urdf" / "rover.urdf").getroot()
    assert urdf.findtext("gazebo/plugin/parameters") == "$(find rover)/config/controllers.yaml"
    hook = (folder / "hooks" / "rover.dsv.in").read_text()
    assert hook == ("prepend-non-duplicate;GZ_SIM_RESOURCE_PATH;share\n"
                    "prepend-non-duplicate;IGN_GAZEBO_RESOURCE_PATH;share\n")


# ---------------------------------------------------------------- ROS 1 files


@pytest.mark.slow
def test_ros1_launch_files_use_only_exec_depends(ros1_small):
    for name in ("turret_bot", "rover"):
        folder = ros1_small / name
        pkg = _parse_package(folder)
        assert [d.name for d in pkg.buildtool_depends] == ["catkin"]
        depends = {d.name for d in pkg.exec_depends}
        for f in ("display.launch", "gazebo.launch"):
            text = (folder / "launch" / f).read_text()
            root = ET.fromstring(text)
            used = {n.get("pkg") for n in root.iter("node")} | set(re.findall(r"\$\(find (\w+)\)", text))
            assert used - {name} <= depends, (f, sorted(used - {name} - depends))
    rover = ET.parse(ros1_small / "rover" / "urdf" / "rover.urdf").getroot()
    plugins = {s.get("name"): s.find("plugin").get("filename") for s in rover.iter("sensor")}
    assert plugins["scan"] == "libgazebo_ros_laser.so" and plugins["sonar"] == "libgazebo_ros_range.so"
    assert plugins["camera_depth"] == "libgazebo_ros_openni_kinect.so"


@pytest.mark.slow
@pytest.mark.parametrize("rel", ["package.xml", "CMakeLists.txt", "launch/display.launch", "launch/gazebo.launch",
                                 "rviz/turret_bot.rviz", "env-hooks/50.turret_bot.sh.in"])
def test_golden_ros1(ros1_small, rel):
    assert_golden(ros1_small / "turret_bot" / rel, GOLDEN / "turret_bot" / rel)


@pytest.mark.slow
@pytest.mark.parametrize("rel", ["package.xml", "CMakeLists.txt", "launch/display.launch.py",
                                 "launch/gazebo.launch.py", "rviz/rover.rviz", "hooks/rover.dsv.in"])
def test_golden_ros2(ros2_packages, rel):
    assert_golden(ros2_packages / "rover" / rel, GOLDEN / "rover" / rel)


# ---------------------------------------------------------------- metadata, worlds, bad input

BOX = "robot: {name}\nlinks:\n  base: {{visual: {{box: {{size: [0.2, 0.2, 0.1]}}}}}}\n"


@pytest.mark.slow
def test_metadata_fills_package_xml(tmp_path):
    recipe = write_recipe(tmp_path, BOX.format(name="meta") + textwrap.dedent("""
    metadata:
      version: "2.3"
      description: A box.
      authors:
        - {name: Ada, email: ada@example.org}
        - {name: Bob}
      license: BSD-3-Clause
      urls: {website: "https://example.org/meta", bugtracker: "https://example.org/meta/issues"}
    """))
    proc = run_cli("build", recipe, "--out", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    pkg = _parse_package(tmp_path / "out" / "meta")
    assert pkg.version == "2.3.0" and pkg.description == "A box."
    assert [(m.name, m.email) for m in pkg.maintainers] == [("Ada", "ada@example.org")]
    assert [(a.name, a.email) for a in pkg.authors] == [("Ada", "ada@example.org"), ("Bob", None)]
    assert [lic for lic in pkg.licenses] == ["BSD-3-Clause"]
    assert [(u.type, u.url) for u in pkg.urls] == [("website", "https://example.org/meta"),
                                                    ("bugtracker", "https://example.org/meta/issues")]


@pytest.mark.slow
def test_no_maintainer_is_a_warning_not_an_invented_address(tmp_path):
    recipe = write_recipe(tmp_path, BOX.format(name="anon") + "metadata: {authors: [{name: Bob}], license: MIT}\n")
    proc = run_cli("build", recipe.name, "--out", tmp_path / "out", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    line = recipe.read_text().splitlines().index("metadata: {authors: [{name: Bob}], license: MIT}") + 1
    assert (f"robot.yaml:{line}: metadata.maintainers: warning: anon: ROS package: no maintainer: package.xml names "
            "none, and catkin and colcon refuse a package without one (give metadata.maintainers, or an author with "
            "an email)") in proc.stderr.splitlines()
    text = (tmp_path / "out" / "anon" / "package.xml").read_text()
    assert "<maintainer" not in text and "example.com" not in text


@pytest.mark.slow
def test_world_goes_into_the_package(tmp_path, assets):
    shutil.copytree(assets / "maps" / "turtlebot3_world", tmp_path / "maps" / "room")
    map_yaml = "maps/room/map.yaml"
    recipe = write_recipe(tmp_path, BOX.format(name="walker") + textwrap.dedent(f"""
    ros: ros1
    worlds:
      room: {{map: {map_yaml}, height: 0.5, spawn: {{xyz: [1, 2, 0], rpy: [0, 0, 1.5]}}}}
    """))
    proc = run_cli("build", recipe, "--out", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    pkg = tmp_path / "out" / "walker"
    assert (pkg / "worlds" / "room" / "room.world").is_file()
    assert (pkg / "worlds" / "room" / "meshes" / "room.stl").is_file()
    # the package's copy leaves the robot out: launch/gazebo spawns it, at the world's spawn pose
    assert "<include>" not in (pkg / "worlds" / "room" / "room.world").read_text()
    assert "<include>" in (tmp_path / "out" / "room" / "room.world").read_text()
    assert "worlds" in _installed_folders((pkg / "CMakeLists.txt").read_text())
    launch = ET.parse(pkg / "launch" / "gazebo.launch").getroot()
    args = {a.get("name"): a.get("default") for a in launch.findall("arg")}
    assert (args["world"], args["x"], args["y"], args["yaw"]) == ("room", "1", "2", "1.5")
    hook = (pkg / "env-hooks" / "50.walker.sh.in").read_text()
    assert '"$_walker_models/walker/worlds"' in hook


@pytest.mark.slow
@pytest.mark.parametrize("extra, args, line", [
    ("ros: ros1\ngazebo: sim\n", [],
     "robot.yaml:5: gazebo: ROS 1 has no Gazebo Sim plugins (gz_ros2_control, ros_gz): use gazebo: classic, "
     "or ros: ros2"),
    ("gazebo: sim\n", ["--ros", "ros1"],
     "robot.yaml:4: gazebo: ROS 1 has no Gazebo Sim plugins (gz_ros2_control, ros_gz): use gazebo: classic, "
     "or ros: ros2"),
    ("ros_control: ros1\n", [], "robot.yaml:4: ros_control: renamed to 'ros' (same values)"),
    ("ros: noetic\n", [], "robot.yaml:4: ros: must be one of 'ros2' or 'ros1' (got 'noetic')"),
    ("metadata: {maintainers: [{name: X, email: nobody}]}\n", [],
     "robot.yaml:4: metadata.maintainers[0].email: not an e-mail address: 'nobody'"),
    ("metadata: {version: v1}\n", [],
     "robot.yaml:4: metadata.version: version must be X, X.Y or X.Y.Z with whole numbers (got 'v1')"),
])
def test_bad_ros_input(tmp_path, extra, args, line):
    recipe = write_recipe(tmp_path, BOX.format(name="bad") + extra)
    proc = run_cli("build", recipe, "--out", tmp_path / "out", *args, cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == [line]
    assert not (tmp_path / "out" / "bad").exists()


def test_rviz_view_fits_the_robot(tmp_path):
    """A 2 m cube raised 1 m: RViz looks at its centre from where its bounding sphere (radius
    sqrt(3)) fills 80 % of the 45-degree view: sqrt(3) / sin(22.5 deg) / 0.8 = 5.658 m."""
    from robotkit.pipeline.runner import build

    recipe = write_recipe(tmp_path, "robot: cube\nlinks:\n  base: {visual: {box: {size: [2, 2, 2]}, "
                                    "origin: {xyz: [0, 0, 1]}}}\n")
    build([recipe], tmp_path / "out")
    rviz = yaml.safe_load((tmp_path / "out" / "cube" / "rviz" / "cube.rviz").read_text())
    view = rviz["Visualization Manager"]["Views"]["Current"]
    assert view["Distance"] == 5.66
    assert view["Focal Point"] == {"X": 0.0, "Y": 0.0, "Z": 1.0}
    assert rviz["Visualization Manager"]["Global Options"]["Fixed Frame"] == "base"
