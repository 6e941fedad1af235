"""The picture report: equivalent inertia boxes against known answers, report.html against a
golden file, the build's report task (no-op rebuilds do not re-render), known defects named
in the table and visible in the pictures, and the page in a real browser (Chromium)."""

from __future__ import annotations

import re
import shutil

import numpy as np
import pytest
import trimesh
from markupsafe import escape
from PIL import Image

from conftest import GOLDEN, RECIPES, assert_golden, run_cli, write_recipe
from robotkit.picture.render import STRIP_SIZE
from robotkit.pipeline.runner import build

CHROMIUM_ARGS = ["--no-sandbox", "--headless", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run"]


def chromium(playwright):
    """Debian's Chromium driven by Playwright (never a downloaded browser)."""
    return playwright.chromium.launch(executable_path=shutil.which("chromium") or "/usr/bin/chromium",
                                      args=CHROMIUM_ARGS)


@pytest.fixture(scope="session")
def turret(tmp_path_factory):
    """turret_bot built once for the session, with its picture report."""
    out = tmp_path_factory.mktemp("picture-build")
    recipe = out / "turret_bot.yaml"
    shutil.copyfile(RECIPES / "turret_bot.yaml", recipe)
    shutil.copytree(RECIPES / "meshes" / "turret_bot", out / "meshes" / "turret_bot")
    assert "turret_bot:report-html" in build_cli([recipe], out / "build")
    return out / "build" / "turret_bot", recipe


def build_cli(recipes, out) -> list[str]:
    """``robotkit build -v`` in its own process (rendering never happens in the test process,
    which doit's worker processes may later be forked from); the names of the tasks that ran."""
    done = run_cli("build", *recipes, "--out", out, "-v")
    assert done.returncode == 0, done.stderr
    return [line.strip() for line in done.stderr.splitlines() if line.startswith("  ") and ":" in line
            and not line.strip().startswith(("warning", "collision"))]


def pixels(path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGB"), dtype=np.int16)


def test_equivalent_box_known_answer():
    from robotkit.check.lints import equivalent_box

    m, (a, b, c) = 2.0, (0.3, 0.2, 0.1)
    moments = (m / 12 * (b * b + c * c), m / 12 * (a * a + c * c), m / 12 * (a * a + b * b))
    assert np.allclose(equivalent_box(m, moments), [a, b, c], rtol=1e-12)
    # moments that break the triangle inequality: that side is drawn flat, never NaN
    assert equivalent_box(1.0, (1.0, 0.1, 0.1)).tolist()[0] == 0.0


@pytest.mark.slow
def test_build_writes_the_report_and_a_noop_build_does_not_rerender(turret):
    robot_dir, recipe = turret
    report = robot_dir / "report"
    names = sorted(p.name for p in report.iterdir())
    assert names == ["collision.png", "frames.png", "front.png", "inertia.png", "iso.png", "joint-j1.png",
                     "joint-j2.png", "left.png", "report.html", "top.png"]
    assert_golden(report / "report.html", GOLDEN / "turret_bot" / "report.html")
    before = {p.name: p.stat().st_mtime_ns for p in report.iterdir()}
    again = build([recipe], robot_dir.parent, report=True)
    assert again.ran == [] and "turret_bot:report-html" in again.uptodate
    assert {p.name: p.stat().st_mtime_ns for p in report.iterdir()} == before


@pytest.mark.slow
def test_report_task_reruns_on_a_recipe_edit_and_pictures_are_byte_identical(turret, tmp_path):
    robot_dir, recipe = turret
    edited = tmp_path / "turret_bot.yaml"
    shutil.copytree(recipe.parent / "meshes", tmp_path / "meshes")
    edited.write_text(recipe.read_text().replace("blue:  {rgba: [0, 0, 0.8, 1]", "blue:  {rgba: [0.9, 0.9, 0, 1]"))
    assert "turret_bot:report-html" in build_cli([edited], tmp_path / "build")
    new = tmp_path / "build" / "turret_bot" / "report"
    old = robot_dir / "report"
    assert (new / "inertia.png").read_bytes() != (old / "front.png").read_bytes()
    assert (new / "collision.png").read_bytes() == (old / "collision.png").read_bytes()  # colour not drawn there
    assert (new / "front.png").read_bytes() != (old / "front.png").read_bytes()  # the rotor turned yellow
    assert (new / "report.html").read_text() == (old / "report.html").read_text()


@pytest.mark.slow
def test_no_report_flag(tmp_path):
    recipe = write_recipe(tmp_path, """
        robot: cube
        links:
          base: {visual: {box: {size: [0.1, 0.1, 0.1]}}}
        """)
    done = run_cli("build", recipe, "--out", tmp_path / "build", "--no-report")
    assert done.returncode == 0, done.stderr
    assert not (tmp_path / "build" / "cube" / "report").exists()
    done = run_cli("build", recipe, "--out", tmp_path / "build")
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "build" / "cube" / "report" / "report.html").is_file()


ARM = """
    robot: {name}
    links:
      base: {{visual: {{box: {{size: [0.2, 0.2, 0.05]}}}}, inertial: {{mass: 5}}}}
      arm:
        visual: {{box: {{size: [0.05, 0.05, 0.4]}}, origin: {{xyz: [0, 0, 0.2]}}}}
        inertial: {inertial}
      tool:
        visual: {{mesh: tool.stl{units}}}
        inertial: {{mass: 0.3}}
    joints:
      shoulder:
        type: revolute
        parent: base
        child: arm
        origin: {{xyz: [0, 0, 0.025]}}
        axis: [0, {axis}, 0]
        limit: {{lower: -1, upper: 1, effort: 10, velocity: 2}}
      wrist:
        type: fixed
        parent: arm
        child: tool
        origin: {{xyz: [0, 0, 0.4]}}
    """
# a uniform 0.05 x 0.05 x 0.4 m box of 2.7 kg about its centre
ARM_INERTIA = {"ixx": 2.7 / 12 * (0.05 ** 2 + 0.4 ** 2), "iyy": 2.7 / 12 * (0.05 ** 2 + 0.4 ** 2),
               "izz": 2.7 / 12 * (2 * 0.05 ** 2)}


def arm_inertial(scale: float) -> str:
    tensor = ", ".join(f"{k}: {v * scale!r}" for k, v in ARM_INERTIA.items())
    return f"{{mass: 2.7, com: [0, 0, 0.2], inertia: {{{tensor}, ixy: 0, ixz: 0, iyz: 0}}}}"


@pytest.fixture(scope="module")
def arms(tmp_path_factory):
    """Three builds of one small arm: healthy, with its joint axis flipped, and with two
    defects (an inertia ten times too large, a millimetre mesh used as metres)."""
    folder = tmp_path_factory.mktemp("arms")
    tool_mm = trimesh.creation.box(extents=[40.0, 40.0, 60.0])  # millimetres
    tool_mm.apply_translation([0, 0, 30.0])
    recipes = []
    for name, axis, scale, units in (("healthy", 1, 1.0, ", units: mm"), ("flipped", -1, 1.0, ", units: mm"),
                                     ("defects", 1, 10.0, "")):
        recipes.append(write_recipe(folder, ARM.format(name=name, axis=axis, inertial=arm_inertial(scale),
                                                       units=units), f"{name}.yaml", {"tool.stl": tool_mm}))
    build_cli(recipes, folder / "build")
    return folder / "build"


def row(html: str, kind: str, name: str) -> str:
    match = re.search(rf'<tr id="{kind}-{name}">(.*?)</tr>', html, re.S)
    assert match, f"no row for {kind} {name}"
    return match.group(1)


@pytest.mark.slow
def test_defects_are_named_in_the_table(arms):
    html = (arms / "defects" / "report" / "report.html").read_text()
    assert "[inertia-box]" in row(html, "link", "arm")
    assert "[part-size]" in row(html, "link", "tool")
    assert "visual tool.stl is 60 m across" in row(html, "link", "tool")
    assert '<span class="error" id="errors">' in html
    healthy = (arms / "healthy" / "report" / "report.html").read_text()
    assert "[inertia-box]" not in healthy and "[part-size]" not in healthy
    # the arm's equivalent box: 0.05 x 0.05 x 0.4 m healthy; sqrt(10) times that when 10x the inertia
    assert "(0.4, 0.05, 0.05)" in row(healthy, "link", "arm")  # along the smallest moment first
    assert "(1.265, 0.1581, 0.1581)" in row(html, "link", "arm")
    flipped = (arms / "flipped" / "report" / "report.html").read_text()
    assert "(0, -1, 0)" in row(flipped, "joint", "shoulder")


@pytest.mark.slow
def test_defects_are_visible_in_the_pictures(arms):
    healthy, defects = arms / "healthy" / "report", arms / "defects" / "report"
    # the flagged links' inertia boxes are drawn red, the 60 m "tool" fills the picture
    def red(path):
        img = pixels(path)
        r, g, b = img[..., 0], img[..., 1], img[..., 2]
        return ((r > 120) & (r > 1.6 * g) & (np.abs(g - b) < 25)).mean()

    assert red(defects / "inertia.png") > 0.2
    assert red(healthy / "inertia.png") == 0


@pytest.mark.slow
def test_flipped_axis_shows_in_the_limit_pictures(arms):
    """q -> -q: the flipped joint at its lower limit is the healthy one at its upper limit."""
    def panels(name):
        strip = pixels(arms / name / "report" / "joint-shoulder.png")
        w, h = STRIP_SIZE  # lower, zero, +0.6 rad, upper
        assert strip.shape == (h + 28, 4 * w, 3)  # the labels on a band above the pictures
        return [strip[28:, i * w:(i + 1) * w] for i in (0, 1, 3)]

    def differ(a, b):  # share of pixels that differ
        return (np.abs(a - b).max(axis=2) > 30).mean()

    healthy, flipped = panels("healthy"), panels("flipped")
    # the same arm pose; only the joint-axis arrow (drawn over it) points the other way
    assert differ(flipped[0], healthy[2]) < 0.002 and differ(flipped[2], healthy[0]) < 0.002
    assert differ(flipped[0], healthy[0]) > 0.02
    assert differ(healthy[0], healthy[2]) > 0.02  # the joint moves visibly


SPINNER = """
    robot: spinner
    links:
      base: {visual: {box: {size: [0.2, 0.2, 0.05]}}, inertial: {mass: 5}}
      arm: {visual: {box: {size: [0.3, 0.04, 0.04]}, origin: {xyz: [0.15, 0, 0]}}, inertial: {mass: 1}}
      hand: {visual: {box: {size: [0.1, 0.03, 0.03]}, origin: {xyz: [0.05, 0, 0]}}, inertial: {mass: 0.2}}
    joints:
      spin:
        type: continuous
        parent: base
        child: arm
        origin: {xyz: [0, 0, 0.05]}
        axis: [0, 0, 1]
        limit: {effort: 10, velocity: 2}
      turn:
        type: revolute
        parent: arm
        child: hand
        origin: {xyz: [0.3, 0, 0]}
        axis: [0, 0, 1]
        limit: {lower: -6.283185307179586, upper: 6.283185307179586, effort: 10, velocity: 2}
    """


@pytest.mark.slow
def test_joints_without_limits_or_whole_turns_are_drawn_at_labelled_samples(tmp_path):
    """A continuous joint has no limits to draw (the table says "–"), a joint limited to +-2 pi
    is at zero's pose at both limits: both are drawn at -90, 0, +34 and +90 degrees, said so."""
    build_cli([write_recipe(tmp_path, SPINNER)], tmp_path / "build")
    report = tmp_path / "build" / "spinner" / "report"
    html = (report / "report.html").read_text()
    samples = "drawn at the sample positions -1.57 rad (-90°), zero, +0.6 rad (+34°), +1.57 rad (+90°)"
    moved = "; the link it moves shows its frame (x red, y green, z blue)</figcaption>"
    assert f"<b>Joint spin</b>: hinge joint with no limits (continuous), {samples}{moved}" in html
    assert (f"<b>Joint turn</b>: hinge joint with limits -6.28 rad (-360°) and 6.28 rad (+360°), a full turn "
            f"or more apart, {samples}{moved}") in html
    assert "lower -1.57" not in html and "upper 1.57" not in html
    assert '<td class="num">–</td><td class="num">–</td>' in row(html, "joint", "spin")

    def differ(a, b):
        return (np.abs(a - b).max(axis=2) > 30).mean()

    for joint in ("spin", "turn"):  # four poses, no two alike
        strip = pixels(report / f"joint-{joint}.png")[28:]
        w = STRIP_SIZE[0]
        panels = [strip[:, i * w:(i + 1) * w] for i in range(4)]
        assert min(differ(a, b) for i, a in enumerate(panels) for b in panels[i + 1:]) > 0.002, joint


@pytest.mark.slow
def test_report_of_a_foreign_urdf_and_an_mjcf_file(assets, turret, tmp_path):
    done = run_cli("report", assets / "turret_bot" / "urdf" / "turret_bot.urdf", "-o", tmp_path / "urdf",
                   "--package-path", f"turret_bot={assets / 'turret_bot'}")
    assert done.returncode == 0, done.stderr
    assert re.fullmatch(r"wrote \S*urdf/report\.html \(\d+\.\d\d s\)\n", done.stdout), done.stdout
    html = (tmp_path / "urdf" / "report.html").read_text()
    assert "[com-offset]" in row(html, "link", "base")
    assert (tmp_path / "urdf" / "inertia.png").is_file() and (tmp_path / "urdf" / "joint-j2.png").is_file()

    robot_dir, _ = turret
    done = run_cli("report", robot_dir / "mjcf" / "turret_bot.xml", "-o", tmp_path / "mjcf")
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "mjcf" / "frames.png").is_file()
    assert "<td>rotor</td>" in (tmp_path / "mjcf" / "report.html").read_text()

    lone = tmp_path / "lone.sdf"  # an SDF outside a build folder: the table only, and why
    shutil.copyfile(robot_dir / "model.sdf", lone)
    done = run_cli("report", lone)
    assert done.returncode == 0, done.stderr
    html = (tmp_path / "lone-report" / "report.html").read_text()
    assert "No pictures: an SDF file outside a robotkit build folder is not drawn yet (a URDF or MJCF is)." in html
    assert "<img" not in html
    built = (robot_dir / "report" / "report.html").read_text()
    # name, mass, centre of mass, principal moments: libsdformat's reading agrees with the URDF's
    assert row(html, "link", "rotor").split("</td>")[:5] == row(built, "link", "rotor").split("</td>")[:5]


