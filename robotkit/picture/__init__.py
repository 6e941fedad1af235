"""`robotkit report`: a picture report (report.html and its PNG pictures, one folder) of a
recipe, a build folder, or a URDF/SDF/MJCF file; and `robotkit view`, the live viewer.

    what PATH is        (here)                      a build folder is the common case
    pictures            (robotkit.picture.render)   MuJoCo offscreen, from the MJCF
    tables              (robotkit.picture.page)     the check package's facts and lints, report.json
    the page            templates/report/report.html.j2

A foreign URDF is imported into a recipe and built in a temporary folder (meshes of any
format, DAE among them, become what MuJoCo reads), its table read from the file itself.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

from robotkit.errors import Problem, RobotkitError

PAGE = "report.html"
VERSION = 1  # bump when the pictures or the page change for the same build


def write_report(path: str | os.PathLike, out_dir: str | os.PathLike | None = None, build_out: str = "build",
                 package_paths: dict[str, str] | None = None) -> Path:
    """Write ``out_dir/report.html`` and its pictures for PATH; return the page's path."""
    p = Path(path)
    package_paths = package_paths or {}
    if p.is_dir():
        robot_dir = _robot_dir(p)
        return report_build_dir(robot_dir, Path(out_dir) if out_dir else robot_dir / "report", str(p))
    if not p.is_file():
        raise RobotkitError(Problem("no such file or folder", file=str(path)))
    suffix = p.suffix.lower()
    if suffix in (".yaml", ".yml"):
        from robotkit.build import build
        from robotkit.recipe.load import load_recipe

        loaded = load_recipe(p)
        build([p], build_out, report=False)
        robot_dir = Path(build_out) / loaded.recipe.robot
        out = Path(out_dir) if out_dir else robot_dir / "report"
        return report_build_dir(robot_dir, out, str(p), loaded.recipe.measured_mass)
    if suffix == ".sdf" and (p.parent / "mjcf" / f"{p.parent.name}.xml").is_file():  # a build folder's SDF
        return report_build_dir(p.parent, Path(out_dir) if out_dir else p.parent / "report", str(p))
    out = Path(out_dir) if out_dir else p.parent / f"{p.stem}-report"
    if suffix == ".urdf":
        return report_urdf(p, out, package_paths)
    if suffix in (".xml", ".sdf", ".world"):
        return report_model_file(p, out, "sdf" if suffix != ".xml" else "mjcf")
    raise RobotkitError(Problem("unknown kind of file (expected a recipe .yaml, .urdf, .sdf or MJCF .xml)",
                                file=str(path)))


def _robot_dir(p: Path) -> Path:
    if (p / "model.sdf").is_file():
        return p
    dirs = sorted(d for d in p.iterdir() if (d / "model.sdf").is_file() and (d / "mjcf").is_dir())
    if len(dirs) == 1:
        return dirs[0]
    if not dirs:
        raise RobotkitError(Problem("not a build folder (no <robot>/model.sdf below it)", file=str(p)))
    raise RobotkitError(Problem(f"holds {len(dirs)} robots ({', '.join(d.name for d in dirs)}); name one folder",
                                file=str(p)))


def report_build_dir(robot_dir: Path, out: Path, source: str, declared_mass: float | None = None) -> Path:
    """The report of a robotkit build folder: pictures from mjcf/<robot>.xml, tables from the URDF
    (the check package's facts and lints) and report.json (collision fidelity, losses)."""
    from robotkit.check.lints import lint, read_urdf_facts
    from robotkit.picture import page

    name = robot_dir.name
    urdf, mjcf = robot_dir / "urdf" / f"{name}.urdf", robot_dir / "mjcf" / f"{name}.xml"
    for f in (urdf, mjcf):
        if not f.is_file():
            raise RobotkitError(Problem(f"not a robotkit build folder: {f.relative_to(robot_dir)} is missing",
                                        file=str(robot_dir)))
    links, joints, notes = read_urdf_facts(urdf, {name: str(robot_dir)})
    findings = notes + lint(links, joints, declared_mass)
    losses, collision = page.read_losses(robot_dir / "report.json")
    pictures = _pictures(mjcf, out, findings)
    return _write(out, name, source, pictures, links, joints, findings, losses, collision,
                  urdf.read_text(encoding="utf-8"))


