"""Checks on built outputs: cross-format equivalence and a simulation smoke test."""

from __future__ import annotations

from pathlib import Path


def equivalence(robot_dir: str | Path, tol: float = 1e-9, configs: int = 100,
                notes: list[str] | None = None) -> dict[str, list[str]]:
    """Compare the URDF, SDF and MJCF of a build folder pairwise; {comparison: differences}.

    A comparison that cannot be made is left out and explained in ``notes``."""
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
    # libsdformat's URDF conversion drops massless links and lumps what hangs below them
    # into the parent: compare with it only when it kept every link that has mass.
    massful = {n for n, link in u.links.items() if link.mass > 0}
    lumped = sorted(massful - set(g.links))
    if lumped and notes is not None:
        notes.append(f"{name}: URDF (libsdformat) vs SDF not compared: libsdformat's URDF conversion "
                     f"drops massless links and lumps {', '.join(lumped)} into their parents")
    if not lumped:
        g_only = {n for n in u.links if n not in g.links}
        result["URDF (libsdformat) vs SDF"] = k.compare(g, _without(s, g_only), tol, configs, ignore=("mimic",))
    return result


def _without(model, names: set[str]):
    """``model`` without the (massless) links ``names`` and the fixed joints to them."""
    import copy

    model = copy.copy(model)
    model.links = {n: v for n, v in model.links.items() if n not in names}
    model.joints = {n: j for n, j in model.joints.items() if j.child not in names}
    return model