@pytest.mark.slow
def test_report_bad_input(tmp_path):
    done = run_cli("report", tmp_path / "nothing.yaml")
    assert (done.returncode, done.stderr) == (2, f"{tmp_path / 'nothing.yaml'}: no such file or folder\n")
    (tmp_path / "robot.txt").write_text("x")
    done = run_cli("report", tmp_path / "robot.txt")
    assert done.returncode == 2
    assert done.stderr == (f"{tmp_path / 'robot.txt'}: unknown kind of file (expected a recipe .yaml, .urdf, "
                           ".sdf or MJCF .xml)\n")


@pytest.mark.browser
@pytest.mark.slow
def test_report_in_chromium(turret):
    """The page loads with no console error, every picture loads and is not blank, and the
    inertia-box picture is not the visual picture."""
    from playwright.sync_api import sync_playwright

    report = turret[0] / "report"
    with sync_playwright() as p:
        browser = chromium(p)
        page = browser.new_page()
        errors = []
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto((report / "report.html").as_uri())
        page.wait_for_load_state("load")
        images = page.eval_on_selector_all(
            "img", "els => els.map(e => [e.getAttribute('src'), e.complete, e.naturalWidth, e.naturalHeight])")
        browser.close()
    assert errors == []
    assert len(images) == 9
    for src, complete, w, h in images:
        assert complete and w > 0 and h > 0, src
        img = pixels(report / src)
        assert img.reshape(-1, 3).std(axis=0).max() > 10, f"{src} is blank"
    diff = np.abs(pixels(report / "inertia.png") - pixels(report / "iso.png")).max(axis=2)
    assert (diff > 30).mean() > 0.01


