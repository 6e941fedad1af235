"""The ROS 1 packages of the examples and of every imported shared model with the real ROS 1 of
Debian 12: one catkin workspace holding all of them, one `catkin_make install`, the install space
sourced, `roslaunch <robot> display.launch gui:=false` under Xvfb (several robots at once, each
with its own ROS master, their RViz windows on one display), read back with rospy and tf2
(tests/ros1_probe.py), and RViz's output and a screenshot of it.

The imported models (issue 30's acceptance: "its ROS package passes the ROS 1 launch test") are
the 21 entry files of ../shared/assets/menagerie (scene*.xml left out) and the 15 model folders of
../shared/assets/gazebo_models, each `robotkit import` (without its verification: the importer's
own tests verify) then built with the examples.  Tree-shaped means no loop closure on the import's
ledger; four are not, their connect equalities dropped for every format (LOOPED): Cassie's four
achilles-rod and plantar-rod loops, the Robotiq 2F-85's two four-bar linkages, and the same
gripper's two on the UFactory xArm7 and its hand alone.  Their URDF is the tree the loops leave
(robotkit writes no URDF loop), a package a user gets and launches as any other: they are launched
too, and their transforms are robotkit's kinematics of that tree.  Two shared files name the same
model as another (barkour_vb_mjx.xml the model barkour_vb, tiago_motor.xml tiago): one workspace
holds one package of a name, so each is renamed after its file in its recipe, as a user would."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import time
from dataclasses import replace
import xml.etree.ElementTree as ET
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from conftest import ASSETS, RECIPES
from validators import require

pytestmark = [pytest.mark.ros, pytest.mark.slow]

EXAMPLES = ["turret_bot", "lidar_mast", "rover", "turtlebot3_burger", "ur5"]
MENAGERIE, GAZEBO = ASSETS / "menagerie", ASSETS / "gazebo_models"
# the shared models, imported (robotkit import) and built into the same workspace: each by its
# path under ASSETS (the test's id), its package named as the import names the robot
IMPORTED = ([f"menagerie/{p.relative_to(MENAGERIE).as_posix()}" for p in sorted(MENAGERIE.glob("*/*.xml"))
             if not p.name.startswith("scene")]
            + [f"gazebo_models/{p.name}" for p in sorted(GAZEBO.iterdir()) if (p / "model.config").is_file()]
            if MENAGERIE.is_dir() and GAZEBO.is_dir() else [])
LOOPED = ["menagerie/agility_cassie/cassie.xml", "menagerie/robotiq_2f85/2f85.xml", "menagerie/ufactory_xarm7/hand.xml",
          "menagerie/ufactory_xarm7/xarm7.xml"]
"""The imported models that are not tree-shaped: a loop closure on the import's ledger."""
LOOP_CLOSURES = ("equality connect", "equality weld", "closes a loop")
"""How the MJCF and SDF imports' ledgers name a dropped loop closure."""
ROBOTS = EXAMPLES + IMPORTED
PROBE = Path(__file__).resolve().parents[1] / "ros1_probe.py"
# Debian's ROS 1 (docs/libraries.md, section 10): these three, and /usr/bin before any pyenv python3
ROS_ENV = {"ROS_VERSION": "1", "ROS_DISTRO": "Debian", "ROS_PYTHON_VERSION": "3"}
SCREENSHOT = "turret_bot"  # the robot whose RViz window is photographed (launched alone: one window on the display)
LAUNCH_TIMEOUT = 90  # seconds for one robot: RViz up, every transform read (with others launching beside it)
AT_ONCE = 3  # robots launched at once (2 cores: roslaunch, RViz and the probe are mostly waiting)
MAINTAINER = "  license: Apache-2.0\n  maintainers: [{name: robotkit tests, email: robotkit-tests@example.com}]\n"
"""Given in an imported recipe's metadata, as a user would: an MJCF or SDF names no maintainer,
which catkin requires (the build warns), and no licence."""


