"""The build report (``report.json``): what each format could not express, and the mesh facts.

Nothing is lost silently: every loss is listed here per format and printed as a warning
on every build.
"""

from __future__ import annotations

from robotkit.model.robot import Robot


def urdf_losses(robot: Robot) -> list[str]:
    out = []
    for j in robot.joints:
        if j.dynamics is not None and j.dynamics.armature:
            out.append(f"joint '{j.name}': armature is not written (URDF has no such joint property)")
    return out


def losses(robot: Robot, facts: dict) -> dict[str, list[str]]:
    from robotkit.emit import mjcf, ros, sdf

    return {"urdf": urdf_losses(robot), "sdf": sdf.losses(robot), "mjcf": mjcf.losses(robot, facts),
            "package": ros.losses(robot)}


def report(robot: Robot, facts: dict) -> dict:
    meshes = {}
    for key, f in sorted(facts.items()):
        meshes[key] = {k: f[k] for k in ("source", "faces", "volume", "used", "repairs", "convex") if k in f}
    links = {}
    for link in robot.links:
        if link.inertial is not None:
            links[link.name] = {"mass": link.inertial.mass, "com": list(link.inertial.com),
                                "inertia": list(link.inertial.inertia), "source": link.inertial_spec.mode}
    collision = {}
    for key, f in sorted(facts.items()):
        if "pieces" in f:
            collision[key] = {"source": f["source"], "strategy": f["strategy"]["kind"], "pieces": f["pieces"],
                              "fidelity": f["fidelity"], "repair": f.get("repair")}
    meshes = {k: v for k, v in meshes.items() if k not in collision}
    return {"robot": robot.name, "losses": losses(robot, facts), "meshes": meshes, "inertials": links,
            "collision": collision}
