"""A temporary copy of a URDF that a simulator without ROS packages can load."""

from __future__ import annotations

import re
from pathlib import Path

from robotkit import urdfxml

PACKAGE_URI = re.compile(r"package://([^/\"'<>\s]+)/")
VISUAL = re.compile(r"<visual\b.*?</visual>|<visual\b[^>]*/>", re.S)


def resolved_urdf(urdf: Path, package_dirs: dict[str, Path], folder: Path, strip_visuals: bool = False) -> Path:
    """``urdf`` written into ``folder`` with ``package://NAME/`` URIs replaced by the absolute
    folders of ``package_dirs`` (unknown packages are left as written) and, if asked, without
    its <visual> elements.  Relative mesh paths keep working: they are made absolute too."""
    text = Path(urdf).read_text(encoding="utf-8")

    def absolute(match: re.Match) -> str:
        d = package_dirs.get(match.group(1))
        return match.group(0) if d is None else Path(d).resolve().as_posix() + "/"

    text = PACKAGE_URI.sub(absolute, text)
    here = Path(urdf).resolve().parent
    text = re.sub(r'filename="(?!/|[a-z]+://)([^"]+)"', lambda m: f'filename="{(here / m.group(1)).as_posix()}"', text)
    if strip_visuals:
        text = VISUAL.sub("", text)
    out = Path(folder) / Path(urdf).name
    out.write_text(text, encoding="utf-8")
    return out


def root_link(urdf: Path) -> str | None:
    """The link of ``urdf`` that is no joint's child (the first one, if several)."""
    root = urdfxml.parse_file(urdf).getroot()
    children = {c.get("link") for j in root.iter("joint") for c in j.iter("child")}
    roots = [el.get("name") for el in root.iter("link") if el.get("name") not in children]
    return roots[0] if roots else None


