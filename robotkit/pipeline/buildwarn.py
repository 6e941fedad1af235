"""What a build warns about, one line each, naming the recipe's ``file:line: key:`` first:

- what an output format cannot express (``report.json``'s losses), placed on the link, joint,
  sensor or mesh it names;
- the cheap lints a build can run on what it already knows (the resolved robot and the mesh
  facts its tasks recorded), so that ``check`` is not the first to notice: a mesh whose declared
  units make it larger than 10 m or smaller than 0.1 mm (millimetres declared as metres), a link
  whose mass and geometry imply an impossible density, a material no geometry uses, an actuator
  that MuJoCo drives with no force range.

The thresholds are the check's (:mod:`robotkit.check.lints`), so a build and ``check`` agree.
"""

from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path

from robotkit.emit import layout
from robotkit.errors import Problem
from robotkit.model.plausible import DENSITY_RANGE, PART_SIZE_RANGE
from robotkit.model.load import mesh_locations
from robotkit.pipeline.publish import STATE

WARNING = "warning: "
_LINE = re.compile(r"^(?:(?P<file>.+?)(?::(?P<line>\d+))?: (?:(?P<key>[^\s:]+): )?)?warning: (?P<text>.*)$")
_PLACE = re.compile(r"^.+?:\d+: [^\s:]+: ")  # the file:line: key: a mesh task put before its warning
_NAMED = re.compile(r"\b(link|joint|sensor|mesh|actuator|material) '([^']+)'")
_KIND = {"link": "links", "joint": "joints", "sensor": "sensors", "actuator": "actuators", "material": "materials"}


def warning_line(text: str, where: dict | None = None) -> str:
    """``file:line: key: warning: text`` (as much of the place as is known)."""
    return str(Problem(WARNING + text, **(where or {})))


def parse(line: str) -> tuple[str | None, int | None, str | None, str]:
    """(file, line, key, text) of a warning line (``text`` without the ``warning:`` mark)."""
    m = _LINE.match(line)
    if m is None:
        return None, None, None, line
    return m["file"], int(m["line"]) if m["line"] else None, m["key"], m["text"]


def build_warnings(robots, out: Path) -> list[tuple[str, str]]:
    """Every warning of this build as (text, line): the text as BuildResult.warnings has it
    (``robot: SDF: joint 'j': ...``; a mesh's with its place before it), the line located
    (``file:line: key: warning: text``) as the command line prints it.  The mesh tasks' own
    warnings come first (shown on every build, not only the one that ran them), then the losses
    and the lints."""
    places = [(loaded, robot, mesh_locations(loaded, robot), _mesh_facts(out / STATE / robot.name, robot))
              for loaded, robot in robots]
    pairs = []
    for loaded, robot, where, facts in places:
        for key, f in facts.items():  # recorded with their place (robotkit.pipeline.actions.mesh_facts): placed anew
            pairs += [(w, warning_line(_PLACE.sub("", w, count=1), where.get(key))) for w in f.get("warnings", [])]
    for loaded, robot, where, facts in places:
        pairs += _losses(loaded, robot, out, where) + lints(loaded, robot, facts, where) + _pictures(loaded, robot, out)
    seen: dict[str, str] = {}
    for text, line in pairs:
        seen.setdefault(line, text)
    return collapse(collapse([(text, line) for line, text in seen.items()], SUBJECT), ROBOTS)


SUBJECT = re.compile(r"^(?P<head>(?:[^':]+: )*)(?P<kind>link|joint|sensor|mesh|actuator|material) '(?P<item>[^']+)'"
                      r"(?: and \d+ more \((?P<more>[^)]*)\))?: (?P<tail>.+)$", re.S)
"""``robot: FORMAT: kind 'name' [and N more (...)]: what``: one warning of a kind on one item."""
ROBOTS = re.compile(r"^(?P<head>)(?P<item>[A-Za-z_][\w-]*(?:, [A-Za-z_][\w-]*)*): (?P<tail>.+)$", re.S)
"""``robot: FORMAT: what``: one warning of a variant's robot (the same on every variant)."""


