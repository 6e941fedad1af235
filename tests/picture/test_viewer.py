"""`robotkit view` driven from headless Chromium: the page connects, a joint slider moves the
robot, editing the recipe (a colour, a joint origin) rebuilds it in place, and a broken recipe
shows its error in the page while the last good robot stays; a recipe with variants shows each
(a selector), the floor grid, sliders in degrees and millimetres, flagged links red."""

from __future__ import annotations

import contextlib
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from conftest import RECIPES
from robotkit.errors import RobotkitError
from tests.picture.test_report import arms, chromium  # noqa: F401  (arms: a fixture)

pytestmark = [pytest.mark.browser, pytest.mark.slow]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def viewing(tmp_path: Path, path: Path, *options: str):
    """``robotkit view PATH`` in its own process: (url, its log file) once it serves."""
    port = free_port()
    log = open(tmp_path / "view.log", "w+")
    proc = subprocess.Popen([sys.executable, "-m", "robotkit", "view", str(path), "--port", str(port),
                             "--no-browser", "--out", str(tmp_path / "build"), *options],
                            stdout=log, stderr=subprocess.STDOUT, text=True)
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 60
    while f"at {url}" not in (tmp_path / "view.log").read_text():
        assert proc.poll() is None and time.monotonic() < deadline, (tmp_path / "view.log").read_text()
        time.sleep(0.1)
    try:
        yield url, tmp_path / "view.log"
    finally:
        proc.terminate()
        proc.wait(timeout=10)
        log.close()


@pytest.fixture
def viewer(tmp_path):
    recipe = tmp_path / "turret_bot.yaml"
    shutil.copyfile(RECIPES / "turret_bot.yaml", recipe)
    shutil.copytree(RECIPES / "meshes" / "turret_bot", tmp_path / "meshes" / "turret_bot")
    with viewing(tmp_path, recipe) as (url, log):
        yield url, recipe, log


def open_page(p, url: str, status: str):
    browser = chromium(p)
    page = browser.new_page(viewport={"width": 1000, "height": 700})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(url)
    page.get_by_text("Connected").wait_for(timeout=30_000)
    wait_for_status(page, status)
    return browser, page, errors


def number_box(page, label: str):
    """The number box of the slider labelled ``label``."""
    return page.locator(f"xpath=//label[normalize-space()='{label}']/following::input[@type='text'][1]")


def shot(page, path) -> np.ndarray:
    page.wait_for_timeout(700)  # let the scene update reach the canvas
    page.locator("canvas").first.screenshot(path=str(path), timeout=60_000)
    return np.asarray(Image.open(path).convert("RGB"), dtype=np.int16)


def changed(a, b) -> float:
    return (np.abs(a - b).max(axis=2) > 30).mean()


def shot_after_change(page, before, path, least: float = 0.002, timeout: float = 20.0) -> np.ndarray:
    """The canvas once it differs from ``before`` by ``least`` (the update may take a moment)."""
    deadline = time.monotonic() + timeout
    while True:
        now = shot(page, path)
        if changed(before, now) > least or time.monotonic() > deadline:
            return now


def wait_for_status(page, text: str, timeout: float = 60_000):
    page.get_by_text(text).first.wait_for(timeout=timeout)


