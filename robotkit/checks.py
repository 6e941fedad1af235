"""`robotkit check`: validators, physics lints, cross-format equivalence and a simulation
smoke test, folded into one list of findings and rendered for people, CI and editors.

PATH may be a recipe (built first), a build folder (``OUT/<robot>`` or ``OUT``), or a URDF,
SDF or MJCF file written anywhere (meshes resolved relative to it or via --package-path).
"""

from __future__ import annotations

import json
import shutil
import subprocess
from dataclasses import asdict, replace
from pathlib import Path

from robotkit.errors import Problem, RobotkitError
from robotkit.lint import Finding


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


def check_urdf_file(path: Path, package_paths: dict[str, str]) -> list[Finding]:
    from robotkit.lint import lint, read_urdf_facts

    links, joints, notes = read_urdf_facts(path, package_paths)
    return validate_urdf(path) + notes + lint(links, joints)


def check_build_dir(robot_dir: Path, declared_mass: float | None = None) -> list[Finding]:
    from robotkit.lint import lint, read_urdf_facts
    from robotkit.verify import equivalence, smoke_test

    name = robot_dir.name
    urdf, sdf = robot_dir / "urdf" / f"{name}.urdf", robot_dir / "model.sdf"
    mjcf, scene = robot_dir / "mjcf" / f"{name}.xml", robot_dir / "mjcf" / "scene.xml"
    for p in (urdf, sdf, mjcf, scene):
        if not p.is_file():
            raise RobotkitError(Problem(f"not a robotkit build folder: {p.relative_to(robot_dir)} is missing",
                                        file=str(robot_dir)))
    links, joints, notes = read_urdf_facts(urdf, {name: str(robot_dir)})
    findings = notes + lint(links, joints, declared_mass)
    validators = validate_urdf(urdf) + validate_sdf(sdf) + validate_mjcf(mjcf) + validate_mjcf(scene)
    findings += validators
    if any(f.severity == "error" for f in findings):
        return findings
    try:
        notes: list[str] = []
        for what, diffs in equivalence(robot_dir, notes=notes).items():
            findings += [Finding("error", "equivalence", f"robot '{name}'", f"{what}: {d}") for d in diffs]
        findings += [Finding("warning", "equivalence", f"robot '{name}'", n) for n in notes]
    except (RuntimeError, ValueError) as exc:
        findings.append(Finding("warning", "equivalence", f"robot '{name}'", str(exc)))
    sim_notes: list[str] = []
    findings += [Finding("error", "simulation", f"robot '{name}'", p,
                         "MuJoCo scene mjcf/scene.xml") for p in smoke_test(scene, notes=sim_notes)]
    findings += [Finding("warning", "simulation", f"robot '{name}'", n) for n in sim_notes]
    return findings


def check_recipe(path: Path, out_dir: str, args: dict[str, str] | None = None) -> list[Finding]:
    from robotkit.build import build
    from robotkit.recipe.load import load_recipes

    located = []
    result = build([path], out_dir, args=args)
    for i, loaded in enumerate(load_recipes(path, args)):  # one per variant
        name = loaded.recipe.robot
        others = [r for r in result.robots if r != name]
        # a warning naming another variant's robot belongs to that one; the rest to the first
        warnings = [w for w in result.warnings if w.startswith(f"{name}:")
                    or (i == 0 and not any(w.startswith(f"{o}:") for o in others))]
        located += _check_variant(loaded, warnings, out_dir)
    return located


def _check_variant(loaded, warnings: list[str], out_dir: str) -> list[Finding]:
    name = loaded.recipe.robot
    findings = [Finding("warning", "build", f"robot '{name}'", w) for w in warnings]
    findings += check_build_dir(Path(out_dir) / name, loaded.recipe.measured_mass)
    marks = loaded.marks
    located = []
    for f in findings:
        key = ("robot",)
        if f.subject.startswith("link '"):
            key = ("links", f.subject[6:-1])
        elif f.subject.startswith("joint '"):
            key = ("joints", f.subject[7:-1])
        file, line = marks.locate(key)
        located.append(replace(f, file=file, line=line))
    return located


