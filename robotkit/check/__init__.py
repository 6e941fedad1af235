"""`robotkit check`: validators, physics lints, cross-format equivalence and a simulation
smoke test, folded into one list of findings and rendered for people, CI and editors.

PATH may be a recipe (built first), a build folder (``OUT/<robot>`` or ``OUT``), or a URDF,
SDF or MJCF file written anywhere (meshes resolved relative to it or via --package-path).
"""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

from robotkit.check.findings import Finding
from robotkit.check.locate import locate
from robotkit.check.report import render  # noqa: F401  (the CLI renders through here)
from robotkit.check.validators import validate_mjcf, validate_sdf, validate_urdf
from robotkit.errors import Problem, RobotkitError


URDF_CONSUMERS = ["Gazebo (URDF)", "Drake (URDF)", "Pinocchio (URDF)", "PyBullet (URDF)"]


def _stage(name: str, subject: str, run) -> list[Finding]:
    """One stage of the check; a stage that cannot run is a finding with its reason, never
    a silent skip."""
    try:
        return run()
    except Exception as exc:  # a stage's own failure is reported: the other stages still run
        return [Finding("error", name, subject, f"the {name} stage could not run: {type(exc).__name__}: {exc}")]


def check_urdf_file(path: Path, package_paths: dict[str, str]) -> list[Finding]:
    """Findings on a URDF, each located at its link's or joint's line.  A broken tree (a
    cycle, a second parent, a missing link) is found here first: the validators and
    consumers are not given it (check_urdf prints a cycle forever, simulators crash)."""
    from robotkit.check.consumers import Build, consumer_findings
    from robotkit.check.lints import lint, read_urdf_facts
    from robotkit.importer.package_xml import with_own_package

    package_paths = with_own_package(path.absolute(), package_paths)
    try:
        links, joints, notes = read_urdf_facts(path, package_paths)
    except (ValueError, TypeError) as exc:  # numbers that are not numbers
        raise RobotkitError(Problem(f"not a valid URDF: {exc}", file=str(path))) from None
    lines, tree = urdf_tree(path)
    findings = notes + lint(links, joints) + tree
    if not tree:
        findings = validate_urdf(path) + findings
        build = Build(path.stem, path.parent, path, None, None, package_paths=package_paths, foreign=True)
        findings += _stage("consumers", f"robot '{path.stem}'", lambda: consumer_findings(build, URDF_CONSUMERS)[0])
    return locate([f if f.file or f.subject not in lines else replace(f, file=str(path), line=lines[f.subject])
                   for f in findings], path)


def check_xacro_file(path: Path, package_paths: dict[str, str], args: dict[str, str]) -> list[Finding]:
    """A xacro file expanded in the import's sandbox (``$(find)`` through ``package_paths``,
    ``args`` as xacro arguments), then checked as the URDF it expands to; findings name the
    xacro file."""
    import tempfile

    from robotkit.importer.package_xml import with_own_package
    from robotkit.importer.xacro_expand import check_package_paths, expand

    packages = with_own_package(path.absolute(), check_package_paths(package_paths))
    text = expand(path, packages, args).text

    def absolute(m: re.Match) -> str:  # relative mesh paths stay relative to the xacro file
        uri = m.group(2)
        if "://" in uri or Path(uri).is_absolute():
            return m.group(0)
        return f'{m.group(1)}{(path.parent / uri).absolute().as_posix()}{m.group(3)}'

    text = re.sub(r'(<mesh\b[^>]*?\bfilename=")([^"]*)(")', absolute, text)
    stem = path.name.removesuffix(".xacro").removesuffix(".urdf")
    with tempfile.TemporaryDirectory(prefix="robotkit-check-") as tmp:
        urdf = Path(tmp) / f"{stem}.urdf"
        urdf.write_text(text, encoding="utf-8")
        findings = check_urdf_file(urdf, packages)
    # the expanded file vanishes: findings in it are placed in the xacro file (on the element
    # when the name is written there literally)
    moved = [replace(f, subject=str(path) if f.subject == str(urdf) else f.subject,
                     file=None if f.file == str(urdf) else f.file, line=None if f.file == str(urdf) else f.line)
             for f in findings]
    return locate(moved, path)


