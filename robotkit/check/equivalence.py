"""Checks on built outputs: cross-format equivalence and a simulation smoke test."""

from __future__ import annotations

from pathlib import Path

from robotkit.check import kinematics as k
from robotkit.check.findings import EQUIVALENCE_CONFIGS
from robotkit.emit.layout import robot_layout
from robotkit.emit.sdf import names_apart


def equivalence(robot_dir: str | Path, tol: float = 1e-9, configs: int = EQUIVALENCE_CONFIGS,
                notes: list[str] | None = None) -> dict[str, list[str]]:
    """Compare the URDF, SDF and MJCF of a build folder pairwise; {comparison: differences}.
    A folder whose MJCF the build left out (a limit of the format) compares the others.

    ``notes`` is kept for comparisons that cannot be made (none today)."""
    layout = robot_layout(robot_dir)
    u = k.read_urdf(layout.urdf)
    s = _urdf_names(k.read_sdf(layout.sdf), u)
    g = k.read_urdf_via_libsdformat(layout.urdf)
    result = {}
    if "mjcf" not in layout.left_out():
        result["URDF (MuJoCo) vs MJCF (MuJoCo)"] = k.compare(u, k.read_mjcf(layout.mjcf), tol, configs,
                                                            ignore=("velocity",))
    result["URDF (MuJoCo) vs SDF"] = k.compare(u, s, tol, configs, ignore=("mimic",))
    # Gazebo spawns a URDF through libsdformat's conversion, which lumps every fixed joint and
    # reprints each orientation (to sqrt(eps) at a pitch of +-pi/2)
    result["URDF (libsdformat) vs URDF lumped as Gazebo does"] = k.compare(
        k.lump(u, u.kept), g, tol, configs, ignore=("mimic",), pose_tol=max(tol, k.LIBSDFORMAT_PRECISION))
    return result


def _urdf_names(sdf: k.KModel, urdf: k.KModel) -> k.KModel:
    """``sdf`` with each joint under its URDF name: model.sdf renames a joint named like a link
    (robotkit.emit.sdf.joint_names), which is the same joint."""
    back = {new: old for old, new in names_apart(list(urdf.links), list(urdf.joints)).items()}
    for joint in sdf.joints.values():
        joint.name = back.get(joint.name, joint.name)
    sdf.joints = {back.get(name, name): joint for name, joint in sdf.joints.items()}
    return sdf