@pytest.mark.consumers
@pytest.mark.slow
def test_check_github_writes_a_job_summary(turret, tmp_path):
    robot_dir, _ = turret
    summary = tmp_path / "summary.md"
    summary.write_text("earlier step\n")
    import os
    import subprocess
    import sys

    env = {**os.environ, "GITHUB_STEP_SUMMARY": str(summary)}
    done = subprocess.run([sys.executable, "-m", "robotkit", "check", str(robot_dir), "--format", "github"],
                          capture_output=True, text=True, env=env, cwd=robot_dir.parent)
    assert done.returncode == 0, done.stderr
    text = summary.read_text()
    assert text.startswith("earlier step\n## robotkit check ")
    assert "Picture report: `turret_bot/report/report.html` (upload the folder `turret_bot/report` as an " \
           "artifact to see it)" in text


NO_GL = {"bogus": "invalid value for environment variable MUJOCO_GL: bogus",  # MuJoCo's import fails
         "disable": "module 'mujoco.rendering.classic.gl_context' has no attribute 'GLContext'"}  # no context


@pytest.mark.slow
@pytest.mark.parametrize("gl", sorted(NO_GL))
def test_where_mujoco_cannot_draw_a_build_writes_everything_and_warns_once(tmp_path, gl):
    """The picture report is optional: with no offscreen OpenGL (no OSMesa, an unusable MUJOCO_GL)
    the build writes every description, the ROS package and a report without pictures, says
    what to install in one warning and exits 0; the next build where MuJoCo can draw draws them.
    ``robotkit report`` stops on it (exit 2) with the same line; no traceback anywhere."""
    from robotkit.ioutil import environ

    shutil.copytree(RECIPES, tmp_path / "recipes", ignore=shutil.ignore_patterns("*.yaml"))
    shutil.copy(RECIPES / "turret_bot.yaml", tmp_path / "recipes")
    why = (f"no pictures: MuJoCo cannot draw offscreen with MUJOCO_GL={gl} ({NO_GL[gl]}); unset MUJOCO_GL "
           "to draw with OSMesa (sudo apt-get install libosmesa6)")
    with environ({"MUJOCO_GL": gl}):
        built = run_cli("build", "recipes/turret_bot.yaml", "--out", "out", cwd=tmp_path)
        report = run_cli("report", "out/turret_bot", "-o", "elsewhere", cwd=tmp_path)
    assert built.returncode == 0, built.stderr
    assert "Traceback" not in built.stderr + report.stderr
    assert [line for line in built.stderr.splitlines() if "pictures" in line] == [
        f"recipes/turret_bot.yaml:6: robot: warning: turret_bot: report/report.html: {why}"]
    robot = tmp_path / "out" / "turret_bot"
    for rel in ("urdf/turret_bot.urdf", "model.sdf", "model.config", "mjcf/turret_bot.xml", "mjcf/scene.xml",
                "package.xml", "CMakeLists.txt", "launch/display.launch", "rviz/turret_bot.rviz", "report.json"):
        assert (robot / rel).is_file(), rel
    assert str(escape(why)) in (robot / "report" / "report.html").read_text(encoding="utf-8")  # as Jinja writes it
    assert not list((robot / "report").glob("*.png"))
    assert (report.returncode, report.stderr.splitlines()) == (2, [why])

    again = run_cli("build", "recipes/turret_bot.yaml", "--out", "out", cwd=tmp_path)  # MuJoCo draws here
    assert again.returncode == 0 and "pictures" not in again.stderr
    assert "1 tasks run" in again.stdout  # the report alone
    assert len(list((robot / "report").glob("*.png"))) > 4
    assert "up to date" in run_cli("build", "recipes/turret_bot.yaml", "--out", "out", cwd=tmp_path).stdout


