"""Reading an MJCF file through MuJoCo itself: the compiled model (default classes,
``childclass``, mesh scale, ``fromto``, frames and compiler options resolved as MuJoCo resolves
them) and its MjSpec (file names, source lines).  A file MuJoCo refuses is one problem with its
file and line, nothing else read."""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from robotkit import mj, urdfxml
from robotkit.errors import Problem, RobotkitError
from robotkit.paths import ReadPolicy

_LINE = re.compile(r"line (\d+)")
_TINYXML_LINE = re.compile(r"Line number=(\d+)")
_SECTIONS = {"actuator", "sensor", "tendon", "equality", "keyframe", "contact"}
"""Sections whose elements are named by their section (an actuator is <position>, <motor>...)."""
_TAGS = {"freejoint": "joint"}
_KINDS = {"MjsBody": "body", "MjsJoint": "joint", "MjsGeom": "geom", "MjsSite": "site", "MjsCamera": "camera",
          "MjsLight": "light", "MjsFrame": "frame", "MjsMesh": "mesh", "MjsMaterial": "material",
          "MjsTexture": "texture", "MjsActuator": "actuator", "MjsSensor": "sensor", "MjsTendon": "tendon",
          "MjsEquality": "equality", "MjsKey": "keyframe", "MjsExclude": "contact", "MjsPair": "contact"}
"""The section or tag of each MjSpec element class (its key in :meth:`Source.named_lines`)."""


@dataclass
class Source:
    path: Path
    spec: object  # mujoco.MjSpec
    model: object  # mujoco.MjModel
    textured_noted: set = field(default_factory=set)
    _lines: dict | None = None

    def located(self, element) -> tuple[str, int | None]:
        """(file label, line) of a spec element: the line MuJoCo recorded (``info``: 'line 26';
        'line 0' for an element read from an ``<include>``d file), else the line of the element
        of its kind and name in the text of the main file or of a file it includes (a light scan)."""
        found = _LINE.search(getattr(element, "info", "") or "")
        if found and int(found.group(1)):
            return self.path.name, int(found.group(1))
        name = getattr(element, "name", "")
        kind = _KINDS.get(type(element).__name__, "")
        return self.named_lines().get((kind, name), (self.path.name, None)) if name else (self.path.name, None)

    def named_lines(self) -> dict:
        """(file label, line) of each element of the main file and the files it includes, in the
        order MuJoCo reads them, the first of a name: by ``(kind, name)`` (kind: the element's
        section for actuators, sensors, tendons, equalities, keys and contacts, else its tag) and
        by ``<tag>``."""
        if self._lines is None:
            self._lines = {}
            for label, root in self._texts():
                for e in root.iter():
                    if urdfxml.is_element(e):
                        parent = e.getparent()
                        kind = parent.tag if parent is not None and parent.tag in _SECTIONS else _TAGS.get(e.tag, e.tag)
                        self._lines.setdefault(f"<{e.tag}>", (label, e.sourceline))
                        if e.get("name"):
                            self._lines.setdefault((kind, e.get("name")), (label, e.sourceline))
        return self._lines

    def includes(self) -> list[Path]:
        """The files the main file ``<include>``s (and those they include), each once."""
        return [self.path.parent / label for label, _ in self._texts()[1:]]

    def _texts(self) -> list:
        """(label, parsed root) of the main file, then of each file it includes (:func:`included`)."""
        return included(self.path)[0]

    def where(self, element=None) -> str:
        """``file:line`` of an element (the file alone when its line is unknown)."""
        label, line = self.located(element) if element is not None else (self.path.name, None)
        return f"{label}:{line}" if line else label

    def where_tag(self, tag: str) -> str:
        """``file:line`` of the first ``<tag>`` element of the file or of its includes (the file
        alone without one)."""
        label, line = self.named_lines().get(f"<{tag}>", (self.path.name, None))
        return f"{label}:{line}" if line else label

    def where_named(self, kind: str, name: str) -> str:
        """``file:line`` of the spec element ``kind`` (body, geom, material...) called ``name``."""
        for element in getattr(self.spec, "bodies" if kind == "body" else kind + "s", []):
            if element.name == name:
                return self.where(element)
        return self.where()

    def geom_where(self, g: int) -> str:
        geoms = list(self.spec.geoms)
        return self.where(geoms[g]) if g < len(geoms) and geoms[g].name == self.model.geom(g).name else self.where()

    def mesh_file(self, d: int) -> Path | None:
        """The file of compiled mesh ``d`` (None for a mesh given by its vertices)."""
        name = self.model.mesh(d).name
        mesh = next((e for e in self.spec.meshes if e.name == name), None)
        if mesh is None or not mesh.file:
            return None
        folder = Path(self.spec.modelfiledir or self.path.parent) / (self.spec.meshdir or "")
        return (folder / mesh.file).resolve()


    def mesh_ref(self, d: int):
        """The ``refpos`` and ``refquat`` (as a matrix) of compiled mesh ``d``."""
        import numpy as np

        from robotkit.importer.mjcf.frames import quat_matrix

        name = self.model.mesh(d).name
        mesh = next((e for e in self.spec.meshes if e.name == name), None)
        if mesh is None:
            return np.zeros(3), np.eye(3)
        return np.array(mesh.refpos, float), quat_matrix(mesh.refquat)


