"""The picture report (report.html and its PNG pictures, one folder) of a build folder, a URDF
or an SDF/MJCF file; and the live viewer (``picture.viewer``).

    pictures            (robotkit.picture.render)   MuJoCo offscreen, from the MJCF
    tables              (robotkit.picture.page)     the check package's facts and lints, report.json
    the page            templates/report/report.html.j2

What PATH is, and building a recipe or a foreign URDF for its pictures, is
``robotkit.commands.report``'s job.
"""

from __future__ import annotations

import re
from pathlib import Path, PurePosixPath

from robotkit.check.kinematics import read_mjcf, read_sdf
from robotkit.check.lints import JointFacts, LinkFacts, lint, lint_joints, lint_link, read_urdf_facts
from robotkit.emit.layout import REPORT_HTML, robot_layout
from robotkit import mj
from robotkit.errors import Problem, RendererUnavailable, RobotkitError
from robotkit.ioutil import write_if_changed
from robotkit.picture import page
from robotkit.picture.plots import step_plots

PAGE = PurePosixPath(REPORT_HTML).name  # report.html, in whichever folder the report is written
VERSION = 3  # 2: strips without multisampling; 3: strips in one framebuffer, own PNG writer, BRIEF_JOINTS
# bump VERSION when the pictures or the page change for the same build


def report_build_dir(robot_dir: Path, out: Path, source: str, declared_mass: float | None = None,
                     no_pictures: str | None = None, motion: dict | None = None) -> Path:
    """The report of a robotkit build folder: pictures from mjcf/<robot>.xml, tables from the URDF
    (the check package's facts and lints) and report.json (collision fidelity, losses).
    ``no_pictures``: draw none, and say why on the page (MuJoCo cannot draw here); ``motion``:
    the motion stage's results, plotted."""
    layout = robot_layout(robot_dir)
    name, urdf, mjcf = layout.name, layout.urdf, layout.mjcf
    for f in (urdf, mjcf) if no_pictures is None else (urdf,):  # no pictures, no MJCF needed
        if not f.is_file():
            raise RobotkitError(Problem(f"not a robotkit build folder: {f.relative_to(robot_dir)} is missing",
                                        file=str(robot_dir)))
    links, joints, notes = read_urdf_facts(urdf, {name: str(robot_dir)})
    findings = notes + lint(links, joints, declared_mass)
    losses, collision = page.read_losses(layout.report_json)
    pictures = _pictures(mjcf, out, findings) if no_pictures is None else []
    return _write(out, name, source, pictures, links, joints, findings, losses, collision,
                  urdf.read_text(encoding="utf-8"), [no_pictures] if no_pictures else [], step_plots(motion))


def report_urdf(urdf: Path, out: Path, package_paths: dict[str, str], mjcf: Path | None,
                notes: list[str]) -> Path:
    """A URDF written anywhere: its table from the file; its pictures from ``mjcf`` (the MJCF of a
    build of its import), none when that could not be built (``notes`` say why)."""
    links, joints, lint_notes = read_urdf_facts(urdf, package_paths)
    findings = lint_notes + lint(links, joints)
    text = urdf.read_text(encoding="utf-8")
    name = re.search(r"<robot[^>]*\bname=\"([^\"]+)\"", text)
    robot = name.group(1) if name else urdf.stem
    pictures = _pictures(mjcf, out, findings) if mjcf is not None else []
    return _write(out, robot, str(urdf), pictures, links, joints, findings, {}, {}, text, notes)


def report_model_file(path: Path, out: Path, kind: str) -> Path:
    """An SDF or MJCF file: masses and inertias (no geometry measured); pictures of an MJCF."""
    try:
        model = read_sdf(path) if kind == "sdf" else read_mjcf(path)
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
    """The pictures of ``mjcf`` drawn into ``out``; RendererUnavailable when MuJoCo cannot draw here."""
    if mj.GL_FAILURE:  # MuJoCo was imported earlier in this process without a GL backend
        raise RendererUnavailable(mj.GL_FAILURE[0])
    try:
        from robotkit.picture.render import render_pictures  # imports MuJoCo (heavy): only to draw
    except Exception as exc:  # noqa: BLE001  (MuJoCo's GL backend fails at import: MUJOCO_GL, no OSMesa)
        raise RendererUnavailable.because(exc) from None

    pictures = render_pictures(mjcf, out, page.flagged_links(findings))
    keep = {p.file for p in pictures}
    for old in out.glob("*.png"):  # pictures of joints that are gone
        if old.name not in keep:
            old.unlink()
    return pictures


def _write(out: Path, robot: str, source: str, pictures, links, joints, findings, losses, collision,
           urdf_text: str | None, notes=(), plots=()) -> Path:
    rows = page.link_rows(links, findings, losses, collision)
    jrows = page.joint_rows(urdf_text, joints, findings, losses)
    html = page.render_page(robot, source, pictures, rows, jrows, page.other_findings(findings, rows, jrows),
                            page.other_losses(losses, rows, jrows), notes, plots)
    target = out / PAGE
    write_if_changed(target, html)
    return target
