"""The programs people load a robot into, each read back as it sees the robot.

One module per program; ``CONSUMERS`` registers each reading (name -> module, function), and
:func:`consumer_findings` compares every reading with the robot's own description (its URDF as
written, read by :mod:`robotkit.check.kinematics`): per-link and total mass, and every link
frame's pose at random joint configurations.  A program that refuses the robot, or is not
installed, is a finding too, never a silent skip.

A reading is a :class:`View`.  Gazebo lumps links joined by fixed joints when it converts a
URDF, so its view is compared with the description lumped the same way.
"""

from __future__ import annotations

import contextlib
import importlib
import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from robotkit import urdfxml
from robotkit.check.findings import Finding
from robotkit.check.kinematics import followed_mimics, lump, read_urdf, real_mass, turn
from robotkit.check.lints import resolve_uri
from robotkit.mesh.export import obj_bytes
from robotkit.mesh.io import load_mesh

CONSUMERS = {
    "Gazebo (URDF)": ("robotkit.check.consumers.gazebo", "from_urdf"),
    "Gazebo (model.sdf)": ("robotkit.check.consumers.gazebo", "from_sdf"),
    "Drake (URDF)": ("robotkit.check.consumers.drake", "from_urdf"),
    "Drake (model.sdf)": ("robotkit.check.consumers.drake", "from_sdf"),
    "Pinocchio (URDF)": ("robotkit.check.consumers.pinocchio", "from_urdf"),
    "PyBullet (URDF)": ("robotkit.check.consumers.pybullet", "from_urdf"),
    "MuJoCo (MJCF)": ("robotkit.check.consumers.mujoco", "from_mjcf"),
}

REL_TOL = 1e-9


class Refused(Exception):
    """The program refused to load the robot (its own message)."""


class Unreadable(Refused):
    """The program refused the robot for a mesh format that the description's own format
    allows (Drake and STL or DAE collision meshes): a limit of the program, not a defect of the
    description, so a warning (robotkit's builds write every collision mesh as OBJ)."""


class Limit(Refused):
    """The program cannot hold the robot for a limit of its own (PyBullet's links in one body, the
    memory Pinocchio's data needs): the program's loss, not a defect of the robot, so a warning
    (as the build states a format's own limit), never an error of the robot."""


class Missing(Exception):
    """The program is not installed (the message says how to install it)."""


@dataclass
class View:
    """A robot as one program sees it."""

    masses: dict[str, float]  # link (as the program splits the robot) -> kg
    poses: Callable[[dict[str, float]], dict[str, np.ndarray]] | None = None  # joint values -> link frames
    lumped: bool = False  # the program merges links joined by fixed joints
    lumps_world: bool = False  # ... and the links welded to the world into one body (Pinocchio's universe)
    kept: frozenset[str] = frozenset()  # but these fixed joints (the URDF's <preserveFixedJoint>)
    pose_tol: float = REL_TOL  # relative: what the program's arithmetic can hold
    notes: list[str] = field(default_factory=list)


@dataclass
class Build:
    """What a consumer reads: a build folder (or the folder of a foreign URDF)."""

    name: str
    dir: Path
    urdf: Path
    sdf: Path | None
    mjcf: Path | None
    base: str = "fixed"  # fixed | free: how the root sits (Pinocchio, PyBullet)
    package_paths: dict[str, str] = field(default_factory=dict)
    foreign: bool = False  # a URDF as its author wrote it (check on an original), not a build's


def listed(names) -> str:
    """The first three names quoted, and how many more (each once): for a note on many links."""
    names = [f"'{n}'" for n in dict.fromkeys(names)]
    return ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")


@contextlib.contextmanager
def with_mesh_paths(build: Build, formats: tuple[str, ...] | None = None):
    """A foreign URDF as a program that knows no ROS packages reads it: a copy whose mesh URIs are
    file paths (``package://`` through ``build.package_paths`` or the package folder the URDF
    sits in, relative paths from the URDF's folder).  With ``formats``, each mesh of another
    format is given as OBJ (in metres, DAE units applied).  Yields (the copy, the meshes so
    converted); a build's own URDF is yielded as it is."""
    if not build.foreign:
        yield build.urdf, []
        return
    tree = urdfxml.parse_file(build.urdf, comments=True)  # the copy keeps the comments
    for el in tree.getroot().iter():  # a line after each element: PyBullet loses characters of long lines
        el.tail = (el.tail or "") + "\n"  # (measured with 3.2.7: a xacro expansion on one line of 9 kB fails)
    converted = []
    with tempfile.TemporaryDirectory(prefix="robotkit-consumer-") as tmp:
        for k, mesh in enumerate(tree.getroot().iter("mesh")):
            uri = mesh.get("filename") or ""
            path = resolve_uri(uri, build.urdf.parent, build.package_paths)
            if path is None or not path.is_file():
                continue  # the program says what it cannot find
            if formats is not None and path.suffix.lower() not in formats:
                obj = Path(tmp) / f"{k}_{path.stem}.obj"
                obj.write_bytes(obj_bytes(load_mesh(str(path))))
                converted.append(uri)
                path = obj
            mesh.set("filename", str(path.absolute()))
        copy = Path(tmp) / build.urdf.name
        tree.write(str(copy), xml_declaration=True, encoding="utf-8")
        yield copy, converted


def read(consumer: str, build: Build) -> View:
    module, function = CONSUMERS[consumer]
    return getattr(importlib.import_module(module), function)(build)


