"""The report's step-response plots: one SVG per joint, the simulators overlaid, from the motion
stage's results."""

from __future__ import annotations

import re

import pytest

from robotkit.picture.plots import HEIGHT, PAD, WIDTH, step_plots
from tests.conftest import run_cli


def run(q: list[float]) -> dict:
    return {"start": 0.0, "target": 1.0, "rise_time": 0.1, "overshoot": 0.0, "settling_time": 0.2,
            "final_error": 0.0, "trace": {"t": [0.0, 0.5, 1.0], "q": q}}


def test_a_plot_per_joint_with_each_simulator_scaled_into_the_frame():
    motion = {"joints": {"j": {"interface": "position", "poses": {"home": {"simulators": {
        "mujoco": run([0.0, 1.0, 1.0]), "drake": run([0.0, 0.5, 1.0])}}}}}}
    [plot] = step_plots(motion)
    assert (plot.joint, plot.pose) == ("j", "home")
    assert [r["simulator"] for r in plot.rows] == ["mujoco", "drake"]
    points = dict(re.findall(r'<polyline class="(\w+)"[^>]*points="([^"]+)"', plot.svg))
    # t 0..1 s spans the frame's width; q 0..1 its height, bottom to top
    assert points["mujoco"] == f"{PAD:.1f},{HEIGHT - PAD:.1f} {WIDTH / 2:.1f},{PAD:.1f} {WIDTH - PAD:.1f},{PAD:.1f}"
    assert points["drake"].split()[1] == f"{WIDTH / 2:.1f},{HEIGHT / 2:.1f}"


def test_no_results_no_plots():
    assert step_plots(None) == [] and step_plots({"joints": {}}) == []


@pytest.mark.slow
@pytest.mark.consumers
def test_the_report_of_a_build_plots_each_joint_in_the_three_simulators(examples, tmp_path):
    proc = run_cli("report", examples / "turret_bot", "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    html = (tmp_path / "report.html").read_text()
    for joint in ("j1", "j2"):
        figure = html.split(f'<figure id="step-{joint}">')[1].split("</figure>")[0]
        assert sorted(re.findall(r'<polyline class="(\w+)"', figure)) == ["drake", "mujoco", "pybullet"]
