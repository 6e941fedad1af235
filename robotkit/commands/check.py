"""``robotkit check PATH...``: what each PATH is (:mod:`robotkit.commands.inputs`), a recipe
built first (:mod:`robotkit.pipeline.runner`), then the check stages (:mod:`robotkit.check`) and
the findings rendered for people, CI and editors.  Exit 0 clean, 1 problems, 2 bad input."""

from __future__ import annotations

import os
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from robotkit.check import (MJCF_STAGES, Clock, check_build_dir, check_model_file, check_urdf_file, check_xacro_file,
                            mjcf_left_out, xacro_robot)
from robotkit.check.findings import Finding, input_findings
from robotkit.check.locate import element_lines, locate
from robotkit.check.render import job_summary, render, skipped_case
from robotkit.commands.build import cores
from robotkit.commands.inputs import classify, package_paths
from robotkit.emit.layout import RobotLayout, robot_layout
from robotkit.errors import RobotkitError


def load_recipes(path, args: dict[str, str] | None = None, variant: str | None = None):
    """robotkit.recipe.load.load_recipes, imported when a recipe is checked: the recipe schema
    (pydantic) and the build are no part of a build folder's check."""
    from robotkit.recipe.load import load_recipes as load

    return load(path, args, variant)


def run(args) -> int:
    packages = package_paths(args.package_path)
    if packages is None:
        return 2
    if args.jobs is not None and args.jobs < 1:
        print("robotkit: error: -j must be at least 1", file=sys.stderr)
        return 2
    if args.temp_out:
        with tempfile.TemporaryDirectory(prefix="robotkit-check-") as out:
            args.out = out
            return _check_paths(args, packages)
    return _check_paths(args, packages)


def _check_paths(args, packages: dict[str, str]) -> int:
    """Every PATH in turn; bad input (exit 2) is reported in the chosen format too, so a CI
    report never comes out empty, and its lines go to stderr as always."""
    findings, status, ran, motion, timings = [], 0, [], {}, {}
    start = time.perf_counter()
    for path in args.paths:
        try:  # a recipe is built as `robotkit build` builds it; its picture report for GitHub's summary,
            # or kept when an earlier build wrote one (None), never drawn anew only for a check
            report = False if args.no_report or args.temp_out else (True if args.format == "github" else None)
            findings += check(path, args.out, packages, args=dict(args.arg), report=report, motion=motion,
                              variant=args.variant, ros=args.ros, jobs=args.jobs or cores(), timings=timings)
            ran += cases(path, args.out, dict(args.arg), args.variant)
        except RobotkitError as exc:
            for line in exc.lines():
                print(line, file=sys.stderr)
            findings += input_findings(exc.problems, path)
            status = max(status, exc.exit_status)
    ran += [("motion", f"robot '{name}'") for name in motion]  # the robots whose drives were stepped
    _write_findings(args, findings, status, ran, motion, time.perf_counter() - start, timings)
    return status or (1 if any(f.fails(args.fail_on) for f in findings) else 0)


def _write_findings(args, findings: list[Finding], status: int, ran: list[tuple[str, str]],
                    motion: dict | None = None, elapsed: float | None = None,
                    timings: dict[str, float] | None = None) -> None:
    source = " ".join(args.paths)
    if args.format != "text" or not status:
        sys.stdout.write(render(findings, args.format, source, args.fail_on, ran, motion=motion, elapsed=elapsed,
                                timings=timings))
    elif any(f.check != "input" for f in findings):  # the paths that could be checked
        sys.stdout.write(render([f for f in findings if f.check != "input"], "text", source, args.fail_on, ran,
                                motion=motion, elapsed=elapsed))
    if args.junit:
        Path(args.junit).parent.mkdir(parents=True, exist_ok=True)
        Path(args.junit).write_text(render(findings, "junit", source, args.fail_on, ran), encoding="utf-8")
    if args.format == "github" and os.environ.get("GITHUB_STEP_SUMMARY"):
        # a temporary build folder is gone when the summary is read: no report to point at
        _job_summary(os.environ["GITHUB_STEP_SUMMARY"], findings, args.paths, None if args.temp_out else args.out,
                     dict(args.arg), args.variant)


def check(path: str, out_dir: str = "build", package_paths: dict[str, str] | None = None,
          args: dict[str, str] | None = None, report: bool | None = False, motion: dict | None = None,
          variant: str | None = None, ros: str | None = None, jobs: int = 1,
          timings: dict[str, float] | None = None) -> list[Finding]:
    """The findings on PATH.  ``report``: a recipe's build also writes its picture report (as
    ``robotkit build`` does); None: when the build folder has one already.  ``motion``: gets each robot's motion results by name.  ``variant``,
    ``ros`` and ``jobs``: a recipe's build (``--variant``, ``--ros``, ``-j``).  ``timings``: gets each
    stage's wall time (seconds by stage: a build folder's stages and a recipe's build)."""
    what = classify(path)
    package_paths = package_paths or {}
    if what.kind == "build":  # a build folder's findings point at its URDF
        return [f for d in what.robots
                for f in locate(check_build_dir(d.root, motion=motion, timings=timings), d.urdf)]
    if what.kind == "recipe":
        return check_recipe(what.path, out_dir, args, report, motion, variant, ros, jobs, timings)
    if what.kind == "urdf":
        return check_urdf_file(what.path, package_paths)
    if what.kind == "xacro":
        return check_xacro_file(what.path, package_paths, args or {})
    return check_model_file(what.path, what.kind, motion)


