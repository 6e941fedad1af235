"""The examples' ROS 1 packages with the real ROS 1 of Debian 12: one catkin workspace holding all
of them, `catkin_make install`, the install space sourced, `roslaunch <robot> display.launch
gui:=false` under Xvfb, read back with rospy and tf2 (tests/ros1_probe.py), and RViz's
output and a screenshot of it."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from conftest import ASSETS, RECIPES
from validators import require

pytestmark = [pytest.mark.ros, pytest.mark.slow]

EXAMPLES = ["turret_bot", "lidar_mast", "rover", "turtlebot3_burger", "ur5"]
# a Menagerie model imported from MJCF (robotkit import), built into the same workspace
IMPORTED = {"so_arm100": ASSETS / "menagerie" / "trs_so_arm100" / "so_arm100.xml"}
ROBOTS = EXAMPLES + list(IMPORTED)
PROBE = Path(__file__).resolve().parents[1] / "ros1_probe.py"
# Debian's ROS 1 (docs/libraries.md, section 10): these three, and /usr/bin before any pyenv python3
ROS_ENV = {"ROS_VERSION": "1", "ROS_DISTRO": "Debian", "ROS_PYTHON_VERSION": "3"}
SCREENSHOT = "turret_bot"  # the robot whose RViz window is photographed
LAUNCH_TIMEOUT = 60  # seconds for one robot: RViz up, every transform read


def _env(**extra) -> dict:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "CMAKE_PREFIX", "PYTHONPATH"))}
    env.update(ROS_ENV, PATH="/usr/bin:/bin:" + env.get("PATH", ""), **extra)
    return env


def _sourced(ws: Path, command: str, *argv: str) -> subprocess.CompletedProcess:
    """``command`` (bash; its arguments "$@" = ``argv``) with the workspace's install space sourced."""
    return subprocess.run(["bash", "-c", f'source "{ws}/install/setup.bash" && {command}', "bash", *argv],
                          capture_output=True, text=True, env=_env())


@pytest.fixture(scope="session")
def recipes(tmp_path_factory) -> dict[str, Path]:
    """Each robot's recipe: the examples', and the imported models' (written by robotkit import)."""
    from robotkit.importer import import_mjcf

    out = {name: RECIPES / f"{name}.yaml" for name in EXAMPLES}
    folder = tmp_path_factory.mktemp("ros1-imported")
    for name, mjcf in IMPORTED.items():
        if not mjcf.is_file():
            pytest.fail(f"test assets not found at {mjcf} (CI clones the repository next to shared/)")
        recipe = folder / f"{name}.yaml"
        import_mjcf(mjcf, recipe)
        # an MJCF names no maintainer, which catkin requires (the build warns): given as a user would,
        # in the recipe's metadata (the import's holds the ledger)
        given = "  license: Apache-2.0\n  maintainers: [{name: robotkit tests, email: robotkit-tests@example.com}]\n"
        text = recipe.read_text(encoding="utf-8")
        text = (text.replace("\nmetadata:\n", "\nmetadata:\n" + given, 1) if "\nmetadata:\n" in text
                else text + "metadata:\n" + given)
        recipe.write_text(text, encoding="utf-8")
        out[name] = recipe
    return out


@pytest.fixture(scope="session")
def ros1_packages(recipes, tmp_path_factory) -> Path:
    from robotkit.pipeline.runner import build

    out = tmp_path_factory.mktemp("ros1-build")
    # one process: a doit worker forked from the test process, which holds other libraries'
    # threads (Drake, rendering), could deadlock; the session's mesh cache makes this quick
    build([recipes[name] for name in ROBOTS], out, ros="ros1")
    return out


@pytest.fixture(scope="session")
def catkin_ws(ros1_packages, tmp_path_factory) -> Path:
    for tool in ("catkin_make", "roslaunch", "rviz", "Xvfb"):
        require(tool)
    ws = tmp_path_factory.mktemp("catkin_ws")
    for name in ROBOTS:
        shutil.copytree(ros1_packages / name, ws / "src" / name)
    proc = subprocess.run(["catkin_make", "-C", str(ws), "install"], cwd=ws, capture_output=True, text=True, env=_env())
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return ws


