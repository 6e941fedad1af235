"""Findings rendered for people (text), programs (JSON), CI test reporters (JUnit) and GitHub
annotations."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from dataclasses import asdict, dataclass, replace

from robotkit.check.findings import EQUIVALENCE_CONFIGS, STAGES, Finding
from robotkit.errors import display_path


def render(findings: list[Finding], fmt: str, source: str, fail_on: str = "error",
           cases: list[tuple[str, str]] | None = None, motion: dict | None = None,
           elapsed: float | None = None, timings: dict[str, float] | None = None) -> str:
    """``fail_on`` (``--fail-on``): the lowest severity that fails the check; every format says
    which findings fail it (JUnit failures, GitHub ``::error``, JSON ``failed``, the text's last line).
    ``cases``: every (check, subject) that ran (:func:`robotkit.commands.check.cases`): JUnit lists the
    ones without findings as passing test cases, the text and JSON each stage with its verdict.
    ``motion``: the motion stage's results by robot (JSON: under ``motion``; text: one line per
    joint).  ``elapsed``: the check's wall time in seconds (the text's last line; JSON: ``seconds``).
    ``timings``: each stage's wall time in seconds (JSON: the stage's ``seconds``; stages run at
    once, so they add up to more than ``elapsed``)."""
    if fmt == "json":
        out = {"source": source, "errors": sum(f.severity == "error" for f in findings),
               "warnings": sum(f.severity == "warning" for f in findings), "fail_on": fail_on,
               "failed": sum(f.fails(fail_on) for f in findings),
               "stages": [{"stage": s.name, "verdict": s.verdict, "subjects": s.subjects}
                          | ({"why": s.why} if s.why else {})
                          | ({"seconds": round(timings[s.name], 3)} if s.name in (timings or {}) else {})
                          for s in stages(findings, cases or [])],
               "findings": [asdict(f) for f in findings]}
        if elapsed is not None:
            out["seconds"] = round(elapsed, 3)
        if motion:
            out["motion"] = motion
        return json.dumps(out, indent=1) + "\n"
    if fmt == "junit":
        return _junit(findings, source, fail_on, cases or [])
    if fmt == "github":
        return "".join(annotation(f, fail_on) + "\n" for f in findings)
    return _text(findings, source, fail_on, cases or [], motion or {}, elapsed)


def _text(findings: list[Finding], source: str, fail_on: str, cases: list[tuple[str, str]], motion: dict,
          elapsed: float | None) -> str:
    """Each stage with its verdict (as test runners list them), the problems by subject, the
    motion table, then one line: the stages passed, the counts, the time."""
    ran = stages(findings, cases)
    width = max((len(s.verdict) for s in ran), default=0)
    out = [f"  {s.verdict:<{width}}  {s.label}" + (f"  ({s.why})" if s.why else "") for s in ran]
    for subject, items in _by_subject(_one_per_kind(findings)).items():
        where = ""
        if items[0].file:
            where = f" ({display_path(items[0].file)}" + (f":{items[0].line}" if items[0].line else "") + ")"
        out.append(f"{subject}{where}")
        for f in items:
            out.append(f"  {f.severity}: {f.message} [{f.check}]")
            if f.hint:
                out.append(f"    hint: {f.hint}")
    errors = sum(f.severity == "error" for f in findings)
    warnings = len(findings) - errors
    tail = " (they fail the check: --fail-on warning)" if fail_on == "warning" and warnings else ""
    passed = sum(s.verdict == "ok" for s in ran)
    took = f" ({elapsed:.1f} s)" if elapsed is not None else ""
    out += motion_table(motion)
    out.append(f"{source}: {passed} stage{'s' * (passed != 1)} passed, {_count(errors, 'error')}, "
               f"{_count(warnings, 'warning')}{tail}{took}")
    return "\n".join(out) + "\n"


def _count(n: int, what: str) -> str:
    return f"{n} {what}{'s' * (n != 1)}"


def _one_per_kind(findings: list[Finding]) -> list[Finding]:
    """The findings that say the same (severity, check, message, hint) of several subjects as
    one, naming the count and the subjects (``link 'a' and 2 more ('b', 'c')``), where the first is."""
    kinds: dict[tuple, list[Finding]] = {}
    for f in findings:
        kinds.setdefault((f.severity, f.check, f.message, f.hint), []).append(f)
    out = []
    for items in kinds.values():
        subjects = list(dict.fromkeys(f.subject for f in items))
        more = f" and {len(subjects) - 1} more ({', '.join(subjects[1:])})" if subjects[1:] else ""
        out.append(replace(items[0], subject=subjects[0] + more))
    return out


def _by_subject(findings: list[Finding]) -> dict[str, list[Finding]]:
    groups: dict[str, list[Finding]] = {}
    for f in findings:
        groups.setdefault(f.subject, []).append(f)
    return groups


ORDER = ("build", "check_urdf", "ign sdf -k", "mujoco", "lints", "equivalence", "consumers", "simulation",
         "self-collision", "motion")
"""The stages in the order a check runs them (``lints``: every physics lint, :mod:`robotkit.check.lints`)."""


@dataclass(frozen=True)
class Stage:
    name: str
    subjects: int  # the files or subjects it ran on
    verdict: str  # ok | skipped | 1 error | 2 warnings | 1 error, 2 warnings
    why: str = ""  # why it was skipped
    compared: str = "URDF, model.sdf, MJCF"  # the equivalence stage's formats (no MJCF when it was skipped)

    @property
    def label(self) -> str:
        if self.name == "lints" and self.subjects:
            return f"lints ({self.subjects} links and joints)"
        if self.name == "equivalence":
            return f"equivalence ({self.compared} and Gazebo's URDF at {EQUIVALENCE_CONFIGS} configurations)"
        if self.name in ("check_urdf", "ign sdf -k", "mujoco") and self.subjects > 1:
            return f"{self.name} ({self.subjects} files)"
        return self.name


SKIPPED = "skipped: "
"""The subject of a case that did not run (:func:`skipped_case`)."""


def skipped_case(check: str, why: str) -> tuple[str, str]:
    """The case of a stage that was not run, and why (a stage that needs a file the build left out)."""
    return check, SKIPPED + why


def stages(findings: list[Finding], cases: list[tuple[str, str]]) -> list[Stage]:
    """Each stage that ran (a case of ``cases``, or a finding of its) with its verdict: ``ok``,
    the count of its findings, or ``skipped`` when all it says is that its program is not installed
    or it was not run (:func:`skipped_case`: its reason)."""
    subjects: dict[str, set[str]] = {}
    found: dict[str, list[Finding]] = {}
    skips = {_stage_of(check): subject.removeprefix(SKIPPED) for check, subject in cases if subject.startswith(SKIPPED)}
    for check, subject in cases:
        if not subject.startswith(SKIPPED):
            subjects.setdefault(_stage_of(check), set()).add(subject)
    for f in findings:
        if f.check != "input":
            found.setdefault(_stage_of(f.check), []).append(f)
    out = []
    for name in sorted(subjects.keys() | found.keys() | skips.keys(), key=lambda s: (ORDER + (s,)).index(s)):
        items = found.get(name, [])
        if name in skips and not items and name not in subjects:
            out.append(Stage(name, 0, "skipped", skips[name]))
            continue
        errors = sum(f.severity == "error" for f in items)
        verdict = ", ".join(([_count(errors, "error")] if errors else [])
                            + ([_count(len(items) - errors, "warning")] if len(items) > errors else [])) or "ok"
        # a validator whose program is missing did not run; a consumer missing is one of several
        missing = name != "consumers" and items and all("not installed" in f.message for f in items)
        out.append(Stage(name, len(subjects.get(name, ())), "skipped" if missing else verdict,
                         "; ".join(dict.fromkeys(f.message for f in items)) if missing else "",
                         "URDF, model.sdf" if "mujoco" in skips else Stage.compared))
    return out


def _stage_of(check: str) -> str:
    """The stage a case or finding belongs to (``consumer``: the consumers stage; a lint: ``lints``)."""
    if check in ("consumer", "consumers"):
        return "consumers"
    return check if check in STAGES else "lints"


def motion_table(motion: dict) -> list[str]:
    """Per robot, one line per joint: its slowest step (pose, simulator), rise time, overshoot
    and final error; then each simulator's wall time."""
    out = []
    for robot, r in motion.items():
        sims = ", ".join(f"{s} {v['wall']:.2f} s" if v.get("wall") is not None else f"{s} {v['status']}"
                         for s, v in r["simulators"].items())
        out.append(f"motion of robot '{robot}' ({r['integrator']}, dt {r['timestep']:g} s; stage {r['wall']:.2f} s: "
                   f"{sims})")
        out.append(f"  {'joint':<24} {'pose':<10} {'sim':<9} {'rise':>9} {'overshoot':>9} {'final error':>12}")
        for joint, j in r["joints"].items():
            runs = [(pose, s, x) for pose, p in j["poses"].items() for s, x in p["simulators"].items()
                    if "refused" not in x]
            if not runs:
                out.append(f"  {joint:<24} not stepped ({j['interface']})")
                continue
            pose, sim, x = max(runs, key=_slowness)
            rise = "diverged" if x.get("diverged") else "never" if x["rise_time"] is None else f"{x['rise_time']:.3f} s"
            over = "-" if x["overshoot"] is None else f"{100 * x['overshoot']:.1f} %"
            out.append(f"  {joint:<24} {pose:<10} {sim:<9} {rise:>9} {over:>9} {x['final_error']:>12.3g}")
        for n in r.get("not_checked", []):
            out.append(f"  actuator '{n['actuator']}' not checked: {n['why']}")
    return out


