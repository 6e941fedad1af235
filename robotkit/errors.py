"""Errors a user can fix, reported as one line each.

Every user-facing failure is a :class:`RobotkitError` holding one or more
:class:`Problem` lines.  The CLI prints each line and exits 2; anything else
that escapes is a bug and keeps its traceback.
"""

from __future__ import annotations

import os
from dataclasses import dataclass


def display_path(path: str | os.PathLike | None) -> str:
    """A path as the user would like to read it: relative to the cwd when below it."""
    if path is None:
        return "<input>"
    path = os.fspath(path)
    try:
        rel = os.path.relpath(path)
        if rel.startswith(".."):  # the cwd may be the same folder reached through a symlink
            real = os.path.relpath(os.path.realpath(path), os.path.realpath(os.getcwd()))
            rel = real if not real.startswith("..") else rel
    except ValueError:  # other drive (Windows)
        return path
    return path if rel.startswith("..") else rel


def short_number(x: float) -> str:
    """A short number for messages: 1e-06 -> 1e-6, 10000.0 -> 10000."""
    return f"{x:g}".replace("e+0", "e").replace("e-0", "e-").replace("e+", "e")


@dataclass(frozen=True)
class Problem:
    """One problem: ``file:line: key: message`` with the parts that are known."""

    message: str
    file: str | None = None
    line: int | None = None
    key: str | None = None

    def __str__(self) -> str:
        where = ""
        if self.file is not None:
            where = display_path(self.file)
            if self.line is not None:
                where += f":{self.line}"
            where += ": "
        key = f"{self.key}: " if self.key else ""
        return f"{where}{key}{self.message}"


def _yaml_syntax_message(exc) -> str:
    """PyYAML's parser wording (``expected <block end>, but found '<block mapping start>'``) in
    the recipe author's words, naming the line where the unclosed or misaligned part began."""
    problem = getattr(exc, "problem", None) or str(exc)
    context = getattr(exc, "context_mark", None)
    began = f" at line {context.line + 1}" if context is not None else ""
    if problem.startswith("expected ',' or '}'"):
        return f"the {{...}} mapping opened{began} is not closed: a '}}' or ',' is missing"
    if problem.startswith("expected ',' or ']'"):
        return f"the [...] list opened{began} is not closed: a ']' or ',' is missing"
    if problem.startswith("expected <block end>"):
        return f"this line is indented differently from the keys of the mapping{began} (indent with spaces, aligned)"
    if problem == "found character '\\t' that cannot start any token":
        return "a tab character: YAML indents with spaces only"
    if problem == "mapping values are not allowed here":
        return "a ': ' where no key may start: quote a value that contains ': ', or put the key on its own line"
    if problem == "could not find expected ':'":
        return f"a line without ':' inside the mapping{began} (a key needs 'key: value')"
    if problem.startswith("found undefined alias"):
        return f"{problem.replace('found undefined alias', 'the alias')} names no anchor (&name) above it"
    return problem


def yaml_syntax_problem(exc, file: str) -> Problem:
    """A YAML syntax error (PyYAML's ``MarkedYAMLError``) as one problem on its line."""
    mark = getattr(exc, "problem_mark", None)
    return Problem(f"invalid YAML: {_yaml_syntax_message(exc)}", file=file, line=mark.line + 1 if mark else None)


class RobotkitError(Exception):
    """A problem with the user's input; carries every problem found, in order.

    ``exit_status`` is what the CLI exits with: 2 for bad input, 1 for a robot that a
    consumer would refuse (:class:`ConsumerError`)."""

    exit_status = 2

    def __init__(self, problems: Problem | str | list[Problem]):
        if isinstance(problems, (Problem, str)):
            problems = [problems]
        self.problems: list[Problem] = [Problem(p) if isinstance(p, str) else p for p in problems]
        super().__init__("\n".join(str(p) for p in self.problems))

    def lines(self) -> list[str]:
        return [str(p) for p in self.problems]


class ConsumerError(RobotkitError):
    """The recipe is valid but asks for a robot that a program loading the outputs refuses
    (MuJoCo, Gazebo): the build stops, naming the link and the fix; exit status 1."""

    exit_status = 1


class RecipeError(RobotkitError):
    """The recipe is invalid (schema, references, tree structure)."""


class MeshError(RobotkitError):
    """A mesh file cannot be read or used as asked."""


class MapError(RobotkitError):
    """An occupancy map (map_server YAML + image) is invalid."""


class RendererUnavailable(RobotkitError):
    """MuJoCo cannot draw offscreen here (no OSMesa, or a ``MUJOCO_GL`` that cannot work): the
    picture report has no pictures.  A build still writes everything else and warns; ``robotkit
    report`` stops on it (exit 2).  The message says what to install, for the backend asked for."""

    def __init__(self, reason: "str | BaseException"):
        gl = os.environ.get("MUJOCO_GL") or "osmesa"  # robotkit's default (robotkit/__init__.py)
        if isinstance(reason, BaseException):
            reason = self.reason(reason, gl)
        if gl == "osmesa":
            advice = "install libosmesa6: sudo apt-get install libosmesa6"
        elif gl == "egl":
            advice = ("install an EGL driver (sudo apt-get install libegl1 libegl-mesa0), or unset MUJOCO_GL "
                      "to draw with OSMesa (sudo apt-get install libosmesa6)")
        else:
            advice = "unset MUJOCO_GL to draw with OSMesa (sudo apt-get install libosmesa6)"
        super().__init__(Problem(f"no pictures: MuJoCo cannot draw offscreen with MUJOCO_GL={gl} ({reason}); "
                                 + advice))

    @staticmethod
    def reason(exc: BaseException, gl: str) -> str:
        """MuJoCo's exception in words: its first line; PyOpenGL's AttributeError on a GL library it
        could not load (``'NoneType' object has no attribute 'glGetError'``) as what it means."""
        text = str(exc).strip()
        if isinstance(exc, AttributeError) and "'NoneType' object has no attribute '" in text:
            return {"osmesa": "libOSMesa", "egl": "libEGL"}.get(gl, "its OpenGL library") + " is not installed"
        return text.splitlines()[0] if text else type(exc).__name__

    @classmethod
    def because(cls, exc: BaseException) -> "RendererUnavailable":
        """The error for MuJoCo's own exception."""
        return cls(exc)