def chain_mjcf(n: int) -> str:
    """An MJCF chain of ``n`` boxes on hinges (limits +-1.5 rad), visual geoms in group 2 as
    robotkit writes them."""
    body = ""
    for i in range(n, 0, -1):
        body = (f'<body name="l{i}" pos="0 0 0.1"><joint name="j{i}" type="hinge" axis="0 {i % 2} {1 - i % 2}" '
                f'range="-1.5 1.5" limited="true"/><geom type="box" size="0.04 0.01 0.05" pos="0.03 0 0.05" '
                f'group="2" mass="0.1"/>{body}</body>')
    return (f'<mujoco model="chain{n}"><compiler angle="radian"/><worldbody><body name="base"><geom type="box" size="0.05 0.05 0.02" '
            f'group="2" mass="1"/>{body}</body></worldbody></mujoco>')


def differ(a, b) -> float:
    """Share of pixels that differ visibly."""
    return (np.abs(a.astype(int) - b.astype(int)).max(axis=2) > 30).mean()


@pytest.mark.slow
def test_a_long_chain_has_three_pictures_per_joint(tmp_path):
    """Past BRIEF_JOINTS joints a strip is lower limit, zero, upper limit (no small move), said
    so in its caption, in smaller pictures, and the joint still moves from one picture to the next."""
    from robotkit.picture.render import BRIEF_JOINTS, BRIEF_STRIP_SIZE

    n = BRIEF_JOINTS + 1
    (tmp_path / "chain.xml").write_text(chain_mjcf(n))
    done = run_cli("report", tmp_path / "chain.xml", "-o", tmp_path / "report")
    assert done.returncode == 0, done.stderr
    html = (tmp_path / "report" / "report.html").read_text()
    assert "<b>Joint j1</b>: hinge joint at its lower limit, zero and its upper limit; the link it moves" in html
    w, h = BRIEF_STRIP_SIZE
    for joint in ("j1", f"j{n}"):
        strip = pixels(tmp_path / "report" / f"joint-{joint}.png")
        assert strip.shape == (h + 28, 3 * w, 3)
        panels = [strip[28:, i * w:(i + 1) * w] for i in range(3)]
        assert min(differ(a, b) for i, a in enumerate(panels) for b in panels[i + 1:]) > 0.001, joint
    assert sorted(p.name for p in (tmp_path / "report").glob("joint-*.png")) == sorted(
        f"joint-j{i}.png" for i in range(1, n + 1))


