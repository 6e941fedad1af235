"""Every shipped example builds with no warning at all (issue 31): what a format cannot hold by
its nature is report.json's ``limits``, not a warning, and the recipes say what the rules ask
(a maintainer, convex collision shapes, an integral gain where the MJCF alone compensates
gravity).  The ``robotkit new`` starter: tests/commands/test_new.py."""

from __future__ import annotations

import json

import pytest

from conftest import RECIPES, run_cli

pytestmark = pytest.mark.slow

PENDING = {  # what is left, and why (strict: the test says when it is fixed)
    "lidar_mast": "its lidar mesh (lds.stl) is not convex, so MuJoCo collides with its hull; but it is a thin "
                  "shell: its hull is 2.9x its volume, a fitted cylinder 5.8x (check's collision-volume), and "
                  "CoACD cuts it into 266 pieces in 3.5 min",
}


@pytest.mark.parametrize("recipe", [
    pytest.param(p.stem, marks=pytest.mark.xfail(reason=PENDING[p.stem], strict=True)) if p.stem in PENDING
    else p.stem for p in sorted(RECIPES.glob("*.yaml"))])
def test_example_builds_without_warning(examples, recipe):
    """The session's build of every example (conftest.examples), built again by the command line
    with -v: every task up to date, every warning of the build printed."""
    proc = run_cli("build", RECIPES / f"{recipe}.yaml", "--out", examples, "--no-report", "-v")
    assert proc.returncode == 0, proc.stderr
    assert [line for line in proc.stderr.splitlines() if "warning" in line] == []


def test_a_format_s_nature_is_recorded_once_in_report_json(examples):
    """The quadruped's 12 joints have no velocity limit in MJCF: one entry per robot, no warning."""
    for robot in ("quadruped_compact", "quadruped_explorer"):
        report = json.loads((examples / robot / "report.json").read_text())
        assert [x for x in report["limits"]["mjcf"] if "velocity" in x] == [
            "joint 'front_left_hip_roll' and 11 more ('front_left_hip_pitch', 'front_left_knee', "
            "'front_right_hip_roll', 'front_right_hip_pitch', 'front_right_knee', 'hind_left_hip_roll', "
            "'hind_left_hip_pitch', 'hind_left_knee', 'hind_right_hip_roll', 'hind_right_hip_pitch', "
            "'hind_right_knee'): MJCF has no velocity limit (8 not enforced)"]
        assert not any("velocity" in x for items in report["losses"].values() for x in items)