def _env(**extra) -> dict:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "CMAKE_PREFIX", "PYTHONPATH"))}
    env.update(ROS_ENV, PATH="/usr/bin:/bin:" + env.get("PATH", ""), **extra)
    return env


def _sourced(ws: Path, command: str, *argv: str) -> subprocess.CompletedProcess:
    """``command`` (bash; its arguments "$@" = ``argv``) with the workspace's install space sourced."""
    return subprocess.run(["bash", "-c", f'source "{ws}/install/setup.bash" && {command}', "bash", *argv],
                          capture_output=True, text=True, env=_env())


def _given(recipe: Path, robot: str | None = None):
    """An imported recipe as a user completes it for catkin: MAINTAINER in its metadata (the
    import's holds the ledger), and its robot (so its package) named ``robot`` if given."""
    text = recipe.read_text(encoding="utf-8")
    text = (text.replace("\nmetadata:\n", "\nmetadata:\n" + MAINTAINER, 1) if "\nmetadata:\n" in text
            else text + "metadata:\n" + MAINTAINER)
    if robot is not None:
        lines = text.splitlines(keepends=True)
        at = next(i for i, line in enumerate(lines) if line.startswith("robot: "))
        lines[at] = f"robot: {robot}\n"
        text = "".join(lines)
    recipe.write_text(text, encoding="utf-8")


@pytest.fixture(scope="session")
def imports(tmp_path_factory) -> dict[str, object]:
    """Each shared model imported (robotkit import, no verification), by its id in IMPORTED; its
    recipe completed by :func:`_given`, renamed after its file if another took its name."""
    from robotkit.importer import import_mjcf, import_sdf
    from robotkit.importer.names import package_name

    if not IMPORTED:
        pytest.fail(f"test assets not found at {ASSETS} (CI clones the repository next to shared/)")
    folder = tmp_path_factory.mktemp("ros1-imported")
    out, taken = {}, set(EXAMPLES)
    for model in IMPORTED:
        source = ASSETS / model
        imported = (import_sdf if source.is_dir() else import_mjcf)(source, folder / f"{model.replace('/', '-')}.yaml")
        name = imported.robot if imported.robot not in taken else package_name(source.stem)
        assert name not in taken, f"{model}: package name {name} is taken"
        taken.add(name)
        _given(imported.recipe_path, None if name == imported.robot else name)
        out[model] = replace(imported, robot=name)
    return out


@pytest.fixture(scope="session")
def recipes(imports) -> dict[str, Path]:
    """Each robot's recipe, by its id in ROBOTS: the examples', and the imported models'."""
    return {**{name: RECIPES / f"{name}.yaml" for name in EXAMPLES},
            **{model: imported.recipe_path for model, imported in imports.items()}}


@pytest.fixture(scope="session")
def packages(imports) -> dict[str, str]:
    """Each robot's ROS package name, by its id in ROBOTS."""
    return {**{name: name for name in EXAMPLES}, **{model: imported.robot for model, imported in imports.items()}}


@pytest.fixture(scope="session")
def wanted(request) -> set[str]:
    """The robots (ids in ROBOTS) this session's tests of this module read: all of them, or with
    ``-k`` those of the launch tests chosen (and SCREENSHOT for RViz's picture)."""
    mine = [item for item in request.session.items if item.path == Path(__file__)]
    if any(item.originalname not in ("test_display_launch", "test_rviz_shows_the_robot") for item in mine):
        return set(ROBOTS)
    return {item.callspec.params["name"] if item.originalname == "test_display_launch" else SCREENSHOT
            for item in mine}


@pytest.fixture(scope="session")
def ros1_packages(wanted, recipes, tmp_path_factory) -> Path:
    from robotkit.pipeline.runner import build

    out = tmp_path_factory.mktemp("ros1-build")
    # one process: a doit worker forked from the test process, which holds other libraries'
    # threads (Drake, rendering), could deadlock; the session's mesh cache makes this quick
    build([recipes[name] for name in ROBOTS if name in wanted], out, ros="ros1")
    return out