def configurations(reference, count: int, seed: int = 0) -> list[dict[str, float]]:
    """Joint values: the zero pose, then random ones within limits (mimic joints follow)."""
    rng = np.random.default_rng(seed)
    reference = followed_mimics(reference)
    movable = {n: j for n, j in reference.joints.items() if j.type in ("revolute", "continuous", "prismatic")}
    out = []
    for k in range(count):
        q = {}
        for n, j in sorted(movable.items()):
            if j.mimic is not None:
                continue
            lo, hi = (j.lower, j.upper) if j.lower is not None else (
                (-math.pi, math.pi) if j.type != "prismatic" else (-0.5, 0.5))
            q[n] = float(rng.uniform(lo, hi)) if k else 0.0
        for n, j in sorted(movable.items()):
            if j.mimic is not None:
                q[n] = j.mimic[1] * q.get(j.mimic[0], 0.0) + j.mimic[2]
        out.append(q)
    return out


def compare(reference, view: View, configs: list[dict[str, float]], tol: float = REL_TOL) -> list[str]:
    """Differences between the description (``reference``, a KModel) and a program's view."""
    reference = followed_mimics(reference)
    ref = lump(reference, view.kept, view.lumps_world) if view.lumped else reference
    expected = {n: real_mass(link.mass) for n, link in ref.links.items() if n != "world"}
    total = sum(expected.values())
    scale = max(total, 1e-12)
    diffs = []
    got_total = sum(real_mass(m) for m in view.masses.values())
    if abs(got_total - total) > tol * scale:
        diffs.append(f"total mass {got_total:.12g} kg, the description's is {total:.12g} kg")
    for name, m in sorted(view.masses.items()):
        if name not in expected:
            if real_mass(m) > 0:
                diffs.append(f"link '{name}' weighs {m:.12g} kg and is not in the description")
            continue
        if abs(real_mass(m) - expected[name]) > tol * max(expected[name], 1e-12 * scale):
            hint = " (its default for a link without <inertial>)" if m == 1.0 and expected[name] == 0 else ""
            diffs.append(f"link '{name}' weighs {m:.12g} kg{hint}, the description says {expected[name]:.12g} kg")
    for name, m in sorted(expected.items()):
        if m > 0 and name not in view.masses:
            diffs.append(f"link '{name}' ({m:.6g} kg) is missing")
    if view.poses is None:
        return diffs
    root = ref.root()
    for q in configs:
        want, got = ref.fk(q), view.poses(q)
        if root not in got:
            diffs.append(f"the root link '{root}' has no frame")
            break
        Rw, Rg = np.linalg.inv(want[root]), np.linalg.inv(got[root])
        for name in sorted(set(want) & set(got)):
            A, B = Rw @ want[name], Rg @ got[name]
            size = max(1.0, float(np.abs(A[:3, 3]).max()))
            ptol = max(tol, view.pose_tol)
            if np.abs(A[:3, 3] - B[:3, 3]).max() > ptol * size:
                diffs.append(f"link '{name}' is at {np.round(B[:3, 3], 9).tolist()}, the description puts it at "
                             f"{np.round(A[:3, 3], 9).tolist()} (joint values {q})")
                return diffs
            if np.abs(A[:3, :3] - B[:3, :3]).max() > ptol:
                diffs.append(f"link '{name}' is turned by {turn(A, B):.3g} rad from the orientation the description "
                             f"gives it (joint values {q})")
                return diffs
    return diffs


def consumer_findings(build: Build, consumers=None, configs: int = 20) -> tuple[list[Finding], dict]:
    """Each program's reading compared with the description: findings, and a summary per
    program (what it loaded, its total mass, its notes) for report.json."""
    findings, summary = [], {}
    subject = f"robot '{build.name}'"
    try:
        reference = read_urdf(build.urdf)
        qs = configurations(reference, configs)
    except ValueError as exc:  # MuJoCo's compiler, our URDF reader, refuses it (the lints say why)
        reference = None
        findings.append(Finding("warning", "consumer", subject, "each program's reading is not compared with the "
                                f"description, which MuJoCo's URDF compiler cannot read: {' '.join(str(exc).split())}"))
    for consumer in consumers or CONSUMERS:
        try:
            view = read(consumer, build)
        except Missing as exc:
            # a plain install has MuJoCo but not Drake, Pinocchio, PyBullet: say what was skipped
            findings.append(Finding("warning", "consumer", subject, f"{consumer}: not checked: {exc}"))
            summary[consumer] = {"loaded": None, "reason": str(exc)}
            continue
        except Limit as exc:
            findings.append(Finding("warning", "consumer", subject, f"{consumer}: not checked, a limit of the "
                                    f"program: {exc}", "a limit of the program, not a defect of the robot"))
            summary[consumer] = {"loaded": False, "reason": str(exc), "limit": True}
            continue
        except Unreadable as exc:
            findings.append(Finding("warning", "consumer", subject, f"{consumer} refuses the robot: {exc}",
                                    "a limit of the program: robotkit import and build write OBJ collision meshes"))
            summary[consumer] = {"loaded": False, "reason": str(exc)}
            continue
        except Refused as exc:
            findings.append(Finding("error", "consumer", subject, f"{consumer} refuses the robot: {exc}"))
            summary[consumer] = {"loaded": False, "reason": str(exc)}
            continue
        diffs = compare(reference, view, qs) if reference is not None else []
        findings += [Finding("error", "consumer", subject, f"{consumer}: {d}") for d in diffs]
        findings += [Finding("warning", "consumer", subject, f"{consumer}: {n}") for n in view.notes]
        summary[consumer] = {"loaded": True, "mass": sum(view.masses.values()), "links": len(view.masses),
                             "agrees": not diffs if reference is not None else None, "notes": view.notes}
    return findings, summary
