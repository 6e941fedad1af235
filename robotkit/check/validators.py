"""The validators: check_urdf (urdfdom), `ign sdf -k` (libsdformat) and MuJoCo's compiler."""

from __future__ import annotations

import resource
import shutil
import subprocess
import tempfile
from pathlib import Path

from robotkit import mj
from robotkit.check import programs
from robotkit.check.findings import Finding


MAX_OUTPUT = 4 * 2**20
"""Most bytes of output kept from a validator (check_urdf prints a cyclic tree forever)."""
TIMEOUT = 300
"""Seconds a validator may run."""


def _limit_output():  # in the child: writing past MAX_OUTPUT to its output file ends it (SIGXFSZ)
    resource.setrlimit(resource.RLIMIT_FSIZE, (MAX_OUTPUT, MAX_OUTPUT))


def _run(cmd: list[str]) -> tuple[int, str]:
    """Run a validator with bounded output and time: (exit status, its output without noise)."""
    with tempfile.TemporaryFile() as f:
        proc = programs.popen(cmd, stdout=f, stderr=subprocess.STDOUT, preexec_fn=_limit_output)
        try:
            rc = proc.wait(timeout=TIMEOUT)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
            rc = -1
        f.seek(0)
        text = f.read(MAX_OUTPUT).decode("utf-8", "replace")
    if rc == -1:
        text += f"\nError: {cmd[0]} did not finish in {TIMEOUT} s"
    return rc, _without_noise(text)


def _without_noise(text: str) -> str:
    return "\n".join(line for line in text.splitlines() if "libignition-tools-backward" not in line).strip()


def validate_urdf(path: Path) -> list[Finding]:
    if shutil.which("check_urdf") is None:
        return [Finding("warning", "check_urdf", str(path), "check_urdf is not installed", "apt install liburdfdom-tools")]
    rc, out = _run(["check_urdf", str(path)])
    errors = [line for line in out.splitlines() if "Error" in line]
    if rc != 0 or errors:
        return [Finding("error", "check_urdf", str(path), (errors or out.splitlines() or [f"exit status {rc}"])[0])]
    return []


def validate_sdf(path: Path) -> list[Finding]:
    if shutil.which("ign") is None:
        return [Finding("warning", "ign sdf -k", str(path), "ign is not installed",
                        "apt install ignition-tools libsdformat-dev")]
    cmd = ["ign", "sdf", "-k", str(path)]
    if programs.is_started(cmd):  # a build folder's check: run once beside the other stages
        proc = programs.run(cmd)
        rc, out = proc.returncode, _without_noise(proc.stdout + proc.stderr)
    else:
        rc, out = _run(cmd)
    if rc != 0 or "Valid" not in out:
        # the first "Error Code" is the cause; the rest unwinds the element stack
        lines = [line for line in out.splitlines() if line.startswith("Error Code")] or out.splitlines()
        return [Finding("error", "ign sdf -k", str(path), (lines or [f"exit status {rc}"])[0])]
    return []


def validate_mjcf(path: Path) -> list[Finding]:
    try:  # heavy and optional: imported when an MJCF is validated (rendering off where it cannot work)
        mujoco = mj.load()
    except ImportError:
        return [Finding("warning", "mujoco", str(path), "mujoco is not installed", "pip install mujoco")]
    try:
        mujoco.MjModel.from_xml_path(str(path))
    except Exception as exc:  # MuJoCo raises ValueError with its compiler message
        return [Finding("error", "mujoco", str(path), " ".join(str(exc).split()))]
    return []