def test_viewer_in_chromium(viewer, tmp_path):
    from playwright.sync_api import sync_playwright

    url, recipe, log = viewer
    with sync_playwright() as p:
        browser, page, errors = open_page(p, url, "turret_bot: 2 joints")
        first = shot(page, tmp_path / "0.png")
        assert first.reshape(-1, 3).std(axis=0).max() > 10, "blank canvas"

        # a joint slider (its number box, in millimetres) moves the slider link
        assert number_box(page, "j2 (°)").input_value() == "0"
        number = number_box(page, "j1 (mm)")
        number.fill("900")
        number.press("Enter")
        moved = shot_after_change(page, first, tmp_path / "1.png")
        assert changed(first, moved) > 0.002

        # a toggle: the inertia boxes drawn over the robot, and gone again
        page.get_by_text("Inertia boxes", exact=True).click()
        boxes = shot_after_change(page, moved, tmp_path / "boxes.png")
        assert changed(moved, boxes) > 0.002
        page.get_by_text("Inertia boxes", exact=True).click()
        deadline = time.monotonic() + 20  # back to the picture before (but the checkbox's own look)
        while changed(moved, shot(page, tmp_path / "no-boxes.png")) >= changed(moved, boxes) / 4:
            assert time.monotonic() < deadline, "the inertia boxes stayed"

        # the recipe's colour, then a joint origin: rebuilt and redrawn in place
        text = recipe.read_text()
        recipe.write_text(text.replace("red:   {rgba: [0.8, 0, 0, 1]", "red:   {rgba: [0.1, 0.8, 0.9, 1]"))
        wait_for_status(page, "turret_bot: 2 joints; shown in", timeout=60_000)
        deadline = time.monotonic() + 60
        while log.read_text().count("turret_bot updated") < 2:
            assert time.monotonic() < deadline, log.read_text()
            time.sleep(0.2)
        recoloured = shot_after_change(page, moved, tmp_path / "2.png")
        assert changed(moved, recoloured) > 0.002
        text = recipe.read_text()
        recipe.write_text(text.replace("origin: {xyz: [0, 0.05, 0.475]}", "origin: {xyz: [0, 0.05, 1.2]}"))
        while log.read_text().count("turret_bot updated") < 3:
            assert time.monotonic() < deadline, log.read_text()
            time.sleep(0.2)
        raised = shot_after_change(page, recoloured, tmp_path / "3.png")
        assert changed(recoloured, raised) > 0.002

        # a broken recipe: the error in the page, the viewer alive
        good = recipe.read_text()
        recipe.write_text(good.replace("density: 1250", "density: -5"))
        page.get_by_text("Build failed").wait_for(timeout=60_000)
        assert page.get_by_text("density: must be > 0").count() >= 1
        # ... and fixed again: the robot is back
        recipe.write_text(good)
        page.get_by_text("Build failed").wait_for(state="detached", timeout=60_000)
        deadline = time.monotonic() + 30
        while log.read_text().count("turret_bot updated") < 4:
            assert time.monotonic() < deadline, log.read_text()
            time.sleep(0.2)
        browser.close()
    assert errors == []


def test_viewer_of_a_recipe_with_variants(tmp_path):
    """The quadruped (two variants) opens: the first variant shown, a selector switches to the
    other; the floor grid (its scale in the status) is drawn and can be hidden; the hinge
    sliders are in degrees."""
    from playwright.sync_api import sync_playwright

    recipe = tmp_path / "quadruped.yaml"
    shutil.copyfile(RECIPES / "quadruped.yaml", recipe)
    shutil.copytree(RECIPES / "parts", tmp_path / "parts")
    with viewing(tmp_path, recipe) as (url, log), sync_playwright() as p:
        browser, page, errors = open_page(p, url, "quadruped_compact: 12 joints")
        assert page.get_by_text("Floor grid: 1 cm squares, a line every 10 cm").count() == 1
        first = shot(page, tmp_path / "0.png")
        page.get_by_text("Floor grid and world axes", exact=True).click()
        bare = shot_after_change(page, first, tmp_path / "no-grid.png")
        assert changed(first, bare) > 0.02  # the grid covers much of the floor
        page.get_by_text("Floor grid and world axes", exact=True).click()

        # degrees: the knee's limits (-2.79 rad .. 0) are -160 .. 0 on its slider; -90 bends it
        knee = number_box(page, "front_left_knee (°)")
        assert knee.input_value() == "0"
        assert page.get_by_text("-160", exact=True).count() >= 1
        grid = shot_after_change(page, bare, tmp_path / "grid.png")
        knee.fill("-90")
        knee.press("Enter")
        bent = shot_after_change(page, grid, tmp_path / "bent.png")
        assert changed(grid, bent) > 0.002

        # the other variant (longer legs, a lidar)
        page.get_by_role("combobox", name="Robot").click()
        page.get_by_role("option", name="quadruped_explorer").click()
        wait_for_status(page, "quadruped_explorer: 12 joints")
        explorer = shot_after_change(page, bent, tmp_path / "explorer.png")
        assert changed(bent, explorer) > 0.002
        browser.close()
    assert errors == []
    assert "quadruped_explorer updated" in log.read_text()


