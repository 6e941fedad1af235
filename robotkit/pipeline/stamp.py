"""The no-op fast path: a stamp of every input and output of a successful build.

A successful ``robotkit build`` writes ``OUT/.robotkit/stamp-<key>.json``: the
size and modification time (ns) of every file the build read or wrote (the
recipe files and the files they include, meshes, map images, templates,
robotkit's own source files, every target), the build's options and the
robotkit and Python versions.  ``<key>`` is a digest of the options (the
recipe paths, the output folder and whatever else shapes the outputs, e.g.
``--arg`` overrides), so builds of different recipes into one folder keep
their own stamps.

The next build with the same options first reads the stamp (standard library
only: no numpy, pydantic, doit, jinja2 or trimesh is imported): when every
file still has its recorded size and time, nothing can have changed and the
build answers "up to date" without loading the recipe or the task graph.
Any difference, a missing file, or an unreadable stamp falls through to the
real build (doit's own content checks), which removes the stamp first and
writes a new one only when it succeeds.  Like make, this trusts that a file
whose content changed also changed its size or modification time.
"""

from __future__ import annotations

import json
import os
import sys
import zlib

from robotkit import __version__
from robotkit.pipeline.publish import STATE  # standard library only, as this module

FORMAT = 1


def _key(options: dict) -> str:
    """A short name for the options (the stamp holds them in full and is checked against them)."""
    text = json.dumps(options, sort_keys=True, separators=(",", ":"))
    return f"{zlib.crc32(text.encode('utf-8')):08x}"


def options(recipes, out_dir, extra: dict | None = None) -> dict:
    """What, besides file contents, decides a build's outputs (the read roots widened on
    purpose, ROBOTKIT_ROOT, decide whether it succeeds)."""
    roots = os.environ.get("ROBOTKIT_ROOT")  # robotkit.paths.ROOT_ENV, not imported: this path stays light
    return {"recipes": [os.path.abspath(os.fspath(r)) for r in recipes], "out": os.path.abspath(os.fspath(out_dir)),
            **({"roots": roots} if roots else {}), **(extra or {})}


def build_options(recipes, out_dir, ros: str | None = None, report: bool = True, moveit: bool = False,
                  args: dict[str, str] | None = None, variant: str | None = None) -> dict:
    """:func:`options` of a build with these settings (``robotkit build``'s, or a build that
    another command runs: ``check`` and ``report`` of a recipe)."""
    extra = {**({"ros": ros} if ros else {}), **({} if report else {"no_report": True}),
             **({"moveit": True} if moveit else {}), **({"args": dict(args)} if args else {}),
             **({"variant": variant} if variant is not None else {})}
    return options(recipes, out_dir, extra or None)


def path(out_dir, opts: dict) -> str:
    return os.path.join(os.path.abspath(os.fspath(out_dir)), STATE, f"stamp-{_key(opts)}.json")


def _versions() -> dict:
    return {"format": FORMAT, "robotkit": __version__, "python": sys.version}


def _own_sources() -> list[str]:
    """robotkit's Python files: an edited or upgraded robotkit is a change."""
    root = os.path.dirname(os.path.abspath(__file__))
    out = []
    stack = [root]
    while stack:
        d = stack.pop()
        with os.scandir(d) as it:
            for e in it:
                if e.is_dir(follow_symlinks=False):
                    if e.name != "__pycache__":
                        stack.append(e.path)
                elif e.name.endswith(".py"):
                    out.append(e.path)
    return sorted(out)


def _stat(p: str):
    st = os.stat(p)
    return [st.st_size, st.st_mtime_ns]


def up_to_date(out_dir, opts: dict) -> dict | None:
    """The stamp's record (``robots``, ``tasks``, ``warnings``) when nothing changed, else None."""
    try:
        with open(path(out_dir, opts), encoding="utf-8") as f:
            data = json.load(f)
        if data.get("versions") != _versions() or data.get("options") != opts:
            return None
        files = data["files"]
        if sorted(files) != sorted(set(files) | set(_own_sources())):
            return None  # a robotkit source file was added
        for p, rec in files.items():
            if _stat(p) != rec:
                return None
        return data["result"]
    except (OSError, ValueError, KeyError, TypeError):
        return None


def remove(out_dir, opts: dict) -> None:
    try:
        os.remove(path(out_dir, opts))
    except OSError:
        pass


def stats(files) -> dict:
    """``{absolute path: [size, mtime_ns]}`` of ``files`` as they are now."""
    return {os.path.abspath(f): _stat(f) for f in files}


def write(out_dir, opts: dict, inputs: dict, outputs, result: dict) -> None:
    """Record ``inputs`` (:func:`stats` taken before the build ran), ``outputs`` and robotkit's
    own sources as they are now, after a successful build."""
    target = path(out_dir, opts)
    files = {**stats(_own_sources()), **inputs, **stats(outputs)}
    record = {"versions": _versions(), "options": opts, "files": dict(sorted(files.items())), "result": result}
    os.makedirs(os.path.dirname(target), exist_ok=True)
    tmp = f"{target}.{os.getpid()}.tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(record, f, separators=(",", ":"))
    os.replace(tmp, target)