def _slowness(run: tuple) -> tuple:
    """Diverged first, then never rising, then the largest final error, then the longest rise."""
    x = run[2]
    return (bool(x.get("diverged")), x["rise_time"] is None, x["final_error"] or 0.0, x["rise_time"] or 0.0)


def _escape_data(text: str) -> str:
    """A workflow command's message: % CR LF escaped (GitHub's workflow-command syntax)."""
    return text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")


def _escape_property(text: str) -> str:
    """A workflow command's property value: also : and , escaped."""
    return _escape_data(text).replace(":", "%3A").replace(",", "%2C")


def annotation(f: Finding, fail_on: str = "error") -> str:
    """One GitHub workflow command: ``::error file=F,line=L,title=T::message``.  A finding that
    fails the check (``--fail-on``) is an ``error`` whatever its severity; the title keeps it."""
    props = []
    if f.file:  # GitHub wants paths relative to the repository (the working directory)
        props.append(f"file={_escape_property(display_path(f.file))}")
        if f.line:
            props.append(f"line={f.line}")
    title = f"robotkit {f.check}" + (f" ({f.severity})" if f.fails(fail_on) and f.severity != "error" else "")
    props.append(f"title={_escape_property(title)}")
    text = f"{f.subject}: {f.message}" + (f" (hint: {f.hint})" if f.hint else "")
    return f"::{'error' if f.fails(fail_on) else f.severity} {','.join(props)}::{_escape_data(text)}"


