"""Every ``robotkit`` command in README.md's code blocks runs as shown: exit status 0 (2 for the
bad-input example), and where the README shows the output, that output (numbers aside: task
counts and times vary).

Each block runs in a scratch folder of its own holding ``recipes/`` and ``docs/examples/`` (the
files the commands name), with ``HOME`` there too (``--out ~/catkin_ws/src``), so blocks do not
depend on each other's builds; the commands of a block run in order.  ``robotkit view`` serves
until stopped: it runs on a free port without a browser, and passes when it serves the page.
The quick start and the build transcript run verbatim on a fresh clone in
tests/docs/test_fresh_install.py as well.
"""

from __future__ import annotations

import itertools
import os
import re
import shlex
import shutil
import socket
import subprocess
import sys
import time
import urllib.request

import pytest

from conftest import REPO

pytestmark = [pytest.mark.slow]

README = REPO / "README.md"
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.S | re.M)
NUMBER = re.compile(r"\d+(?:\.\d+)?")
EXIT = {"robotkit build docs/examples/bad_arm.yaml": 2}
"""Exit statuses other than 0 (the README says bad input exits 2)."""


def commands(markdown: str) -> list[tuple[int, str, list[str]]]:
    """(block index, command, the output the README shows under it) for every robotkit command
    in the fenced code blocks: shell lines (``.venv/bin/robotkit``, after ``&&``, continued with
    ``\\``) and transcript lines (``$ robotkit ...`` followed by its output)."""
    out = []
    for index, match in enumerate(FENCE.finditer(markdown)):
        if match.group(1) not in ("sh", ""):  # YAML and other files: no commands
            continue
        lines = match.group(2).replace("\\\n", " ").splitlines()
        for i, line in enumerate(lines):
            transcript = line.startswith("$ ")
            for part in (line[2:] if transcript else line).split("&&"):
                if "robotkit" not in part:
                    continue
                words = shlex.split(part, comments=True)
                if not words or words[0].rsplit("/", 1)[-1] != "robotkit":
                    continue
                shown = []
                if transcript:
                    shown = list(itertools.takewhile(lambda s: not s.startswith("$ "), lines[i + 1:]))
                out.append((index, shlex.join(["robotkit", *words[1:]]), shown))
    return out


def test_the_readme_commands_are_found():
    """The extraction itself, against the README as it is (a command added to the README is run
    by test_every_readme_command_runs_as_shown without more ado)."""
    found = [c for _, c, _ in commands(README.read_text(encoding="utf-8"))]
    assert "robotkit build recipes/turret_bot.yaml" in found
    assert "robotkit check build/turret_bot" in found
    assert "robotkit view recipes/turret_bot.yaml" in found
    assert "robotkit build docs/examples/bad_arm.yaml" in found
    assert ("robotkit import docs/examples/their_robot_description/urdf/their_robot.urdf.xacro --package-path "
            "their_robot_description=docs/examples/their_robot_description --arg use_gripper:=true -o "
            "their_robot.yaml") in found
    assert not [c for c in found if "recipes/arm.yaml" in c or "their_robot.urdf " in c]


def _scratch(root) -> dict:
    """A folder with what the README's commands read; the environment they run in."""
    shutil.copytree(REPO / "recipes", root / "recipes")
    shutil.copytree(REPO / "docs" / "examples", root / "docs" / "examples")
    (root / "home").mkdir()
    return {**os.environ, "HOME": str(root / "home"),
            "PATH": os.path.dirname(sys.executable) + os.pathsep + os.environ["PATH"]}


def _robotkit(command: str, env: dict) -> list[str]:
    """The command line, run by this Python, ``~`` being the scratch home as a shell would have it."""
    return [sys.executable, "-m", "robotkit",
            *(env["HOME"] + w[1:] if w.startswith("~/") else w for w in shlex.split(command)[1:])]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _view(command: str, cwd, env) -> str | None:
    """Serve ``command`` on a free port; None once the page is served, else what went wrong."""
    port = _free_port()
    proc = subprocess.Popen(_robotkit(command, env) + ["--port", str(port), "--no-browser"], cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 180
        while time.monotonic() < deadline and proc.poll() is None:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=5) as page:
                    if page.status == 200:
                        return None
            except OSError:
                time.sleep(1)
        return f"not served (exit status {proc.poll()})"
    finally:
        proc.terminate()
        try:
            proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()


def _matches(shown: list[str], got: str) -> bool:
    return [NUMBER.sub("#", s) for s in shown] == [NUMBER.sub("#", s) for s in got.splitlines()]


def test_every_readme_command_runs_as_shown(tmp_path):
    failures = []
    scratch = {}
    for block, command, shown in commands(README.read_text(encoding="utf-8")):
        cwd = tmp_path / f"block{block}"
        if block not in scratch:
            scratch[block] = _scratch(cwd)
        env = scratch[block]
        if command.startswith("robotkit view "):
            if (why := _view(command, cwd, env)) is not None:
                failures.append(f"{command}: {why}")
            continue
        proc = subprocess.run(_robotkit(command, env), cwd=cwd, env=env, capture_output=True, text=True)
        if proc.returncode != EXIT.get(command, 0) or "Traceback" in proc.stderr:
            failures.append(f"{command}: exit status {proc.returncode}\n{proc.stdout[-2000:]}{proc.stderr[-2000:]}")
        elif shown and not (_matches(shown, proc.stdout) or _matches(shown, proc.stderr)):
            failures.append(f"{command}: the README shows\n" + "\n".join(shown) + f"\ngot\n{proc.stdout}{proc.stderr}")
    assert not failures, "\n\n".join(failures)
