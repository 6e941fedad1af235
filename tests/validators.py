"""The real validators the tests run: check_urdf, ign sdf -k, MuJoCo.

A missing validator skips the test on a developer's machine and fails it under
CI (CI=true): CI must never pass because a validator was absent.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")


def require(tool: str) -> str:
    path = shutil.which(tool)
    if path is None:
        msg = f"validator '{tool}' is not installed (scripts/test.sh installs it)"
        if IN_CI:
            pytest.fail(msg)
        pytest.skip(msg)
    return path


def check_urdf(path: str | Path) -> str:
    """Run check_urdf; fail the test unless it accepts the file.  Returns its output."""
    exe = require("check_urdf")
    proc = subprocess.run([exe, str(path)], capture_output=True, text=True)
    out = proc.stdout + proc.stderr
    # check_urdf may print "Error" and still exit 0 (docs/libraries.md, section 8)
    assert proc.returncode == 0 and "Error" not in out, f"check_urdf rejected {path}:\n{out}"
    return out


def ign_sdf_check(path: str | Path) -> str:
    """Run `ign sdf -k`; fail the test unless it prints Valid."""
    exe = require("ign")
    proc = subprocess.run([exe, "sdf", "-k", str(path)], capture_output=True, text=True)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0 and "Valid" in proc.stdout, f"ign sdf -k rejected {path}:\n{out}"
    return out


def mujoco():
    """The mujoco module, or skip (fail under CI)."""
    try:
        import mujoco as mj
    except ImportError:
        if IN_CI:
            pytest.fail("mujoco is not installed (pip install '.[test]')")
        pytest.skip("mujoco is not installed")
    return mj