@pytest.fixture(scope="session")
def catkin_ws(wanted, ros1_packages, packages, tmp_path_factory) -> Path:
    for tool in ("catkin_make", "roslaunch", "rviz", "Xvfb"):
        require(tool)
    ws = tmp_path_factory.mktemp("catkin_ws")
    for name in sorted(wanted):
        shutil.copytree(ros1_packages / packages[name], ws / "src" / packages[name])
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


def launched(name: str, ws: Path, display: str, tmp: Path) -> dict:
    """roslaunch NAME display.launch gui:=false (NAME a package), read back; what went wrong, if
    anything, under "error" (a robot's failure is its test's, not the others')."""
    urdf = ws / "install" / "share" / name / "urdf" / f"{name}.urdf"
    root, links = _links(urdf)
    port = _free_port()
    logs = tmp / f"{name}-logs"
    env = _env(DISPLAY=display, ROS_MASTER_URI=f"http://localhost:{port}", ROS_LOG_DIR=str(logs),
               ROS_HOME=str(tmp / f"{name}-ros_home"), XDG_RUNTIME_DIR=str(tmp))
    out_file = (tmp / f"{name}-roslaunch.txt").open("w")
    proc = subprocess.Popen(["bash", "-c", f'source "{ws}/install/setup.bash" && exec roslaunch -p {port} '
                                           f'{name} display.launch gui:=false'],
                            stdout=out_file, stderr=subprocess.STDOUT, env=env)
    result: dict = {}
    try:
        probe = subprocess.run(["bash", "-c", f'source "{ws}/install/setup.bash" && exec /usr/bin/python3 '
                                              f'"{PROBE}" {root} {" ".join(links)}'],
                               capture_output=True, text=True, env=env, timeout=LAUNCH_TIMEOUT)
        if probe.returncode == 0:
            result = json.loads(probe.stdout.strip().splitlines()[-1])
        else:
            result["error"] = f"the probe failed:\n{probe.stderr[-3000:]}"
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
    except subprocess.TimeoutExpired:
        result["error"] = f"no transforms within {LAUNCH_TIMEOUT} s"
    finally:
        _stop(proc)
        out_file.close()
    output = (tmp / f"{name}-roslaunch.txt").read_text(errors="replace")
    for log in sorted(logs.rglob("*.log")):
        output += log.read_text(errors="replace")
    result.update(root=root, links=links, urdf=urdf.read_text(encoding="utf-8"), output=output, screenshot=shot)
    return result


@pytest.fixture(scope="session")
def launches(wanted, catkin_ws, display, packages, tmp_path_factory) -> dict[str, dict]:
    """Every robot this session's tests read, launched, by its id in ROBOTS: SCREENSHOT first and
    alone (RViz's window photographed, no other on the display), then the others AT_ONCE at a time."""
    tmp = tmp_path_factory.mktemp("roslaunch")
    run = lambda name: launched(packages[name], catkin_ws, display, tmp)  # noqa: E731
    out = {SCREENSHOT: run(SCREENSHOT)} if SCREENSHOT in wanted else {}
    rest = [name for name in ROBOTS if name in wanted and name not in out]
    with ThreadPoolExecutor(AT_ONCE) as pool:
        out.update(zip(rest, pool.map(run, rest)))
    return out


def test_install_space_holds_the_packages(catkin_ws, packages):
    for name in map(packages.get, ROBOTS):
        share = catkin_ws / "install" / "share" / name
        for rel in ("package.xml", f"urdf/{name}.urdf", "model.sdf", "model.config", f"mjcf/{name}.xml",
                    "launch/display.launch", "launch/gazebo.launch", f"rviz/{name}.rviz"):
            assert (share / rel).exists(), f"{name}: {rel} is not installed"
        # meshes/ when the robot has meshes (eight Gazebo models are shapes only)
        meshes = f"package://{name}/meshes/" in (share / f"urdf/{name}.urdf").read_text(encoding="utf-8")
        assert (share / "meshes").is_dir() == meshes, name
    assert (catkin_ws / "install/share/turret_bot/config/controllers.yaml").is_file()
    proc = _sourced(catkin_ws, 'rospack find ur5 && echo "$GAZEBO_MODEL_PATH"')
    assert proc.returncode == 0, proc.stderr
    where, model_path = proc.stdout.split()
    assert where == str(catkin_ws / "install" / "share" / "ur5")
    # the env hooks put the models on Gazebo's path, once however many packages add it
    assert model_path.split(":")[0] == str(catkin_ws / "install" / "share")
    assert model_path.split(":").count(str(catkin_ws / "install" / "share")) == 1