def report_urdf(urdf: Path, out: Path, package_paths: dict[str, str]) -> Path:
    """A URDF written anywhere: its table from the file; its pictures from a build of its import."""
    from robotkit.check.lints import lint, read_urdf_facts

    links, joints, notes = read_urdf_facts(urdf, package_paths)
    findings = notes + lint(links, joints)
    text = urdf.read_text(encoding="utf-8")
    name = re.search(r"<robot[^>]*\bname=\"([^\"]+)\"", text)
    robot = name.group(1) if name else urdf.stem
    extra: list[str] = []
    with tempfile.TemporaryDirectory(prefix="robotkit-report-") as tmp:
        try:
            from robotkit.build import build
            from robotkit.importer import import_file

            result = import_file(str(urdf), Path(tmp) / "recipe.yaml", package_paths, {})
            build([Path(tmp) / "recipe.yaml"], Path(tmp) / "build", report=False)
            mjcf = Path(tmp) / "build" / result.robot / "mjcf" / f"{result.robot}.xml"
            pictures = _pictures(mjcf, out, findings)
        except RobotkitError as exc:
            pictures = []
            extra.append("No pictures: the URDF could not be built for MuJoCo: " + "; ".join(exc.lines()))
    return _write(out, robot, str(urdf), pictures, links, joints, findings, {}, {}, text, extra)


def report_model_file(path: Path, out: Path, kind: str) -> Path:
    """An SDF or MJCF file: masses and inertias (no geometry measured); pictures of an MJCF."""
    from robotkit.check import kinematics as k
    from robotkit.check.lints import JointFacts, LinkFacts, lint_link, lint_joints

    try:
        model = k.read_sdf(path) if kind == "sdf" else k.read_mjcf(path)
    except Exception as exc:  # noqa: BLE001  (any reader error is the file's problem)
        raise RobotkitError(Problem(f"cannot read: {str(exc).splitlines()[0] if str(exc) else exc!r}",
                                    file=str(path))) from None
    links = [LinkFacts(link.name, link.mass, link.com, link.inertia) for link in model.links.values()]
    joints = [JointFacts(j.name, j.type, j.lower, j.upper, j.effort, j.velocity, j.mimic[0] if j.mimic else None)
              for j in model.joints.values()]
    findings = [f for link in links if link.mass or link.inertia.any() for f in lint_link(link)]
    findings += lint_joints(joints)
    notes = []
    if kind == "mjcf":
        pictures = _pictures(path, out, findings)
    else:
        pictures = []
        notes.append("No pictures: an SDF file outside a robotkit build folder is not drawn yet (a URDF or MJCF is).")
    return _write(out, path.stem, str(path), pictures, links, joints, findings, {}, {}, None, notes)


def _pictures(mjcf: Path, out: Path, findings) -> list:
    from robotkit.picture.render import render_pictures

    flagged = {f.subject[6:-1] for f in findings if f.subject.startswith("link '")}
    pictures = render_pictures(mjcf, out, flagged)
    keep = {p.file for p in pictures}
    for old in out.glob("*.png"):  # pictures of joints that are gone
        if old.name not in keep:
            old.unlink()
    return pictures


def _write(out: Path, robot: str, source: str, pictures, links, joints, findings, losses, collision,
           urdf_text: str | None, notes=()) -> Path:
    from robotkit.ioutil import write_if_changed
    from robotkit.picture import page

    rows = page.link_rows(links, findings, losses, collision)
    jrows = page.joint_rows(urdf_text, joints, findings, losses)
    html = page.render_page(robot, source, pictures, rows, jrows, page.other_findings(findings, rows, jrows),
                            page.other_losses(losses, rows, jrows), notes)
    target = out / PAGE
    write_if_changed(target, html)
    return target
