"""The no-op fast path (robotkit.pipeline.stamp): a second build answers from the stamp without loading
anything, and every change to an input or an output falls through to the real build."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import robotkit.pipeline.runner
from robotkit.pipeline import stamp
from robotkit.cli import main

REPO = Path(__file__).resolve().parents[2]

RECIPE = """robot: bot
units: m
density: 1000
include: [parts.yaml]
links:
  base: {visual: {box: {size: [0.2, 0.2, 0.1]}}}
  arm: {visual: {mesh: slider.stl, material: grey}}
joints:
  j1: {type: revolute, parent: base, child: arm, axis: [0, 0, 1],
       limit: {lower: -1, upper: 1, effort: 1, velocity: 1}}
"""
PARTS = "materials:\n  grey: {rgba: [0.5, 0.5, 0.5, 1]}\n"


@pytest.fixture
def project(tmp_path, monkeypatch):
    monkeypatch.setenv("ROBOTKIT_CACHE", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bot.yaml").write_text(RECIPE)
    (tmp_path / "parts.yaml").write_text(PARTS)
    shutil.copy(REPO / "recipes" / "meshes" / "turret_bot" / "slider.stl", tmp_path / "slider.stl")
    return tmp_path


class Calls:
    """Counts real builds (robotkit.pipeline.runner.build) made by the CLI."""

    def __init__(self, monkeypatch):
        self.n = 0
        real = robotkit.pipeline.runner.build

        def counted(*a, **k):
            self.n += 1
            return real(*a, **k)

        monkeypatch.setattr(robotkit.pipeline.runner, "build", counted)


def build(capsys) -> str:
    # -j 1: the CLI runs inside the test process, which holds other libraries' threads (rendering,
    # Drake): a doit worker forked from it could deadlock
    assert main(["build", "bot.yaml", "--out", "out", "-j", "1"]) == 0
    return capsys.readouterr().out.strip()


def bump(path: Path, text: str | None = None):
    """Change a file (or only its modification time) in a way a stamp must notice."""
    st = path.stat()
    if text is not None:
        path.write_text(text)
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000))


def scale_mesh(path: Path):
    import trimesh

    mesh = trimesh.load(path, force="mesh")
    mesh.apply_scale(1.1)
    mesh.export(path)


@pytest.mark.slow
def test_second_build_answers_from_the_stamp_and_changes_fall_through(project, capsys, monkeypatch):
    calls = Calls(monkeypatch)
    first = build(capsys)
    assert first.startswith("built out/bot: ") and calls.n == 1
    assert build(capsys).startswith("out/bot: up to date (") and calls.n == 1  # the stamp answered
    stamps = list((project / "out" / ".robotkit").glob("stamp-*.json"))
    assert len(stamps) == 1
    recorded = stamp.up_to_date("out", stamp.options(["bot.yaml"], "out"))
    assert recorded == {"robots": ["bot"], "tasks": recorded["tasks"], "warnings": recorded["warnings"]}

    # each change runs the real build once; the build after it answers from the stamp again
    from robotkit.emit.env import template_dirs

    template = sorted(Path(template_dirs()[0]).rglob("*.j2"))[0]
    template_times = template.stat()
    changes = [
        ("recipe", lambda: bump(project / "bot.yaml", RECIPE.replace("density: 1000", "density: 2000")), True),
        ("included file", lambda: bump(project / "parts.yaml", PARTS.replace("0.5, 0.5, 0.5", "0.4, 0.4, 0.4")),
         True),
        ("mesh", lambda: scale_mesh(project / "slider.stl"), True),
        ("template, touched only", lambda: bump(template), False),
        # the staged file is published again (robotkit.pipeline.publish): no task reruns
        ("output deleted", lambda: (project / "out" / "bot" / "urdf" / "bot.urdf").unlink(), False),
        # doit reruns a task for its inputs, not for an edited target: the real build decides
        ("output edited", lambda: bump(project / "out" / "bot" / "model.sdf", "<sdf/>\n"), False),
    ]
    try:
        for what, change, reruns_tasks in changes:
            before = calls.n
            change()
            out = build(capsys)
            assert calls.n == before + 1, what
            assert out.startswith("built out/bot: ") == reruns_tasks, (what, out)
            assert build(capsys).startswith("out/bot: up to date (") and calls.n == before + 1, what
    finally:
        os.utime(template, ns=(template_times.st_atime_ns, template_times.st_mtime_ns))
    assert (project / "out" / "bot" / "urdf" / "bot.urdf").is_file()


@pytest.mark.slow
def test_a_failed_build_removes_the_stamp(project, capsys, monkeypatch):
    calls = Calls(monkeypatch)
    build(capsys)
    bump(project / "bot.yaml", RECIPE.replace("density: 1000", "density: -1"))
    assert main(["build", "bot.yaml", "--out", "out", "-j", "1"]) == 2
    assert "density" in capsys.readouterr().err
    assert not list((project / "out" / ".robotkit").glob("stamp-*.json"))
    bump(project / "bot.yaml", RECIPE)  # back to what was built: doit finds every task up to date
    assert build(capsys).startswith("out/bot: up to date (") and calls.n == 3
    assert build(capsys).startswith("out/bot: up to date (") and calls.n == 3


@pytest.mark.slow
def test_another_output_folder_has_its_own_stamp(project, capsys, monkeypatch):
    calls = Calls(monkeypatch)
    build(capsys)
    assert main(["build", "bot.yaml", "--out", "other", "-j", "1"]) == 0
    assert capsys.readouterr().out.startswith("built other/bot: ") and calls.n == 2
    assert build(capsys).startswith("out/bot: up to date (") and calls.n == 2


@pytest.mark.slow
def test_a_no_op_build_imports_no_heavy_library(project, capsys):
    build(capsys)
    code = ("import sys; from robotkit.cli import main; rc = main(['build', 'bot.yaml', '--out', 'out']); "
            "heavy = sorted(m for m in ('numpy', 'pydantic', 'doit', 'jinja2', 'trimesh', 'yaml') if m in sys.modules); "
            "print(rc, heavy)")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=project, env=os.environ)
    assert p.stdout.strip().splitlines()[-1] == "0 []", p.stderr
