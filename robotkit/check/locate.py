"""Where a finding is: the line of the element it names in the URDF, SDF or MJCF file it was
read from (``<link name=...>``, ``<joint name=...>``, MJCF ``<body name=...>``), so editors and
GitHub annotations point at it.  Findings in a recipe are located by the recipe's line marks
instead (:func:`robotkit.check._check_variant`)."""

from __future__ import annotations

import os
import xml.parsers.expat
from dataclasses import replace
from pathlib import Path

from robotkit.check.findings import Finding

ROOTS = ("robot", "sdf", "mujoco")
TAGS = {"link": ("link", "body"), "joint": ("joint",)}  # a subject's kind -> the elements that may hold it


def element_lines(path: Path) -> dict[tuple[str, str], int]:
    """(tag, name) -> the line of the first such element; ("root", "") -> the root element's."""
    parser = xml.parsers.expat.ParserCreate()
    lines: dict[tuple[str, str], int] = {}

    def start(tag, attrs):
        if tag in ROOTS:
            lines.setdefault(("root", ""), parser.CurrentLineNumber)
        if "name" in attrs:
            lines.setdefault((tag, attrs["name"]), parser.CurrentLineNumber)

    parser.StartElementHandler = start
    try:
        with open(path, "rb") as f:
            parser.ParseFile(f)
    except (OSError, xml.parsers.expat.ExpatError):
        pass  # what was read so far; the validators report the file's problem
    return lines


def locate(findings: list[Finding], path: Path) -> list[Finding]:
    """Give each finding that has no line yet a file and line in the description ``path`` (or
    in the file it already names: a validator's finding names the file it read, say model.sdf):
    the line of the link or joint it is about, else of the root element."""
    read: dict[str, dict] = {}
    out = []
    for f in findings:
        if f.line is not None:
            out.append(f)
            continue
        file = f.file or (f.subject if os.path.isfile(f.subject) else str(path))
        if file not in read:
            read[file] = element_lines(Path(file))
        lines = read[file]
        kind, _, rest = f.subject.partition(" '")
        name = rest[:-1] if rest.endswith("'") else None
        line = next((lines[(tag, name)] for tag in TAGS.get(kind, ()) if (tag, name) in lines), None)
        out.append(replace(f, file=file, line=line or lines.get(("root", ""))))
    return out