def check(path: str, out_dir: str = "build", package_paths: dict[str, str] | None = None,
          args: dict[str, str] | None = None) -> list[Finding]:
    p = Path(path)
    package_paths = package_paths or {}
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
        return check_recipe(p, out_dir, args)
    if suffix == ".urdf":
        return check_urdf_file(p, package_paths)
    if suffix in (".sdf", ".world"):
        return validate_sdf(p) + _inertial_lints(p, "sdf")
    if suffix == ".xml":
        return validate_mjcf(p) or _inertial_lints(p, "mjcf")
    raise RobotkitError(Problem("unknown kind of file (expected a recipe .yaml, .urdf, .sdf or MJCF .xml)", file=path))


def _inertial_lints(path: Path, kind: str) -> list[Finding]:
    """Mass and inertia lints for SDF and MJCF files (their geometry is not measured yet)."""
    from robotkit.lint import LinkFacts, lint_link
    from robotkit.verify import kinematics as k

    try:
        model = k.read_sdf(path) if kind == "sdf" else k.read_mjcf(path)
    except Exception as exc:  # an invalid file is reported by its validator
        return [Finding("warning", "inertia", str(path), f"could not read inertials: {exc}")]
    out = []
    for link in model.links.values():
        if link.mass == 0 and not link.inertia.any():
            continue
        out += lint_link(LinkFacts(link.name, link.mass, link.com, link.inertia))
    return out


# ---------------------------------------------------------------- reports

SEVERITIES = ("error", "warning")


def render(findings: list[Finding], fmt: str, source: str) -> str:
    if fmt == "json":
        return json.dumps({"source": source, "errors": sum(f.severity == "error" for f in findings),
                           "warnings": sum(f.severity == "warning" for f in findings),
                           "findings": [asdict(f) for f in findings]}, indent=1) + "\n"
    if fmt == "junit":
        return _junit(findings, source)
    if fmt == "github":
        from robotkit.errors import display_path

        lines = []
        for f in findings:  # GitHub wants paths relative to the repository (the working directory)
            where = f"file={display_path(f.file)}" + (f",line={f.line}" if f.line else "") if f.file else ""
            text = f"{f.subject}: {f.message}" + (f" (hint: {f.hint})" if f.hint else "")
            text = text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")
            lines.append(f"::{f.severity} {where}{',' if where else ''}title=robotkit {f.check}::{text}"
                         .replace(" ,title", " title"))
        return "".join(line + "\n" for line in lines)
    if not findings:
        return f"{source}: ok, no problems found\n"
    groups: dict[str, list[Finding]] = {}
    for f in findings:
        groups.setdefault(f.subject, []).append(f)
    out = []
    for subject, items in groups.items():
        where = ""
        if items[0].file:
            from robotkit.errors import display_path

            where = f" ({display_path(items[0].file)}" + (f":{items[0].line}" if items[0].line else "") + ")"
        out.append(f"{subject}{where}")
        for f in items:
            out.append(f"  {f.severity}: {f.message} [{f.check}]")
            if f.hint:
                out.append(f"    hint: {f.hint}")
    errors = sum(f.severity == "error" for f in findings)
    warnings = len(findings) - errors
    out.append(f"{source}: {errors} error{'s' * (errors != 1)}, {warnings} warning{'s' * (warnings != 1)}")
    return "\n".join(out) + "\n"


def _junit(findings: list[Finding], source: str) -> str:
    """One test case per check and subject, so CI test reporters list them."""
    import xml.etree.ElementTree as ET

    cases: dict[tuple[str, str], list[Finding]] = {}
    for f in findings:
        cases.setdefault((f.check, f.subject), []).append(f)
    suite = ET.Element("testsuite", name=f"robotkit check {source}", tests=str(max(len(cases), 1)),
                       failures=str(sum(any(x.severity == "error" for x in v) for v in cases.values())),
                       errors="0", skipped="0")
    if not cases:
        ET.SubElement(suite, "testcase", classname="robotkit", name="all checks")
    for (check, subject), items in cases.items():
        case = ET.SubElement(suite, "testcase", classname=f"robotkit.{check}", name=subject)
        text = "\n".join(f"{f.severity}: {f.message}" + (f" (hint: {f.hint})" if f.hint else "") for f in items)
        if any(f.severity == "error" for f in items):
            ET.SubElement(case, "failure", message=items[0].message).text = text
        else:
            ET.SubElement(case, "system-out").text = text
    suites = ET.Element("testsuites")
    suites.append(suite)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(suites, encoding="unicode") + "\n"
