"""The validators: check_urdf (urdfdom), `ign sdf -k` (libsdformat) and MuJoCo's compiler."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

from robotkit.check.findings import Finding


def _run(cmd: list[str]) -> tuple[int, str]:
    proc = subprocess.run(cmd, capture_output=True, text=True)
    out = "\n".join(line for line in (proc.stdout + proc.stderr).splitlines()
                    if "libignition-tools-backward" not in line)
    return proc.returncode, out.strip()


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
    rc, out = _run(["ign", "sdf", "-k", str(path)])
    if rc != 0 or "Valid" not in out:
        # the first "Error Code" is the cause; the rest unwinds the element stack
        lines = [line for line in out.splitlines() if line.startswith("Error Code")] or out.splitlines()
        return [Finding("error", "ign sdf -k", str(path), (lines or [f"exit status {rc}"])[0])]
    return []


def validate_mjcf(path: Path) -> list[Finding]:
    try:
        import mujoco
    except ImportError:
        return [Finding("warning", "mujoco", str(path), "mujoco is not installed", "pip install mujoco")]
    try:
        mujoco.MjModel.from_xml_path(str(path))
    except Exception as exc:  # MuJoCo raises ValueError with its compiler message
        return [Finding("error", "mujoco", str(path), " ".join(str(exc).split()))]
    return []
