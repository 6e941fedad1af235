"""The results of a build folder's pure check stages, cached by content.

The consumers (Drake, Pinocchio, PyBullet, MuJoCo; Gazebo's view through libsdformat), the
equivalence, self-collision and each simulator's motion runs read nothing but the build folder's
files, with libraries and programs whose versions are known: the same files, the same robotkit and the same libraries give the same result.  Such a
result is kept in robotkit's content-addressed cache (:mod:`robotkit.mesh.cache`, the build's own:
``$ROBOTKIT_CACHE``...) under a key made of the stage, every file of the folder (its relative
path and bytes; not the picture report, which no stage reads), the folder's absolute path (the
results name files in it), robotkit's own files under ``robotkit/``, the libraries' versions and
the outside programs' files (libsdformat's reading feeds the equivalence stage and Gazebo's view).
A later check of the same folder takes the result from there: no worker process, no import of
the library.  Stored as JSON (findings as their fields): a cache shared with others holds no
pickles.  ``ROBOTKIT_CHECK_CACHE=0`` turns it off (every stage computed, nothing stored)."""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import os
import shutil
import sys
from pathlib import Path

from robotkit.check.findings import Finding
from robotkit.emit.layout import PICTURES
from robotkit.mesh.cache import code_digest

LIBRARIES = ("mujoco", "pybullet", "drake", "pin", "numpy", "scipy")
"""The libraries whose versions a cached stage's result depends on (``pin`` is Pinocchio)."""
SKIPPED = (PICTURES,)
"""The build folder's parts no cached stage reads (the picture report)."""
OP = "check-stage/1"


def enabled() -> bool:
    return os.environ.get("ROBOTKIT_CHECK_CACHE", "1") != "0"


@functools.lru_cache(maxsize=None)
def installed_versions(names: tuple[str, ...]) -> dict[str, str]:
    """The installed version of each distribution ``names`` (robotkit.mesh.cache.library_versions'
    answer), read from the names of the ``NAME-VERSION.dist-info`` folders on ``sys.path``, the
    first one found as importlib.metadata takes it: a listing of each folder, not
    importlib.metadata's 0.25 s of CPU; a distribution not found so is asked of importlib.metadata."""
    from importlib import metadata

    import robotkit

    wanted = {n.lower().replace("-", "_").replace(".", "_"): n for n in names}
    found: dict[str, str] = {}
    for folder in sys.path:
        try:
            entries = sorted(os.listdir(folder or "."))
        except OSError:
            continue
        for entry in entries:
            name, _, version = entry.removesuffix(".dist-info").partition("-")
            if entry.endswith(".dist-info") and wanted.get(name.lower().replace(".", "_")) not in (None, *found):
                found[wanted[name.lower().replace(".", "_")]] = version
    out = {}
    for n in names:
        if n not in found:
            try:
                found[n] = metadata.version(n)
            except metadata.PackageNotFoundError:
                found[n] = "not installed"
        out[n] = found[n]
    out["robotkit"] = robotkit.__version__
    return out


@functools.lru_cache(maxsize=None)
def programs() -> str:
    """The outside programs and library the stages run (check_urdf, ``ign``, libsdformat), each
    as where it is, its size and its time of change: an upgrade of one is a miss."""
    import subprocess

    from robotkit.check.programs import LIBRARY

    found = [shutil.which("check_urdf"), shutil.which("ign")]
    try:
        listed = subprocess.run(["ldconfig", "-p"], capture_output=True, text=True).stdout
    except OSError:
        listed = ""
    found += sorted({line.split("=>")[-1].strip() for line in listed.splitlines() if f"lib{LIBRARY}." in line})
    out = []
    for path in found:
        try:
            st = os.stat(path) if path else None
        except OSError:
            st = None
        out.append(f"{path}:{st.st_size}:{st.st_mtime_ns}" if st else f"{path}:missing")
    return "\n".join(out)


def folder_digest(folder: Path) -> str:
    """sha256 of every file of ``folder`` (relative path and bytes) but :data:`SKIPPED`'s."""
    h = hashlib.sha256()
    for path in sorted(p for p in folder.rglob("*") if p.is_file()):
        rel = path.relative_to(folder)
        if rel.parts[0] in SKIPPED:
            continue
        h.update(rel.as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()


class StageCache:
    """The cached results of one build folder's stages (None: caching is off)."""

    def __init__(self, folder: Path):
        from robotkit.mesh.cache import Cache

        self.cache = Cache(versions=installed_versions(LIBRARIES))
        self.inputs = [str(Path(folder).resolve()), folder_digest(Path(folder)), code_digest(), programs()]

    def key(self, stage: str) -> str:
        return self.cache.key(OP, {"stage": stage}, self.inputs)

    def has(self, stage: str) -> bool:
        return self.cache.manifest_path(self.key(stage)).is_file()

    def get(self, stage: str):
        """The stage's cached value (JSON), or None."""
        from robotkit.mesh.cache import CacheCorrupt

        try:
            value = self.cache.get(self.key(stage))
            return None if value is None else json.loads(bytes(value["value.json"]))
        except (OSError, ValueError, KeyError, TypeError, CacheCorrupt):
            return None

    def put(self, stage: str, value) -> None:
        from robotkit.mesh.cache import Files

        data = json.dumps(value, sort_keys=True, allow_nan=True).encode()
        try:
            self.cache.put(self.key(stage), Files({"value.json": data}), op=OP, params={"stage": stage})
        except (OSError, TypeError, ValueError):
            pass  # a cache that cannot be written costs time, never correctness


def stage_cache(folder: Path) -> StageCache | None:
    """The folder's stage cache; None when it is turned off or cannot be set up."""
    if not enabled():
        return None
    try:
        return StageCache(folder)
    except (OSError, ValueError):
        return None


def kept(findings: list[Finding]) -> bool:
    """Whether a stage's findings may be cached: not when the stage itself could not run (a worker
    that died, a program that crashed: maybe only this once)."""
    return not any("stage could not run" in f.message for f in findings)


def to_json(findings: list[Finding]) -> list[dict]:
    return [dataclasses.asdict(f) for f in findings]


def from_json(rows: list[dict]) -> list[Finding]:
    return [Finding(**row) for row in rows]
