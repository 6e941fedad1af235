"""A machine where MuJoCo cannot draw offscreen because Debian's libosmesa6 (or, for MUJOCO_GL=egl,
libEGL) is not installed.

The library cannot be removed from the test machine, so the robotkit processes are started with a
``sitecustomize`` on PYTHONPATH that makes loading it fail as it does where the file is missing
(``OSError: ... cannot open shared object file``); everything else is real: MuJoCo's and PyOpenGL's
imports, the build and its worker processes, the report command."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import RECIPES
from robotkit.ioutil import environ

MISSING = '''\
import ctypes

_load = ctypes.CDLL.__init__


def _missing(self, name, *args, **kwargs):
    if name and "{library}" in str(name):
        raise OSError(f"{name}: cannot open shared object file: No such file or directory")
    _load(self, name, *args, **kwargs)


ctypes.CDLL.__init__ = _missing
'''

WHY = ("no pictures: MuJoCo cannot draw offscreen with MUJOCO_GL=osmesa (libOSMesa is not installed); "
       "install libosmesa6: sudo apt-get install libosmesa6")


def run_without_osmesa(tmp_path: Path, *args: str, library: str = "OSMesa", gl: str | None = None):
    """robotkit ``args`` in a process (and its workers) that cannot load ``library`` (libOSMesa,
    libEGL), with ``MUJOCO_GL`` unset (robotkit's default: osmesa) or ``gl``."""
    fake = tmp_path / "no-osmesa"
    fake.mkdir(exist_ok=True)
    (fake / "sitecustomize.py").write_text(MISSING.replace("{library}", library), encoding="utf-8")
    # PYOPENGL_PLATFORM: set in this process by an earlier test's MuJoCo import, not in a user's shell
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    if gl is not None:
        env["MUJOCO_GL"] = gl
    env["PYTHONPATH"] = os.pathsep.join([str(fake)] + [p for p in [os.environ.get("PYTHONPATH")] if p])
    return subprocess.run([sys.executable, "-m", "robotkit", *args], capture_output=True, text=True,
                          cwd=tmp_path, env=env)


@pytest.mark.slow
def test_without_osmesa_a_build_writes_everything_warns_once_and_report_stops(tmp_path):
    """The quick start's build on a machine without libosmesa6 (issue 31: a traceback from the drives'
    tuning or the report task, nothing written): every description and the ROS package are
    written, one warning names what to install, exit 0; ``robotkit report`` exits 2 with that line."""
    fake = run_without_osmesa(tmp_path, "schema")  # writes the sitecustomize; then: does it refuse?
    assert fake.returncode == 0, fake.stderr
    check = subprocess.run([sys.executable, "-c", "import ctypes; ctypes.CDLL('libOSMesa.so.8')"],
                           capture_output=True, text=True, cwd=tmp_path,
                           env={**os.environ, "PYTHONPATH": str(tmp_path / "no-osmesa")})
    assert "libOSMesa.so.8: cannot open shared object file" in check.stderr

    shutil.copytree(RECIPES, tmp_path / "recipes", ignore=shutil.ignore_patterns("*.yaml"))
    shutil.copy(RECIPES / "turret_bot.yaml", tmp_path / "recipes")
    built = run_without_osmesa(tmp_path, "build", "recipes/turret_bot.yaml", "--out", "out")
    report = run_without_osmesa(tmp_path, "report", "out/turret_bot", "-o", "elsewhere")

    assert built.returncode == 0, built.stderr
    assert "Traceback" not in built.stderr + built.stdout + report.stderr + report.stdout
    assert [line for line in built.stderr.splitlines() if "pictures" in line or "osmesa" in line.lower()] == [
        f"recipes/turret_bot.yaml:6: robot: warning: turret_bot: report/report.html: {WHY}"]
    robot = tmp_path / "out" / "turret_bot"
    for rel in ("urdf/turret_bot.urdf", "model.sdf", "model.config", "mjcf/turret_bot.xml", "mjcf/scene.xml",
                "package.xml", "CMakeLists.txt", "launch/display.launch", "rviz/turret_bot.rviz", "report.json",
                "report/report.html"):
        assert (robot / rel).is_file(), rel
    assert not list((robot / "report").glob("*.png"))
    assert (report.returncode, report.stderr.splitlines()) == (2, [WHY])


MJCF = """<mujoco><worldbody><body name="box"><freejoint/><geom type="box" size="0.1 0.1 0.1" group="2"/>
</body></worldbody></mujoco>
"""


@pytest.mark.parametrize("gl, library, why", [
    (None, "OSMesa", WHY),
    ("egl", "EGL", "no pictures: MuJoCo cannot draw offscreen with MUJOCO_GL=egl (libEGL is not installed); install "
                   "an EGL driver (sudo apt-get install libegl1 libegl-mesa0), or unset MUJOCO_GL to draw with OSMesa "
                   "(sudo apt-get install libosmesa6)"),
])
def test_report_of_an_mjcf_says_which_library_the_backend_lacks(tmp_path, gl, library, why):
    (tmp_path / "box.xml").write_text(MJCF, encoding="utf-8")
    done = run_without_osmesa(tmp_path, "report", "box.xml", library=library, gl=gl)
    assert (done.returncode, done.stdout, done.stderr) == (2, "", why + "\n")
    assert not (tmp_path / "box-report").exists()


@pytest.mark.slow
def test_a_cached_report_with_pictures_is_not_reused_where_none_can_be_drawn(tmp_path):
    """The report is cached by content (robotkit.pipeline.actions.cached_task); a machine that
    cannot draw does not take the pictures another build drew into the same cache: it writes
    the page without them and warns, as without a cache."""
    shutil.copytree(RECIPES, tmp_path / "recipes", ignore=shutil.ignore_patterns("*.yaml"))
    shutil.copy(RECIPES / "turret_bot.yaml", tmp_path / "recipes")
    env = {**os.environ, "ROBOTKIT_CACHE": str(tmp_path / "cache")}
    drawn = subprocess.run([sys.executable, "-m", "robotkit", "build", "recipes/turret_bot.yaml", "--out", "drawn"],
                           capture_output=True, text=True, cwd=tmp_path, env=env)
    assert drawn.returncode == 0, drawn.stderr
    assert list((tmp_path / "drawn" / "turret_bot" / "report").glob("*.png"))
    with environ({"ROBOTKIT_CACHE": str(tmp_path / "cache")}):  # run_without_osmesa passes this process's
        built = run_without_osmesa(tmp_path, "build", "recipes/turret_bot.yaml", "--out", "out")
    assert built.returncode == 0, built.stderr
    assert f"recipes/turret_bot.yaml:6: robot: warning: turret_bot: report/report.html: {WHY}" in built.stderr
    assert not list((tmp_path / "out" / "turret_bot" / "report").glob("*.png"))