@pytest.fixture(scope="session")
def display(tmp_path_factory):
    """An Xvfb server on a free display number (-displayfd), stopped at the end."""
    require("Xvfb")
    r, w = os.pipe()
    proc = subprocess.Popen(["Xvfb", "-displayfd", str(w), "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                            pass_fds=(w,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(w)
    with os.fdopen(r) as f:
        number = f.readline().strip()
    yield f":{number}"
    proc.terminate()
    proc.wait(10)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _children(pid: int) -> list[int]:
    """Every descendant of ``pid`` (roslaunch starts each node in its own session)."""
    parents: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        parents.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    out, todo = [], [pid]
    while todo:
        for child in parents.get(todo.pop(), []):
            out.append(child)
            todo.append(child)
    return out


def _stop(proc: subprocess.Popen):
    """SIGINT to roslaunch (it stops its nodes); then any node left, by pid."""
    pids = _children(proc.pid)
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(20)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


def _links(urdf: Path) -> tuple[str, list[str]]:
    root = ET.parse(urdf).getroot()
    links = [link.get("name") for link in root.findall("link")]
    children = {j.find("child").get("link") for j in root.findall("joint")}
    return next(n for n in links if n not in children), links


def _screenshot(display: str, path: Path):
    from PIL import ImageGrab

    image = ImageGrab.grab(xdisplay=display)
    image.save(path)
    return image


_RUNS: dict[str, dict] = {}


def launched(name: str, ws: Path, display: str, tmp: Path) -> dict:
    """roslaunch NAME display.launch gui:=false, read back; cached per robot for the session."""
    if name in _RUNS:
        return _RUNS[name]
    urdf = ws / "install" / "share" / name / "urdf" / f"{name}.urdf"
    root, links = _links(urdf)
    port = _free_port()
    logs = tmp / f"{name}-logs"
    env = _env(DISPLAY=display, ROS_MASTER_URI=f"http://localhost:{port}", ROS_LOG_DIR=str(logs),
               ROS_HOME=str(tmp / "ros_home"), XDG_RUNTIME_DIR=str(tmp))
    out_file = (tmp / f"{name}-roslaunch.txt").open("w")
    proc = subprocess.Popen(["bash", "-c", f'source "{ws}/install/setup.bash" && exec roslaunch -p {port} '
                                           f'{name} display.launch gui:=false'],
                            stdout=out_file, stderr=subprocess.STDOUT, env=env)
    try:
        probe = subprocess.run(["bash", "-c", f'source "{ws}/install/setup.bash" && exec /usr/bin/python3 '
                                              f'"{PROBE}" {root} {" ".join(links)}'],
                               capture_output=True, text=True, env=env, timeout=LAUNCH_TIMEOUT)
        assert probe.returncode == 0, probe.stderr[-3000:]
        result = json.loads(probe.stdout.strip().splitlines()[-1])
        # RViz draws the robot once it has the description and the transforms: wait for a frame
        # that stops changing, then keep it (one robot is enough: test_rviz_shows_the_robot)
        shot, previous = tmp / f"{name}.png", None
        deadline = time.monotonic() + (20 if name == SCREENSHOT else 0)
        while time.monotonic() < deadline:
            time.sleep(1.5)
            image = _screenshot(display, shot)
            if previous is not None and image.tobytes() == previous:
                break
            previous = image.tobytes()
        result["alive"] = proc.poll() is None
    finally:
        _stop(proc)
        out_file.close()
    output = (tmp / f"{name}-roslaunch.txt").read_text(errors="replace")
    for log in sorted(logs.rglob("*.log")):
        output += log.read_text(errors="replace")
    result.update(root=root, links=links, urdf=urdf.read_text(encoding="utf-8"), output=output, screenshot=shot)
    _RUNS[name] = result
    return result


@pytest.fixture
def run(catkin_ws, display, tmp_path_factory):
    tmp = tmp_path_factory.getbasetemp() / "roslaunch"
    tmp.mkdir(exist_ok=True)
    return lambda name: launched(name, catkin_ws, display, tmp)


def test_install_space_holds_the_packages(catkin_ws):
    for name in ROBOTS:
        share = catkin_ws / "install" / "share" / name
        for rel in ("package.xml", f"urdf/{name}.urdf", "model.sdf", "model.config", f"mjcf/{name}.xml",
                    "launch/display.launch", "launch/gazebo.launch", f"rviz/{name}.rviz", "meshes"):
            assert (share / rel).exists(), f"{name}: {rel} is not installed"
    assert (catkin_ws / "install/share/turret_bot/config/controllers.yaml").is_file()
    proc = _sourced(catkin_ws, 'rospack find ur5 && echo "$GAZEBO_MODEL_PATH"')
    assert proc.returncode == 0, proc.stderr
    where, model_path = proc.stdout.split()
    assert where == str(catkin_ws / "install" / "share" / "ur5")
    # the env hooks put the models on Gazebo's path, once however many packages add it
    assert model_path.split(":")[0] == str(catkin_ws / "install" / "share")
    assert model_path.split(":").count(str(catkin_ws / "install" / "share")) == 1


@pytest.mark.parametrize("name", ROBOTS)
def test_display_launch(run, recipes, name):
    from robotkit.emit.ros import link_poses
    from robotkit.model.resolve import resolve
    from robotkit.recipe.load import load_recipe

    r = run(name)
    assert r["alive"], f"roslaunch stopped early:\n{r['output'][-3000:]}"
    assert r["description"] == r["urdf"]
    movable = {j.get("name") for j in ET.fromstring(r["urdf"]).findall("joint")
               if j.get("type") not in ("fixed", "floating") and j.find("mimic") is None}
    assert movable <= set(r["joint_states"]), movable - set(r["joint_states"])
    assert set(r["tf"]) == set(r["links"])
    # robot_state_publisher's transforms are robotkit's kinematics, at the published joint values
    from scipy.spatial.transform import Rotation

    robot = resolve(load_recipe(recipes[name]), "ros1")
    # joint_state_publisher starts at the recipe's home pose (its private ~zeros), the other joints at 0
    home = dict(robot.home().values) if robot.home() is not None else {}
    for joint in movable:
        assert r["joint_states"][joint] == pytest.approx(home.get(joint, 0.0), abs=1e-9), joint
    for link, T in link_poses(robot, r["joint_states"]).items():
        np.testing.assert_allclose(r["tf"][link][:3], T[:3, 3], atol=1e-6, err_msg=link)
        R = Rotation.from_quat(r["tf"][link][3:]).as_matrix()
        np.testing.assert_allclose(R, T[:3, :3], atol=1e-6, err_msg=link)
    assert "Could not load resource" not in r["output"], r["output"][-3000:]
    assert "[rviz-" in r["output"]


def test_rviz_shows_the_robot(run):
    """turret_bot is red, green and blue: RViz drew all three (the empty scene is grey)."""
    image = np.asarray(_load(run(SCREENSHOT)["screenshot"]))[..., :3].astype(int)
    red = (image[..., 0] > 100) & (image[..., 1] < 50) & (image[..., 2] < 50)
    green = (image[..., 1] > 100) & (image[..., 0] < 50) & (image[..., 2] < 50)
    blue = (image[..., 2] > 100) & (image[..., 0] < 50) & (image[..., 1] < 50)
    counts = [int(m.sum()) for m in (red, green, blue)]
    assert min(counts) > 2000, f"red, green, blue pixels: {counts}"


def _load(path: Path):
    from PIL import Image

    return Image.open(path)


def test_gazebo_launch_world_argument_resolves(catkin_ws):
    """Gazebo is not in Debian 12, so gazebo.launch is not launched; its world choice is a roslaunch
    $(eval), resolved here by roslaunch's own substitution code."""
    launch = ET.parse(catkin_ws / "install/share/turret_bot/launch/gazebo.launch").getroot()
    value = launch.find("include/arg[@name='world_name']").get("value")
    script = ("import sys; from roslaunch.substitution_args import resolve_args; "
              f"print(resolve_args({value!r}, context={{'arg': {{'world': sys.argv[1]}}}}))")
    for world, expected in (("empty", "worlds/empty.world"),
                            ("room", f"{catkin_ws}/install/share/turret_bot/worlds/room/room.world")):
        proc = _sourced(catkin_ws, '/usr/bin/python3 -c "$1" "$2"', script, world)
        assert proc.returncode == 0, proc.stderr
        assert proc.stdout.strip() == expected
