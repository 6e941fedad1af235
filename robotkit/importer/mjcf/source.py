"""Reading an MJCF file through MuJoCo itself: the compiled model (default classes,
``childclass``, mesh scale, ``fromto``, frames and compiler options resolved as MuJoCo resolves
them) and its MjSpec (file names, source lines).  A file MuJoCo refuses is one problem with its
file and line, nothing else read."""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from robotkit import mj
from robotkit.errors import Problem, RobotkitError

_LINE = re.compile(r"line (\d+)")
_TINYXML_LINE = re.compile(r"Line number=(\d+)")


@dataclass
class Source:
    path: Path
    spec: object  # mujoco.MjSpec
    model: object  # mujoco.MjModel
    textured_noted: set = field(default_factory=set)
    _lines: dict | None = None

    def line(self, element) -> int | None:
        """The source line MuJoCo recorded for a spec element (``info``: 'line 26'), else the
        line of the element of that name in the file's own text (a light scan)."""
        found = _LINE.search(getattr(element, "info", "") or "")
        if found:
            return int(found.group(1))
        name = getattr(element, "name", "")
        return self.named_lines().get(name) if name else None

    def named_lines(self) -> dict[str, int]:
        """Line of each named element of the main file (the first of a name)."""
        if self._lines is None:
            from robotkit import urdfxml

            try:
                root = urdfxml.parse_text(self.path.read_text(encoding="utf-8")).getroot()
                self._lines = {}
                for e in root.iter():
                    if urdfxml.is_element(e):
                        self._lines.setdefault(f"<{e.tag}>", e.sourceline)
                        if e.get("name"):
                            self._lines.setdefault(e.get("name"), e.sourceline)
            except (OSError, UnicodeDecodeError, urdfxml.MalformedXML):
                self._lines = {}
        return self._lines

    def where(self, element=None) -> str:
        """``file:line`` of an element (the file alone when MuJoCo gives no line)."""
        line = self.line(element) if element is not None else None
        return f"{self.path.name}:{line}" if line else self.path.name


    def where_tag(self, tag: str) -> str:
        """``file:line`` of the file's first ``<tag>`` element (the file alone without one)."""
        line = self.named_lines().get(f"<{tag}>")
        return f"{self.path.name}:{line}" if line else self.path.name

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
    mujoco = mj.load()
    try:
        spec = mujoco.MjSpec.from_file(str(source))
        model = spec.compile()
    except ValueError as exc:
        raise refused(source, str(exc)) from None
    return Source(source, spec, model)