def collapse(pairs: list[tuple[str, str]], form: re.Pattern) -> list[tuple[str, str]]:
    """The warnings of one kind (the same text but for the item ``form`` finds: a link, joint,
    sensor... with ``SUBJECT``; the robot with ``ROBOTS``) as one, naming the count and the
    items, placed where the first was, in the first's place in the order.  With ``ROBOTS``
    only warnings placed on the same line are one (the variants of one recipe line)."""
    groups: dict[tuple, list[tuple[str, str, re.Match]]] = {}
    for text, line in pairs:
        m = form.match(text)
        place = parse(line)[:3]
        key = (m["head"], m.groupdict().get("kind"), m["tail"], place if form is ROBOTS else None) if m else (line,)
        groups.setdefault(key, []).append((text, line, m))
    out = []
    for items in groups.values():
        text, line, m = items[0]
        if len(items) > 1:
            text = _merged(m, [i for _, _, x in items for i in _named(x)])
            file, number, key = parse(line)[:3]
            line = warning_line(text, {"file": file, "line": number, "key": key} if file else None)
        out.append((text, line))
    return out


def _named(m: re.Match) -> list[str]:
    """The items one warning names (``joint 'a' and 2 more ('b', 'c')``: a, b, c)."""
    more = m.groupdict().get("more")
    return [m["item"]] + ([x.strip().strip("'") for x in more.split(", ")] if more else [])


def _merged(m: re.Match, items: list[str]) -> str:
    items = list(dict.fromkeys(i for x in items for i in x.split(", ")))
    if m.groupdict().get("kind") is None:  # robots
        return f"{', '.join(items)}: {m['tail']}"
    rest = f" and {len(items) - 1} more ({', '.join(repr(i) for i in items[1:])})" if items[1:] else ""
    return f"{m['head']}{m['kind']} '{items[0]}'{rest}: {m['tail']}"