def urdf_tree(path: Path) -> tuple[dict[str, int], list[Finding]]:
    """(subject -> line of each ``<link>`` and ``<joint>``, findings on the kinematic tree)."""
    from lxml import etree

    from robotkit.check.consumers import parse_urdf

    try:
        root = parse_urdf(path).getroot()
    except (etree.XMLSyntaxError, OSError) as exc:
        raise RobotkitError(Problem(f"not well-formed XML: {exc}", file=str(path))) from None
    lines = {f"{e.tag} '{e.get('name')}'": e.sourceline for e in root if e.tag in ("link", "joint")}
    links = {e.get("name") for e in root.iter("link") if e.getparent() is root}
    found: list[Finding] = []

    def bad(joint, message):
        found.append(Finding("error", "tree", f"joint '{joint.get('name')}'", message, file=str(path),
                             line=joint.sourceline))

    parent_of: dict[str, str] = {}
    for j in (e for e in root if e.tag == "joint"):
        ends = {}
        for end in ("parent", "child"):
            el = j.find(end)
            ends[end] = el.get("link") if el is not None else None
            if ends[end] not in links:
                bad(j, f"its {end} link {ends[end]!r} is not a link of the robot")
        child = ends["child"]
        if child in parent_of:
            bad(j, f"link '{child}' already has a parent ('{parent_of[child]}'); a link has at most one")
        elif child in links and ends["parent"] in links:
            parent_of[child] = ends["parent"]
    cycles = set()
    for start in sorted(parent_of):
        seen, node = [], start
        while node in parent_of and node not in seen:
            seen.append(node)
            node = parent_of[node]
        if node == start and frozenset(seen) not in cycles:
            cycles.add(frozenset(seen))
            found.append(Finding("error", "tree", f"link '{start}'", "its joints form a cycle: "
                                 + " <- ".join(seen + [start]), file=str(path), line=lines.get(f"link '{start}'")))
    return lines, found


def check_build_dir(robot_dir: Path, declared_mass: float | None = None) -> list[Finding]:
    """Every stage on a build folder: lints, validators, equivalence of the formats, what each
    consuming program sees, and the MuJoCo scene's own simulation.  Every stage always runs."""
    from robotkit.check.consumers import Build, consumer_findings
    from robotkit.check.equivalence import equivalence
    from robotkit.check.lints import lint, read_urdf_facts
    from robotkit.check.simulation import smoke_test

    name = robot_dir.name
    urdf, sdf = robot_dir / "urdf" / f"{name}.urdf", robot_dir / "model.sdf"
    mjcf, scene = robot_dir / "mjcf" / f"{name}.xml", robot_dir / "mjcf" / "scene.xml"
    for p in (urdf, sdf, mjcf, scene):
        if not p.is_file():
            raise RobotkitError(Problem(f"not a robotkit build folder: {p.relative_to(robot_dir)} is missing",
                                        file=str(robot_dir)))
    subject = f"robot '{name}'"
    links, joints, notes = read_urdf_facts(urdf, {name: str(robot_dir)})
    findings = notes + lint(links, joints, declared_mass)
    findings += validate_urdf(urdf) + validate_sdf(sdf) + validate_mjcf(mjcf) + validate_mjcf(scene)

    def equivalent() -> list[Finding]:
        return [Finding("error", "equivalence", subject, f"{what}: {d}")
                for what, diffs in equivalence(robot_dir).items() for d in diffs]

    base = "free" if "<freejoint" in mjcf.read_text(encoding="utf-8") else "fixed"
    build = Build(name, robot_dir, urdf, sdf, mjcf, base)
    findings += _stage("equivalence", subject, equivalent)
    findings += _stage("consumers", subject, lambda: consumer_findings(build)[0])
    def simulate() -> list[Finding]:
        notes: list[str] = []
        problems = smoke_test(scene, notes=notes)
        return ([Finding("error", "simulation", subject, p, "MuJoCo scene mjcf/scene.xml") for p in problems]
                + [Finding("warning", "simulation", subject, n, "MuJoCo scene mjcf/scene.xml") for n in notes])

    findings += _stage("simulation", subject, simulate)
    return findings


def check_recipe(path: Path, out_dir: str, args: dict[str, str] | None = None, report: bool = False) -> list[Finding]:
    from robotkit.build import build
    from robotkit.buildwarn import parse
    from robotkit.recipe.load import load_recipes

    located = []
    result = build([path], out_dir, args=args, report=report)
    warnings = [parse(w) for w in result.warning_lines]  # (file, line, key, text)
    for i, loaded in enumerate(load_recipes(path, args)):  # one per variant
        name = loaded.recipe.robot
        others = [r for r in result.robots if r != name]
        # a warning naming another variant's robot belongs to that one; the rest to the first
        mine = [w for w in warnings if w[3].startswith(f"{name}:")
                or (i == 0 and not any(w[3].startswith(f"{o}:") for o in others))]
        located += _check_variant(loaded, mine, out_dir)
    return located


def _check_variant(loaded, warnings: list[tuple], out_dir: str) -> list[Finding]:
    name = loaded.recipe.robot
    build_findings = [Finding("warning", "build", key or f"robot '{name}'", text, file=file, line=line)
                      for file, line, key, text in warnings]
    findings = check_build_dir(Path(out_dir) / name, loaded.recipe.measured_mass)
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
    return [f if f.file else replace(f, **dict(zip(("file", "line"), marks.locate(("robot",)))))
            for f in build_findings] + located


