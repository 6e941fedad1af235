"""The ROS package an imported description comes from: its package.xml -> the recipe's
``metadata`` (version, description, authors, maintainers, licence, URLs) and ``ros``."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

from robotkit.errors import display_path
from robotkit.recipe.schema import EMAIL_RE

SEARCH_DEPTH = 4  # folders above the file: <pkg>/urdf/<robot>/x.urdf.xacro is three


def find_package_xml(source: Path) -> Path | None:
    """The package.xml of the nearest folder above ``source`` that has one."""
    folder = source.parent
    for _ in range(SEARCH_DEPTH):
        candidate = folder / "package.xml"
        if candidate.is_file():
            return candidate
        if folder.parent == folder:
            break
        folder = folder.parent
    return None


def with_own_package(source: Path, packages: dict[str, str]) -> dict[str, str]:
    """``packages`` and the ROS package ``source`` sits in (the nearest package.xml above it, by
    its <name>), as ROS finds a package's own files: a ``package://`` or ``$(find)`` of it needs
    no ``--package-path``.  A path given for that name wins."""
    path = find_package_xml(source)
    if path is None:
        return packages
    try:
        name = (ET.parse(path).getroot().findtext("name") or "").strip()
    except (OSError, ET.ParseError):
        return packages
    if not name or name in packages:
        return packages
    return {**packages, name: str(path.parent.absolute())}


def _text(el) -> str:
    return re.sub(r"\s+", " ", "".join(el.itertext())).strip()


def package_metadata(source: Path) -> tuple[dict, str | None, list[str]]:
    """(recipe ``metadata``, recipe ``ros`` or None, warnings) from the package around ``source``;
    an empty mapping when there is no package.xml."""
    path = find_package_xml(source)
    if path is None:
        return {}, None, []
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as exc:
        return {}, None, [f"{display_path(path)}: not read ({exc}); no metadata imported"]
    warnings = [f"metadata from {display_path(path)}"]
    md: dict = {}
    version = root.findtext("version", "").strip()
    if re.fullmatch(r"\d+(\.\d+){0,2}", version):
        md["version"] = version
    if root.find("description") is not None and _text(root.find("description")):
        md["description"] = _text(root.find("description"))
    authors = [{"name": _text(a), **({"email": a.get("email")} if a.get("email") else {})}
               for a in root.findall("author") if _text(a)]
    if authors:
        md["authors"] = [a if EMAIL_RE.match(a.get("email", "x@y.zz")) else {"name": a["name"]} for a in authors]
    maintainers = []
    for m in root.findall("maintainer"):
        if m.get("email") and EMAIL_RE.match(m.get("email")):
            maintainers.append({"name": _text(m), "email": m.get("email")})
        else:
            warnings.append(f"{display_path(path)}: maintainer '{_text(m)}' has no valid e-mail address; left out")
    if maintainers:
        md["maintainers"] = maintainers
    licenses = [_text(lic) for lic in root.findall("license") if lic.get("file") is None and _text(lic)]
    if licenses:
        md["license"] = licenses[0]
    urls = {}
    for u in root.findall("url"):
        kind = u.get("type", "website")
        if kind in ("website", "repository", "bugtracker") and kind not in urls and _text(u):
            urls[kind] = _text(u)
    if urls:
        md["urls"] = urls
    tools = {_text(t) for t in root.findall("buildtool_depend")}
    ros = "ros1" if "catkin" in tools else "ros2" if "ament_cmake" in tools else None
    return md, ros, warnings