def _has_report(path: Path, out_dir: str, args: dict[str, str] | None, variant: str | None) -> bool:
    """Whether a robot of the recipe has a picture report in ``out_dir`` (an earlier build's:
    check's build keeps it, as publishing would remove it); a recipe that does not load has none
    (the build says why)."""
    try:
        return any(robot_layout(Path(out_dir) / loaded.recipe.robot).pictures.joinpath("report.html").is_file()
                   for loaded in load_recipes(path, args, variant))
    except RobotkitError:
        return False


def check_recipe(path: Path, out_dir: str, args: dict[str, str] | None = None, report: bool | None = False,
                 motion: dict | None = None, variant: str | None = None, ros: str | None = None,
                 jobs: int = 1, timings: dict[str, float] | None = None) -> list[Finding]:
    """Build the recipe, then check each of its robots (one per variant, or ``variant``), the
    build's warnings and the findings placed on the recipe's lines."""
    from robotkit.pipeline.buildwarn import parse
    from robotkit.pipeline.runner import build

    located = []
    if report is None:
        report = _has_report(path, out_dir, args, variant)
    clock = Clock(timings)
    result = clock.timed("build", lambda: build([path], out_dir, jobs=jobs, args=args, report=report, ros=ros,
                                                variant=variant))
    warnings = [parse(w) for w in result.warning_lines]  # (file, line, key, text)
    for i, loaded in enumerate(load_recipes(path, args, variant)):  # one per variant
        name = loaded.recipe.robot
        others = [r for r in result.robots if r != name]
        # a warning naming another variant's robot belongs to that one; the rest to the first
        mine = [w for w in warnings if w[3].startswith(f"{name}:")
                or (i == 0 and not any(w[3].startswith(f"{o}:") for o in others))]
        located += _check_variant(loaded, mine, out_dir, motion, timings)
    return located


def _check_variant(loaded, warnings: list[tuple], out_dir: str, motion: dict | None = None,
                   timings: dict[str, float] | None = None) -> list[Finding]:
    name = loaded.recipe.robot
    build_findings = [Finding("warning", "build", key or f"robot '{name}'", text, file=file, line=line)
                      for file, line, key, text in warnings]
    findings = check_build_dir(Path(out_dir) / name, loaded.recipe.measured_mass, motion, timings)
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


def cases(path: str, out_dir: str = "build", args: dict[str, str] | None = None,
          variant: str | None = None) -> list[tuple[str, str]]:
    """Every (check, subject) that a check of ``path`` ran, named as its findings name them, so
    CI reports list what passed too: each validator on each file, the equivalence, consumer and
    simulation stages on the robot, and the physics lints (``lints``) on each link and joint."""
    what = classify(path)
    p = what.path
    if what.kind == "build":
        return [c for d in what.robots for c in _folder_cases(d)]
    if what.kind == "recipe":  # the build, then its folder
        return [c for loaded in load_recipes(p, args, variant)
                for c in [("build", f"robot '{loaded.recipe.robot}'")]
                + _folder_cases(robot_layout(Path(out_dir) / loaded.recipe.robot))]
    if what.kind == "urdf":
        return [("check_urdf", str(p)), ("consumer", f"robot '{p.stem}'")] + _described(p)
    if what.kind == "xacro":
        return [("check_urdf", str(p)), ("consumer", f"robot '{xacro_robot(p)}'")]
    if what.kind == "sdf":
        return [("ign sdf -k", str(p))]
    return [("mujoco", str(p))]


def _described(file: Path) -> list[tuple[str, str]]:
    return [("lints", f"{'link' if tag in ('link', 'body') else 'joint'} '{name}'")
            for (tag, name) in element_lines(file) if tag in ("link", "joint", "body")]


def _folder_cases(d: RobotLayout) -> list[tuple[str, str]]:
    """The cases of a build folder's check; the stages that need the MJCF skipped, with the
    reason, when the build left it out (robotkit.check.mjcf_left_out)."""
    robot = f"robot '{d.name}'"
    lost = mjcf_left_out(d.root)
    if lost is not None:
        return ([("check_urdf", str(d.urdf)), ("ign sdf -k", str(d.sdf))]
                + [(c, robot) for c in ("equivalence", "consumer")]
                + [skipped_case(c, lost) for c in MJCF_STAGES] + _described(d.urdf))
    files = [("check_urdf", d.urdf), ("ign sdf -k", d.sdf), ("mujoco", d.mjcf), ("mujoco", d.scene)]
    return ([(c, str(f)) for c, f in files]
            + [(c, robot) for c in ("equivalence", "consumer", "simulation", "self-collision")]
            + _described(d.urdf))


def _job_summary(summary_file: str, findings, paths: list[str], out: str | None, args: dict[str, str] | None = None,
                 variant: str | None = None) -> None:
    """Append the check's summary, pointing at the picture report, to GitHub's job summary."""
    folders: list[RobotLayout] = []
    for path in paths:
        try:
            what = classify(path)
            if what.kind == "recipe" and out is not None:
                folders += [robot_layout(Path(out) / one.recipe.robot) for one in load_recipes(what.path, args, variant)]
            elif what.kind == "build":
                folders += what.robots
        except RobotkitError:
            pass  # a recipe that does not load has no report; its findings say why
    pages = [os.path.relpath(f.report_html) for f in folders if f.report_html.is_file()]
    with open(summary_file, "a", encoding="utf-8") as f:
        f.write(job_summary(findings, " ".join(paths), pages))