def _mesh_facts(state: Path, robot) -> dict[str, dict]:
    """The facts the mesh tasks recorded (below the robot's ``state`` folder)."""
    out = {}
    for key in robot.meshes():
        try:
            out[key] = json.loads((state / layout.RECORDS["mesh"].format(key=key)).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            pass
    return out


def no_pictures(name: str, out: Path) -> str | None:
    """Why robot ``name``'s published picture report has no pictures (MuJoCo cannot draw here, as
    the report task recorded), or None."""
    if not layout.robot_layout(out / name).report_html.is_file():  # built without the report
        return None
    try:
        record = json.loads((out / STATE / name / layout.RECORDS["pictures"]).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return record.get("no_pictures") if isinstance(record, dict) else None


def _pictures(loaded, robot, out: Path) -> list[tuple[str, str]]:
    why = no_pictures(robot.name, out)
    if not why:
        return []
    text = f"{robot.name}: report/report.html: {why}"
    return [(text, warning_line(text, _at(loaded, ("robot",))))]


def _place(loaded, robot, what: str, name: str, where: dict) -> dict:
    if what == "mesh":  # a mesh file's name: the first geometry using it
        for link in robot.links:
            for g in robot.all_geoms(link):
                m = g.shape.mesh
                if m is not None and os.path.basename(m.source) == name and m.key in where:
                    return where[m.key]
        return _at(loaded, ("links",))
    return _at(loaded, (_KIND[what], name))


def _at(loaded, path: tuple) -> dict:
    p = loaded.marks.problem(path, "")
    return {"file": p.file, "line": p.line, "key": p.key} if p.file else {}


def _losses(loaded, robot, out: Path, where: dict) -> list[tuple[str, str]]:
    """What each output format could not express (from the robot's report.json)."""
    names = {"urdf": "URDF", "sdf": "SDF", "mjcf": "MJCF", "package": "ROS package", "moveit": "MoveIt"}
    try:
        data = json.loads(layout.robot_layout(out / robot.name).report_json.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return []
    lines = []
    for fmt, items in sorted(data.get("losses", {}).items()):
        for item in items:
            m = _NAMED.search(item)
            if m:
                place = _place(loaded, robot, m[1], m[2], where)
            else:  # the package's metadata, or the robot as a whole
                place = (fmt == "package" and _at(loaded, ("metadata", "maintainers"))) or _at(loaded, ("robot",))
            text = f"{robot.name}: {names.get(fmt, fmt)}: {item}"
            lines.append((text, warning_line(text, place)))
    return lines


def _volume(geom, facts: dict[str, dict]) -> float | None:
    s = geom.shape
    if s.kind == "box":
        return s.size[0] * s.size[1] * s.size[2]
    if s.kind == "cylinder":
        return math.pi * s.radius ** 2 * s.length
    if s.kind == "sphere":
        return 4 / 3 * math.pi * s.radius ** 3
    if s.kind == "capsule":
        return math.pi * s.radius ** 2 * (s.length + 4 / 3 * s.radius)
    if s.kind == "mesh" and s.mesh.key in facts:
        return facts[s.mesh.key].get("volume")
    return None


def lints(loaded, robot, facts: dict[str, dict], where: dict) -> list[tuple[str, str]]:
    """The build-time lints (see the module's docstring): (text, located line) each."""
    out = []

    def warn(text, place):
        out.append((text, warning_line(text, place)))

    for key, mesh in robot.meshes().items():
        f = facts.get(key)
        if not f or "bbox_min" not in f:
            continue
        extent = max(hi - lo for lo, hi in zip(f["bbox_min"], f["bbox_max"]))
        name = os.path.basename(mesh.source)
        if extent > PART_SIZE_RANGE[1]:
            warn(f"mesh '{name}' is {extent:.4g} m across as declared (scale {mesh.scale[0]:g}): "
                 "a mesh in millimetres declared as metres? (units: mm)", where.get(key))
        elif 0 < extent < PART_SIZE_RANGE[0]:
            warn(f"mesh '{name}' is {extent * 1000:.3g} mm across as declared (scale "
                 f"{mesh.scale[0]:g}): a mesh in metres declared as millimetres? (units: m)", where.get(key))
    for link in robot.links:
        spec = link.inertial_spec
        if spec.mode not in ("density", "mass", "explicit"):
            continue
        volumes = [_volume(g, facts) for g in link.source_geoms()]
        given = loaded.recipe.links.get(link.name)
        given = getattr(given.inertial, "density", None) if given is not None else None
        if spec.mode == "density":  # the recipe's own density is looked at once, below
            rho, why = (given, "density") if given is not None else (None, "")
        elif volumes and None not in volumes and sum(volumes) > 0:
            mass = spec.mass if spec.mode == "mass" else spec.explicit.mass
            rho, why = mass / sum(volumes), f"mass {mass:.4g} kg in {sum(volumes):.4g} m^3 of {spec.source} geometry"
        else:
            continue
        if rho is not None and not DENSITY_RANGE[0] <= rho <= DENSITY_RANGE[1]:
            cause = ("grams written as kilograms, or a mesh in millimetres declared as metres?"
                     if rho > DENSITY_RANGE[1] else "MeshLab's density 1, or a mesh in metres declared as millimetres?")
            text = (f"link '{link.name}': density {rho:.4g} kg/m^3" if why == "density" else
                    f"link '{link.name}': {why} implies {rho:.4g} kg/m^3")
            warn(f"{text}, outside {DENSITY_RANGE[0]:g}..{DENSITY_RANGE[1]:g} ({cause})",
                 _at(loaded, ("links", link.name, "inertial")) or where.get(f"link:{link.name}"))
    rho = loaded.recipe.density
    if rho is not None and not DENSITY_RANGE[0] <= rho <= DENSITY_RANGE[1]:
        warn(f"density {rho:.4g} kg/m^3 is outside {DENSITY_RANGE[0]:g}..{DENSITY_RANGE[1]:g} "
             "(kg/m^3: water is 1000, steel 7850)", _at(loaded, ("density",)))
    used = {g.material for link in robot.links for g in robot.all_geoms(link)}
    for material in robot.materials:
        if material.name not in used:
            warn(f"material '{material.name}': used by no geometry", _at(loaded, ("materials", material.name)))
    joints = {j.name: j for j in robot.joints}
    for a in robot.actuators:
        j = joints.get(a.joint)
        if a.interface in ("position", "velocity") and j is not None and not (j.limit and j.limit.effort):
            warn(f"joint '{j.name}': the {a.interface} actuator has no force range in MuJoCo (unbounded torque) "
                 "without an effort limit (give the joint limit: {effort: ...})", _at(loaded, ("actuators", a.joint)))
    return out