def test_viewer_of_one_variant_and_an_unknown_one(tmp_path):
    """--variant NAME shows that one, with the --arg values; an unknown one is one line."""
    from robotkit.commands.view import resolve

    recipe = tmp_path / "quadruped.yaml"
    shutil.copyfile(RECIPES / "quadruped.yaml", recipe)
    shutil.copytree(RECIPES / "parts", tmp_path / "parts")
    kind, make = resolve(recipe, str(tmp_path / "build"), variant="compact", args={"lidar": "true"})
    assert kind == "recipe"
    shown = make()
    assert [b.name for b in shown] == ["quadruped_compact"]
    assert '<sensor name="scan" type="gpu_lidar">' in shown[0].urdf.read_text()  # --arg lidar:=true
    with pytest.raises(RobotkitError) as exc:
        resolve(recipe, str(tmp_path / "build"), variant="tall")
    assert exc.value.lines() == [f"{recipe}: --variant: no variant named 'tall' (variants: compact, explorer)"]


def test_flagged_links_are_red_in_the_viewer(arms, tmp_path):  # noqa: F811  (arms: the fixture)
    """The arm with a 10x inertia and a millimetre mesh read as metres: the links the report
    draws red (arm, tool) are red in the viewer, said so in the status; the healthy arm is not."""
    from playwright.sync_api import sync_playwright

    def red(img):
        r, g, b = img[..., 0], img[..., 1], img[..., 2]
        return ((r > 150) & (r > 2.5 * g) & (r > 2.5 * b)).mean()

    seen = {}
    for name in ("defects", "healthy"):
        folder = tmp_path / name
        folder.mkdir()
        with viewing(folder, arms / name) as (url, _), sync_playwright() as p:
            browser, page, errors = open_page(p, url, f"{name}: 1 joints")
            seen[name] = shot(page, folder / "shot.png")
            flagged = page.get_by_text("Red: links a lint fired on (see the report): arm, tool").count()
            browser.close()
        assert errors == []
        assert flagged == (1 if name == "defects" else 0)
    assert red(seen["defects"]) > 0.01
    assert red(seen["healthy"]) < 0.001  # the world x axis only


def test_view_bad_input(tmp_path):
    from conftest import run_cli

    (tmp_path / "robot.sdf").write_text("<sdf/>")
    done = run_cli("view", tmp_path / "robot.sdf", "--no-browser")
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == (f"{tmp_path / 'robot.sdf'}: unknown kind of file (expected a recipe .yaml, a build "
                           "folder or a .urdf)\n")
    done = run_cli("view", tmp_path / "missing.yaml", "--no-browser")
    assert (done.returncode, done.stderr) == (2, f"{tmp_path / 'missing.yaml'}: no such file or folder\n")


def test_slider_units():
    """Degrees for a hinge, millimetres for a slide; the limits rounded inwards to the step."""
    import yourdfpy

    from robotkit.picture.viewer import slider_scale

    def joint(kind, lower=None, upper=None):
        return yourdfpy.Joint(name="j", type=kind, limit=yourdfpy.Limit(effort=1, velocity=1, lower=lower, upper=upper))

    label, per, low, high, step = slider_scale(joint("revolute", -1.0, 1.0))
    assert (label, step) == ("j (°)", 0.1) and per == pytest.approx(57.29578)
    assert (low, high) == pytest.approx((-57.2, 57.2))  # +-57.2958 degrees, inside the limits
    assert slider_scale(joint("continuous"))[:4] == ("j (°)", pytest.approx(57.29578), pytest.approx(-180.0),
                                                     pytest.approx(180.0))
    assert slider_scale(joint("prismatic", 0.0, 0.25)) == ("j (mm)", 1000.0, 0.0, pytest.approx(250.0), 0.1)