def included(path: Path, policy=None) -> tuple[list, list[Problem]]:
    """(label, parsed root) of the file ``path``, then of each file it ``<include>``s (and those
    they include: a label relative to its folder, where MuJoCo looks for each), each once, an
    unreadable one skipped; and with a read ``policy`` (robotkit.paths.ReadPolicy), a problem for
    each include outside it, at its line, that file not read."""
    texts: list = []
    problems: list[Problem] = []
    main = path.resolve()
    pending, seen = [main], set()
    while pending:
        target = pending.pop(0)
        if target in seen:
            continue
        seen.add(target)
        try:
            root = urdfxml.parse_text(target.read_text(encoding="utf-8")).getroot()
        except (OSError, UnicodeDecodeError, urdfxml.MalformedXML):
            continue
        texts.append((path.name if target == main else Path(os.path.relpath(target, main.parent)).as_posix(), root))
        for e in root.iter("include"):
            if not e.get("file"):
                continue
            file = (main.parent / e.get("file")).resolve()
            problem = policy.problem(file, file=str(target), line=e.sourceline) if policy is not None else None
            if problem is not None:
                problems.append(problem)
            else:
                pending.append(file)
    return texts, problems


def refused(path: Path, message: str) -> RobotkitError:
    """MuJoCo's refusal as one line: its first line (with tinyxml2's detail when that line is only a
    heading), at the line it names."""
    lines = [line.strip() for line in message.strip().splitlines() if line.strip()] or ["MuJoCo refused the file"]
    first = re.sub(r"^(XML )?Error:\s*", "", lines[0])
    if first.endswith(":") and len(lines) > 1:  # "XML parse error 14:" then tinyxml2's own line
        detail = re.sub(r"Error=|ErrorID=\S+ \(\S+\)\s*|Line number=\d+:?\s*", "", lines[1]).strip()
        first = f"{first} {detail}"
    found = _LINE.search(message) or _TINYXML_LINE.search(message)
    return RobotkitError(Problem(f"MuJoCo refuses the file: {first}", file=str(path),
                                 line=int(found.group(1)) if found else None))


def read(path: str | os.PathLike) -> Source:
    """The file's MjSpec and compiled MjModel; RobotkitError (one line) when MuJoCo refuses it."""
    source = Path(path).absolute()
    if not source.is_file():
        raise RobotkitError(Problem("file not found", file=str(source)))
    outside = included(source, ReadPolicy.for_file(source))[1]
    if outside:  # the read rules of the URDF import's (its xacro includes'): nothing read there
        raise RobotkitError(outside)
    mujoco = mj.load()
    try:
        spec = mujoco.MjSpec.from_file(str(source))
        model = spec.compile()
    except ValueError as exc:
        raise refused(source, str(exc)) from None
    return Source(source, spec, model)
