"""Checks on built outputs: cross-format equivalence and a simulation smoke test."""

from __future__ import annotations

from pathlib import Path


def equivalence(robot_dir: str | Path, tol: float = 1e-9, configs: int = 100,
                notes: list[str] | None = None) -> dict[str, list[str]]:
    """Compare the URDF, SDF and MJCF of a build folder pairwise; {comparison: differences}.

    ``notes`` is kept for comparisons that cannot be made (none today)."""
    from robotkit.check import kinematics as k

    robot_dir = Path(robot_dir)
    name = robot_dir.name
    urdf = robot_dir / "urdf" / f"{name}.urdf"
    u = k.read_urdf(urdf)
    m = k.read_mjcf(robot_dir / "mjcf" / f"{name}.xml")
    s = k.read_sdf(robot_dir / "model.sdf")
    g = k.read_urdf_via_libsdformat(urdf)
    result = {
        "URDF (MuJoCo) vs MJCF (MuJoCo)": k.compare(u, m, tol, configs, ignore=("velocity",)),
        "URDF (MuJoCo) vs SDF": k.compare(u, s, tol, configs, ignore=("mimic",)),
    }
    # Gazebo spawns a URDF through libsdformat's conversion, which lumps every fixed joint
    result["URDF (libsdformat) vs URDF lumped as Gazebo does"] = k.compare(k.lump(u), g, tol, configs,
                                                                                   ignore=("mimic",))
    return result