def _junit(findings: list[Finding], source: str, fail_on: str, ran: list[tuple[str, str]]) -> str:
    """One test case per check and subject, so CI test reporters list them; a case fails when
    one of its findings fails the check (``--fail-on``).  The checks that ran and found nothing
    are passing cases (``robotkit.lints`` for a link or joint no physics lint fired on)."""
    cases: dict[tuple[str, str], list[Finding]] = {}
    for f in findings:
        cases.setdefault((f.check, f.subject), []).append(f)
    linted = {f.subject for f in findings if f.check not in STAGES}
    warned = any(f.check == "build" for f in findings)  # the build's warnings are placed on the recipe's keys
    passed = list(dict.fromkeys(c for c in ran if c not in cases and not (c[0] == "lints" and c[1] in linted)
                                and not (c[0] == "build" and warned)))
    failing = [any(x.fails(fail_on) for x in v) for v in cases.values()]
    total = len(cases) + len(passed)
    suite = ET.Element("testsuite", name=f"robotkit check {source}", tests=str(max(total, 1)),
                       failures=str(sum(failing)), errors="0",
                       skipped=str(sum(subject.startswith(SKIPPED) for _, subject in passed)))
    if not total:
        ET.SubElement(suite, "testcase", classname="robotkit", name="all checks")
    for ((check, subject), items), fails in zip(cases.items(), failing):
        case = ET.SubElement(suite, "testcase", classname=f"robotkit.{check}", name=subject)
        first = next((x for x in items if x.fails(fail_on)), items[0])
        text = "\n".join(_where(f) + f"{f.severity}: {f.message}" + (f" (hint: {f.hint})" if f.hint else "")
                         for f in items)
        if fails:
            ET.SubElement(case, "failure", type=first.severity, message=first.message).text = text
        else:
            ET.SubElement(case, "system-out").text = text
    for check, subject in passed:
        case = ET.SubElement(suite, "testcase", classname=f"robotkit.{check}",
                             name=subject if not subject.startswith(SKIPPED) else check)
        if subject.startswith(SKIPPED):
            ET.SubElement(case, "skipped", message=subject.removeprefix(SKIPPED))
    suites = ET.Element("testsuites", tests=suite.get("tests"), failures=suite.get("failures"), errors="0")
    suites.append(suite)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(suites, encoding="unicode") + "\n"


def _where(f: Finding) -> str:
    """``file:line: `` of a finding (the JUnit schema has no place for it but the text)."""
    if not f.file:
        return ""
    return display_path(f.file) + (f":{f.line}" if f.line else "") + ": "


def job_summary(findings: list[Finding], source: str, reports: list[str]) -> str:
    """Markdown for a GitHub job summary ($GITHUB_STEP_SUMMARY): the counts, the findings,
    and where the picture report is (a folder to upload as an artifact)."""
    errors = sum(f.severity == "error" for f in findings)
    warnings = len(findings) - errors
    out = [f"## robotkit check {source}", "",
           f"{errors} error{'s' * (errors != 1)}, {warnings} warning{'s' * (warnings != 1)}", ""]
    if findings:
        out += ["| severity | subject | message | check |", "|---|---|---|---|"]
        for f in findings:
            cells = [f.severity, f.subject, f.message + (f" (hint: {f.hint})" if f.hint else ""), f.check]
            out.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
        out.append("")
    for page in reports:
        folder = page.rsplit("/", 1)[0]
        out.append(f"Picture report: `{page}` (upload the folder `{folder}` as an artifact to see it)")
    if not reports:
        out.append("No picture report: `robotkit report PATH -o DIR` writes one.")
    return "\n".join(out) + "\n"
