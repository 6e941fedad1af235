"""Findings rendered for people (text), programs (JSON), CI test reporters (JUnit) and GitHub
annotations."""

from __future__ import annotations

import json
from dataclasses import asdict

from robotkit.check.findings import Finding

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
