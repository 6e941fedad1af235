"""One place that decides which paths robotkit may read and write.

Recipes come from pull requests and descriptions from strangers, and CI runs robotkit on
both, so every path a recipe, a map file or an imported description names goes through here:

- **Reads** stay inside the *project*: the repository root holding the recipe (the nearest
  folder with ``.git``; the recipe's own folder when there is none), the roots given on
  purpose (``--root DIR``, ``ROBOTKIT_ROOT``) and the package paths the user declared.
  Symlinks are followed before deciding, so a link pointing out of the project is outside.
- **Writes** stay inside the output folder (or an import's target folder): :func:`out_join`.
- **Names that become file names** (robot, world, sensor frame, mesh stems) have a safe
  character set and a length limit on every filesystem: :func:`name_problem`, :func:`file_stem`.

Nothing here imports more than the standard library: it runs on the CLI's start-up path.
"""

from __future__ import annotations

import hashlib
import os
import re
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from robotkit.errors import Problem, RobotkitError, display_path
from robotkit.ioutil import environ

ROOT_ENV = "ROBOTKIT_ROOT"
"""Extra read roots, separated by ``os.pathsep``: widening the project on purpose."""

MAX_NAME = 100
"""Longest name that becomes a file or folder name (255-byte limits leave room for suffixes)."""

_SAFE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.\-]*\Z")


def _real(path: str | os.PathLike) -> str:
    return os.path.realpath(os.path.abspath(os.fspath(path)))


def inside(path: str | os.PathLike, root: str | os.PathLike) -> bool:
    """Whether ``path`` is ``root`` or below it once both are resolved (``..`` and symlinks)."""
    try:
        p, r = _real(path), _real(root)
        return os.path.commonpath([p, r]) == r
    except ValueError:  # different drives, a NUL character
        return False


def project_root(start: str | os.PathLike) -> Path:
    """The repository root holding ``start`` (a file or folder): the nearest ancestor with a
    ``.git`` entry, else ``start``'s own folder."""
    p = Path(_real(start))
    folder = p if p.is_dir() else p.parent
    for d in (folder, *folder.parents):
        if (d / ".git").exists():
            return d
    return folder


def env_roots() -> tuple[Path, ...]:
    """The roots named by ``ROBOTKIT_ROOT``."""
    value = os.environ.get(ROOT_ENV, "")
    return tuple(Path(_real(p)) for p in value.split(os.pathsep) if p)


@dataclass(frozen=True)
class ReadPolicy:
    """Where reads may go: the project root first, then roots widened on purpose and package paths."""

    roots: tuple[Path, ...]
    packages: dict[str, Path] = field(default_factory=dict)

    @classmethod
    def for_file(cls, file: str | os.PathLike, extra_roots=(), packages: dict | None = None) -> "ReadPolicy":
        """The policy for a recipe (or imported description) at ``file``."""
        roots = [project_root(file), *(Path(_real(r)) for r in extra_roots), *env_roots()]
        pk = {name: Path(_real(d)) for name, d in (packages or {}).items()}
        return cls(tuple(dict.fromkeys(roots)), pk)

    def allows(self, path: str | os.PathLike) -> bool:
        return any(inside(path, r) for r in (*self.roots, *self.packages.values()))

    def refusal(self, path: str | os.PathLike) -> str | None:
        """Why ``path`` may not be read (to follow the path's own name), or None when it may."""
        if "\0" in os.fspath(path):
            return "is not a valid file name (it holds a NUL character)"
        if self.allows(path):
            return None
        root = display_path(self.roots[0]).rstrip("/")
        return (f"is outside the project {root}/: robotkit reads only the project and "
                f"declared package paths (widen on purpose with --root DIR or {ROOT_ENV})")

    def problem(self, path: str | os.PathLike, *, file=None, line=None, key=None) -> Problem | None:
        """A :class:`Problem` naming ``key`` when ``path`` is outside every allowed root, else None."""
        why = self.refusal(path)
        return None if why is None else Problem(f"{os.fspath(path)!s} {why}", file, line, key)

    def check(self, path: str | os.PathLike, *, file=None, line=None, key=None) -> str:
        """``path`` itself when allowed; raises :class:`RobotkitError` otherwise."""
        p = self.problem(path, file=file, line=line, key=key)
        if p is not None:
            raise RobotkitError(p)
        return os.fspath(path)


def recipe_policy(recipe: str | os.PathLike) -> ReadPolicy:
    """The reads a recipe may make: its project, the roots widened on purpose, and robotkit's
    own data (the presets' meshes)."""
    return ReadPolicy.for_file(recipe, extra_roots=(Path(__file__).resolve().parent / "presets",))


@contextmanager
def widened(folders):
    """Reads also below ``folders`` while inside the ``with`` block (``ROBOTKIT_ROOT``, so
    worker processes see it too): an importer checking the recipe it wrote, whose meshes sit
    in the package paths the user declared."""
    old = os.environ.get(ROOT_ENV)
    extra = [os.path.abspath(os.fspath(f)) for f in folders]
    with environ({ROOT_ENV: os.pathsep.join(dict.fromkeys(extra + [p for p in (old or "").split(os.pathsep) if p]))}):
        yield


def out_join(out_dir: str | os.PathLike, *parts: str, key: str | None = None) -> Path:
    """``out_dir/parts...``, refusing any result that leaves ``out_dir`` (``..``, absolute parts,
    symlinks inside the output pointing out)."""
    target = Path(out_dir, *parts)
    if any(os.path.isabs(p) for p in parts) or not inside(target, out_dir):
        raise RobotkitError(Problem(f"{os.path.join(*parts)} would be written outside the output folder "
                                    f"{display_path(out_dir)}", key=key))
    return target


def name_problem(name: str) -> str | None:
    """Why ``name`` cannot become a file or folder name, or None. Safe on every filesystem:
    ASCII letters, digits, ``_ . -``, not starting with ``.`` or ``-``, at most :data:`MAX_NAME`."""
    if not name:
        return "must not be empty"
    if len(name) > MAX_NAME:
        return f"is {len(name)} characters long; names that become file names are at most {MAX_NAME}"
    if not _SAFE.match(name):
        return ("may contain only ASCII letters, digits, '_', '.' and '-' and must start with a letter, "
                "a digit or '_' (it becomes a file name)")
    return reserved_problem(name)


_RESERVED = re.compile(r"(CON|PRN|AUX|NUL|COM[0-9]|LPT[0-9])(\..*)?\Z", re.IGNORECASE)


def reserved_problem(name: str) -> str | None:
    """Why ``name`` cannot be a file name on Windows (a device name, a trailing dot), or None."""
    if _RESERVED.match(name):
        return f"'{name}' is a device name on Windows and cannot name a file there"
    if name.endswith("."):
        return "must not end with '.' (Windows drops it from file names)"
    return None


def file_stem(name: str) -> str:
    """A file-name-safe stem for any name (link names may hold ``/`` or be long): unsafe
    characters become ``_``; a changed or shortened name gets a short hash so that two
    different names never share a file."""
    stem = re.sub(r"[^A-Za-z0-9_.\-]", "_", name).lstrip(".-") or "_"
    if stem == name and len(stem) <= MAX_NAME:
        return stem
    digest = hashlib.sha1(name.encode()).hexdigest()[:8]
    return f"{stem[:MAX_NAME - 9]}-{digest}"