def check(path: str, out_dir: str = "build", package_paths: dict[str, str] | None = None,
          args: dict[str, str] | None = None, report: bool = False) -> list[Finding]:
    """``report``: a recipe's build also writes its picture report (as ``robotkit build`` does)."""
    p = Path(path)
    package_paths = package_paths or {}
    if p.is_dir():
        if (p / "model.sdf").is_file():
            dirs = [p]
        else:
            dirs = sorted(d for d in p.iterdir() if (d / "model.sdf").is_file() and (d / "mjcf").is_dir())
        if not dirs:
            raise RobotkitError(Problem("not a build folder (no <robot>/model.sdf below it)", file=path))
        # a build folder's findings point at its URDF
        return [f for d in dirs for f in locate(check_build_dir(d), d / "urdf" / f"{d.name}.urdf")]
    if not p.is_file():
        raise RobotkitError(Problem("no such file or folder", file=path))
    suffix = p.suffix.lower()
    if suffix in (".yaml", ".yml"):
        return check_recipe(p, out_dir, args, report)
    if suffix == ".urdf":
        return check_urdf_file(p, package_paths)
    if suffix == ".xacro":
        return check_xacro_file(p, package_paths, args or {})
    if suffix in (".sdf", ".world"):
        return locate(validate_sdf(p) + _inertial_lints(p, "sdf"), p)
    if suffix == ".xml":
        return locate(validate_mjcf(p) or _inertial_lints(p, "mjcf"), p)
    raise RobotkitError(Problem("unknown kind of file (expected a recipe .yaml, .urdf, .xacro, .sdf or MJCF .xml)",
                                file=path))


def _inertial_lints(path: Path, kind: str) -> list[Finding]:
    """Mass and inertia lints for SDF and MJCF files (their geometry is not measured yet)."""
    from robotkit.check.lints import LinkFacts, lint_link
    from robotkit.check import kinematics as k

    try:
        model = k.read_sdf(path) if kind == "sdf" else k.read_mjcf(path)
    except Exception as exc:  # an invalid file is reported by its validator
        return [Finding("warning", "inertia", str(path), f"could not read inertials: {exc}")]
    out = []
    if kind == "sdf":  # what Gazebo and Drake will see: SDF's default for a link without <inertial>
        import xml.etree.ElementTree as ET

        for el in ET.parse(path).getroot().iter("link"):
            if el.find("inertial") is None:
                out.append(Finding("error", "consumer", f"link '{el.get('name')}'",
                                   "has no <inertial>: Gazebo and Drake give it a mass of 1 kg and a unit inertia",
                                   "give it an <inertial>, or make a massless thing a <frame>", file=str(path)))
    for link in model.links.values():
        if link.mass == 0 and not link.inertia.any():
            continue
        out += lint_link(LinkFacts(link.name, link.mass, link.com, link.inertia))
    return out


def cases(path: str, out_dir: str = "build", args: dict[str, str] | None = None) -> list[tuple[str, str]]:
    """Every (check, subject) that a check of ``path`` ran, named as its findings name them, so
    CI reports list what passed too: each validator on each file, the equivalence, consumer and
    simulation stages on the robot, and the physics lints (``lints``) on each link and joint."""
    from robotkit.check.locate import element_lines

    p = Path(path)

    def described(file: Path) -> list[tuple[str, str]]:
        names = element_lines(file)
        return [("lints", f"{'link' if tag in ('link', 'body') else 'joint'} '{name}'")
                for (tag, name) in names if tag in ("link", "joint", "body")]

    def folder(d: Path) -> list[tuple[str, str]]:
        name, robot = d.name, f"robot '{d.name}'"
        urdf = d / "urdf" / f"{name}.urdf"
        files = [("check_urdf", urdf), ("ign sdf -k", d / "model.sdf"), ("mujoco", d / "mjcf" / f"{name}.xml"),
                 ("mujoco", d / "mjcf" / "scene.xml")]
        return ([(c, str(f)) for c, f in files] + [(c, robot) for c in ("equivalence", "consumer", "simulation")]
                + described(urdf))

    if p.is_dir():
        dirs = [p] if (p / "model.sdf").is_file() else sorted(
            d for d in p.iterdir() if (d / "model.sdf").is_file() and (d / "mjcf").is_dir())
        return [c for d in dirs for c in folder(d)]
    suffix = p.suffix.lower()
    if suffix in (".yaml", ".yml"):
        from robotkit.recipe.load import load_recipes

        return [c for loaded in load_recipes(p, args) for c in folder(Path(out_dir) / loaded.recipe.robot)]
    if suffix == ".urdf":
        return [("check_urdf", str(p)), ("consumer", f"robot '{p.stem}'")] + described(p)
    if suffix == ".xacro":
        return [("check_urdf", str(p)), ("consumer", f"robot '{p.name.removesuffix('.xacro').removesuffix('.urdf')}'")]
    if suffix in (".sdf", ".world"):
        return [("ign sdf -k", str(p))]
    return [("mujoco", str(p))]
