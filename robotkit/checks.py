"""`robotkit check`: validators, cross-format equivalence and a simulation smoke test,
folded into one list of findings.

PATH may be a recipe (built first into ``build/``), a build folder (``OUT/<robot>``), or a
URDF, SDF or MJCF file (its validator only, for now).
"""

from __future__ import annotations

import json
import shutil
import subprocess
from dataclasses import asdict, dataclass
from pathlib import Path

from robotkit.errors import Problem, RobotkitError


@dataclass(frozen=True)
class Finding:
    severity: str  # error | warning
    check: str  # e.g. "equivalence", "check_urdf"
    subject: str  # robot, file or link
    message: str

    def __str__(self) -> str:
        return f"{self.severity}: {self.subject}: [{self.check}] {self.message}"


def _run(cmd: list[str]) -> tuple[int, str]:
    proc = subprocess.run(cmd, capture_output=True, text=True)
    out = "\n".join(line for line in (proc.stdout + proc.stderr).splitlines()
                    if "libignition-tools-backward" not in line)
    return proc.returncode, out.strip()


def validate_urdf(path: Path) -> list[Finding]:
    if shutil.which("check_urdf") is None:
        return [Finding("warning", "check_urdf", str(path), "check_urdf is not installed (Debian: liburdfdom-tools)")]
    rc, out = _run(["check_urdf", str(path)])
    if rc != 0 or "Error" in out:
        return [Finding("error", "check_urdf", str(path), out.splitlines()[-1] if out else f"exit status {rc}")]
    return []


def validate_sdf(path: Path) -> list[Finding]:
    if shutil.which("ign") is None:
        return [Finding("warning", "ign sdf -k", str(path), "ign is not installed (Debian: ignition-tools, libsdformat-dev)")]
    rc, out = _run(["ign", "sdf", "-k", str(path)])
    if rc != 0 or "Valid" not in out:
        return [Finding("error", "ign sdf -k", str(path), out or f"exit status {rc}")]
    return []


def validate_mjcf(path: Path) -> list[Finding]:
    try:
        import mujoco
    except ImportError:
        return [Finding("warning", "mujoco", str(path), "mujoco is not installed (pip install mujoco)")]
    try:
        mujoco.MjModel.from_xml_path(str(path))
    except Exception as exc:  # MuJoCo raises ValueError with its compiler message
        return [Finding("error", "mujoco", str(path), str(exc).strip())]
    return []


def check_build_dir(robot_dir: Path) -> list[Finding]:
    from robotkit.verify import equivalence, smoke_test

    name = robot_dir.name
    urdf, sdf = robot_dir / "urdf" / f"{name}.urdf", robot_dir / "model.sdf"
    mjcf, scene = robot_dir / "mjcf" / f"{name}.xml", robot_dir / "mjcf" / "scene.xml"
    for p in (urdf, sdf, mjcf, scene):
        if not p.is_file():
            raise RobotkitError(Problem(f"not a robotkit build folder: {p.relative_to(robot_dir)} is missing",
                                        file=str(robot_dir)))
    findings = validate_urdf(urdf) + validate_sdf(sdf) + validate_mjcf(mjcf) + validate_mjcf(scene)
    if any(f.severity == "error" for f in findings):
        return findings
    try:
        for what, diffs in equivalence(robot_dir).items():
            findings += [Finding("error", "equivalence", name, f"{what}: {d}") for d in diffs]
    except RuntimeError as exc:
        findings.append(Finding("warning", "equivalence", name, str(exc)))
    findings += [Finding("error", "simulation", name, p) for p in smoke_test(scene)]
    return findings


def check(path: str, out_dir: str = "build") -> list[Finding]:
    p = Path(path)
    if p.is_dir():
        if (p / "model.sdf").is_file():
            return check_build_dir(p)
        dirs = sorted(d for d in p.iterdir() if (d / "model.sdf").is_file() and (d / "mjcf").is_dir())
        if not dirs:
            raise RobotkitError(Problem("not a build folder (no <robot>/model.sdf below it)", file=path))
        return [f for d in dirs for f in check_build_dir(d)]
    if not p.is_file():
        raise RobotkitError(Problem("no such file or folder", file=path))
    suffix = p.suffix.lower()
    if suffix in (".yaml", ".yml"):
        from robotkit.build import build

        result = build([p], out_dir)
        return [f for name in result.robots for f in check_build_dir(Path(out_dir) / name)]
    if suffix == ".urdf":
        return validate_urdf(p)
    if suffix in (".sdf", ".world"):
        return validate_sdf(p)
    if suffix == ".xml":
        return validate_mjcf(p)
    raise RobotkitError(Problem("unknown kind of file (expected a recipe .yaml, .urdf, .sdf or MJCF .xml)", file=path))


def render(findings: list[Finding], fmt: str) -> str:
    if fmt == "json":
        return json.dumps({"findings": [asdict(f) for f in findings],
                           "errors": sum(f.severity == "error" for f in findings),
                           "warnings": sum(f.severity == "warning" for f in findings)}, indent=1) + "\n"
    if not findings:
        return "ok: no problems found\n"
    return "".join(f"{f}\n" for f in findings)