STRIP_AGAINST_PICTURES = """
import sys
import numpy as np
from robotkit.picture.render import Painter, STRIP_SIZE, VISUAL, load_model

model = load_model(sys.argv[1])
model.vis.quality.offsamples = 0
strip = Painter(model, *STRIP_SIZE, panels=4)
single = Painter(model, *STRIP_SIZE)
name, kind, poses, caption = strip.joint_poses()[1]
pictures = strip.strip([q for _, q in poses], 135.0, -25.0, {VISUAL: True})
w = STRIP_SIZE[0]
for i, (_, q) in enumerate(poses):
    single.pose(q)
    alone = single._draw(135.0, -25.0, {VISUAL: True}, ghost=False)
    panel = pictures[:, i * w:(i + 1) * w]
    print(int((np.abs(panel.astype(int) - alone.astype(int)).max(axis=2) > 30).sum()), panel.shape == alone.shape)
strip.close()
single.close()
"""


@pytest.mark.slow
def test_a_strip_drawn_in_one_framebuffer_is_its_pictures_drawn_one_by_one(tmp_path):
    """Painter.strip draws a joint's poses side by side in one framebuffer and reads it once:
    each panel is the picture of that pose drawn alone (in another process: no GL here)."""
    import subprocess
    import sys

    (tmp_path / "chain.xml").write_text(chain_mjcf(3))
    done = subprocess.run([sys.executable, "-c", STRIP_AGAINST_PICTURES, str(tmp_path / "chain.xml")],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    rows = [line.split() for line in done.stdout.splitlines()]
    assert len(rows) == 4  # lower, zero, +0.6 rad, upper
    assert all(shape == "True" and int(count) <= 20 for count, shape in rows), rows


def test_png_bytes_is_a_png_of_the_same_pixels(tmp_path):
    """The strips' PNG writer: Pillow reads back the very pixels, and the bytes are the same each time."""
    from robotkit.picture.render import png_bytes

    rng = np.random.default_rng(0)
    img = rng.integers(0, 256, size=(37, 53, 3), dtype=np.uint8)
    img[:10] = (235, 238, 242)  # a flat band, as the background
    data = png_bytes(img)
    (tmp_path / "a.png").write_bytes(data)
    assert np.array_equal(np.asarray(Image.open(tmp_path / "a.png").convert("RGB")), img)
    assert png_bytes(img.copy()) == data
