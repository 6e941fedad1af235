"""Findings rendered for people (text), programs (JSON), CI test reporters (JUnit) and GitHub
annotations."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from dataclasses import asdict

from robotkit.check.findings import STAGES, Finding
from robotkit.errors import display_path


def render(findings: list[Finding], fmt: str, source: str, fail_on: str = "error",
           cases: list[tuple[str, str]] | None = None, motion: dict | None = None) -> str:
    """``fail_on`` (``--fail-on``): the lowest severity that fails the check; every format says
    which findings fail it (JUnit failures, GitHub ``::error``, JSON ``failed``, the text's last line).
    ``cases``: every (check, subject) that ran (:func:`robotkit.commands.check.cases`): JUnit lists the
    ones without findings as passing test cases.  ``motion``: the motion stage's results by robot
    (JSON: under ``motion``; text: one line per joint)."""
    if fmt == "json":
        out = {"source": source, "errors": sum(f.severity == "error" for f in findings),
               "warnings": sum(f.severity == "warning" for f in findings), "fail_on": fail_on,
               "failed": sum(f.fails(fail_on) for f in findings), "findings": [asdict(f) for f in findings]}
        if motion:
            out["motion"] = motion
        return json.dumps(out, indent=1) + "\n"
    if fmt == "junit":
        return _junit(findings, source, fail_on, cases or [])
    if fmt == "github":
        return "".join(annotation(f, fail_on) + "\n" for f in findings)
    table = motion_table(motion or {})
    if not findings:
        return "".join(line + "\n" for line in table) + f"{source}: ok, no problems found\n"
    groups: dict[str, list[Finding]] = {}
    for f in findings:
        groups.setdefault(f.subject, []).append(f)
    out = []
    for subject, items in groups.items():
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
    out += table
    out.append(f"{source}: {errors} error{'s' * (errors != 1)}, {warnings} warning{'s' * (warnings != 1)}{tail}")
    return "\n".join(out) + "\n"


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
    passed = list(dict.fromkeys(c for c in ran if c not in cases and not (c[0] == "lints" and c[1] in linted)))
    failing = [any(x.fails(fail_on) for x in v) for v in cases.values()]
    total = len(cases) + len(passed)
    suite = ET.Element("testsuite", name=f"robotkit check {source}", tests=str(max(total, 1)),
                       failures=str(sum(failing)), errors="0", skipped="0")
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
        ET.SubElement(suite, "testcase", classname=f"robotkit.{check}", name=subject)
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