def test_the_models_not_tree_shaped_are_the_ones_whose_import_drops_a_loop(imports):
    assert len(IMPORTED) == 36  # 21 Menagerie entry files, 15 Gazebo model folders
    assert [model for model, imported in imports.items()
            if any(kind in line for line in imported.ledger for kind in LOOP_CLOSURES)] == LOOPED


@pytest.mark.parametrize("name", ROBOTS)
def test_display_launch(launches, recipes, name):
    from robotkit.emit.ros import link_poses
    from robotkit.model.resolve import resolve
    from robotkit.recipe.load import load_recipe

    r = launches[name]
    assert "error" not in r, f"{r.get('error')}\n{r['output'][-3000:]}"
    assert r["alive"], f"roslaunch stopped early:\n{r['output'][-3000:]}"
    assert r["description"] == r["urdf"]
    movable = {j.get("name") for j in ET.fromstring(r["urdf"]).findall("joint")
               if j.get("type") not in ("fixed", "floating") and j.find("mimic") is None}
    assert movable <= set(r["joint_states"]), movable - set(r["joint_states"])
    assert set(r["tf"]) == set(r["links"])
    # robot_state_publisher's transforms are robotkit's kinematics, at the published joint values
    from scipy.spatial.transform import Rotation

    robot = resolve(load_recipe(recipes[name]), "ros1")
    home = dict(robot.home().values) if robot.home() is not None else {}
    for joint in ET.fromstring(r["urdf"]).findall("joint"):
        if joint.get("name") in movable:
            assert r["joint_states"][joint.get("name")] == pytest.approx(_start(joint, home), abs=1e-9), joint.get("name")
    for link, T in link_poses(robot, r["joint_states"]).items():
        np.testing.assert_allclose(r["tf"][link][:3], T[:3, 3], atol=1e-6, err_msg=link)
        R = Rotation.from_quat(r["tf"][link][3:]).as_matrix()
        np.testing.assert_allclose(R, T[:3, :3], atol=1e-6, err_msg=link)
    assert "Could not load resource" not in r["output"], r["output"][-3000:]
    assert "[rviz-" in r["output"]
    # no node logged an error (roscpp's "[ERROR] [time]: ..."; RViz, robot_state_publisher)
    assert not [line for line in r["output"].splitlines() if "[ERROR] [" in line], r["output"][-3000:]


def _start(joint: ET.Element, home: dict) -> float:
    """Where joint_state_publisher starts a joint (its own rule): the recipe's home pose (its private
    ~zeros) unless 0, else 0 if within the limits, else their middle (the Allegro hands' thumb
    base: 0.263 to 1.396 rad), the limits narrowed by a <safety_controller>'s soft ones."""
    if home.get(joint.get("name")):
        return home[joint.get("name")]
    limit, soft = joint.find("limit"), joint.find("safety_controller")
    if joint.get("type") == "continuous" or limit is None:
        return 0.0
    lower, upper = float(limit.get("lower", 0)), float(limit.get("upper", 0))
    if soft is not None:
        lower = max(lower, float(soft.get("soft_lower_limit", lower)))
        upper = min(upper, float(soft.get("soft_upper_limit", upper)))
    return (lower + upper) / 2 if lower > 0 or upper < 0 else 0.0


def test_rviz_shows_the_robot(launches):
    """turret_bot is red, green and blue: RViz drew all three (the empty scene is grey)."""
    image = np.asarray(_load(launches[SCREENSHOT]["screenshot"]))[..., :3].astype(int)
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
