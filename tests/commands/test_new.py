"""robotkit new NAME: the starter recipe (golden), its mesh and schema; it builds as written,
with no warning (what a format cannot express is in report.json's ``limits``); no file is ever
overwritten."""

from __future__ import annotations

import pytest

import json

import numpy as np
import trimesh

from conftest import GOLDEN, assert_golden, run_cli


@pytest.mark.slow
def test_new_writes_a_starter_that_builds(tmp_path):
    proc = run_cli("new", "my_bot", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines() == ["my_bot.yaml", "meshes/my_bot/arm.stl", "recipe.schema.json",
                                        "build it: robotkit build my_bot.yaml"]
    assert_golden(tmp_path / "my_bot.yaml", GOLDEN / "new" / "my_bot.yaml")
    assert (tmp_path / "my_bot.yaml").read_text().startswith("# yaml-language-server: $schema=recipe.schema.json\n")
    assert (tmp_path / "recipe.schema.json").read_text() == run_cli("schema").stdout
    mesh = trimesh.load(tmp_path / "meshes" / "my_bot" / "arm.stl")
    assert mesh.is_watertight and np.allclose(mesh.bounds, [[-10, -10, 0], [10, 10, 200]])

    build = run_cli("build", "my_bot.yaml", "--out", "out", "--no-report", "-j", "1", cwd=tmp_path)
    assert build.returncode == 0, build.stderr
    assert "warning" not in build.stderr
    report = json.loads((tmp_path / "out" / "my_bot" / "report.json").read_text())
    assert report["limits"] == {"mjcf": ["joint 'shoulder': MJCF has no velocity limit (2 not enforced)"]}
    assert report["losses"] == {"mjcf": [], "package": [], "sdf": [], "urdf": []}
    arm = report["inertials"]["arm"]
    # the 20 x 20 x 200 mm bar at 1200 kg/m^3, from the millimetre mesh: m = 0.096 kg, COM 0.1 m up,
    # Ixx = Iyy = m (0.02^2 + 0.2^2) / 12, Izz = m (0.02^2 + 0.02^2) / 12
    m = 0.02 * 0.02 * 0.2 * 1200
    assert abs(arm["mass"] - m) < 1e-12 and np.allclose(arm["com"], [0, 0, 0.1], atol=1e-12)
    assert np.allclose(arm["inertia"], [m * 0.0404 / 12, 0, 0, m * 0.0404 / 12, 0, m * 0.0008 / 12], atol=1e-15)


@pytest.mark.slow
def test_new_never_overwrites(tmp_path):
    assert run_cli("new", "my_bot", cwd=tmp_path).returncode == 0
    proc = run_cli("new", "my_bot", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == [
        "my_bot.yaml: already exists; robotkit new writes no file over another",
        "meshes/my_bot/arm.stl: already exists; robotkit new writes no file over another"]
    assert run_cli("new", "other_bot", cwd=tmp_path).returncode == 0  # the same schema file is fine


def test_new_refuses_a_name_that_is_no_file_name(tmp_path):
    proc = run_cli("new", "my bot", cwd=tmp_path)
    assert (proc.returncode, proc.stdout) == (2, "")
    assert proc.stderr == ("robot name 'my bot' may contain only ASCII letters, digits, '_', '.' and '-' and must "
                           "start with a letter, a digit or '_' (it becomes a file name)\n")
    assert list(tmp_path.iterdir()) == []
