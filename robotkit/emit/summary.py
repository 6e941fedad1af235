"""The build's summary (``report.json``): what each format could not express, what each program
that loads the outputs will see, and the mesh facts.

Nothing is lost silently: every loss is listed here per format.  The losses the recipe could
avoid (``losses``) are printed as warnings on every build; those that are the format's nature
(``limits``: MJCF has no velocity limit, URDF no armature; :class:`robotkit.emit.formats.Limit`)
are listed here once per build and printed by no build.
"""

from __future__ import annotations

import json

from robotkit.emit import layout, mjcf, moveit, ros, sdf
from robotkit.emit.controllers import armature_losses, gravcomp_losses, joints_phrase
from robotkit.emit.formats import Format, Limit
from robotkit.emit.sensors import host_of
from robotkit.emit.urdf import massless_mass, typed_transmissions
from robotkit.model.robot import Robot


def urdf_losses(robot: Robot) -> list[str]:
    out = armature_losses(robot, "URDF")
    for extra in robot.urdf_extras:
        for name, kind in typed_transmissions(extra)[1]:
            out.append(f"transmission '{name}' names its class in <plugin> only: written with <type>{kind}</type> "
                       "too, without which Drake refuses the URDF")
    return out


def losses(robot: Robot, facts: dict) -> dict[str, list[str]]:
    """Every loss per format, the format's limits (:class:`Limit`) among them."""
    return {"urdf": urdf_losses(robot) + mjcf.loop_losses(robot, "the URDF") + mjcf.mjcf_extras_losses(robot, "the URDF"),
            "sdf": sdf.losses(robot) + mjcf.loop_losses(robot, "model.sdf") + mjcf.mjcf_extras_losses(robot, "model.sdf"),
            "mjcf": mjcf.losses(robot, facts),
            "package": ros.losses(robot) + gravcomp_losses(robot, "the ros_control controllers (controllers.yaml)")
            + matrix_losses(robot),
            **({"moveit": moveit.losses(robot)} if robot.moveit else {})}


def matrix_losses(robot: Robot) -> list[str]:
    """The links whose URDF and SDF collision geometry is not the MJCF's, on which the
    self-collision matrix was sampled (robotkit.model.selfcollision)."""
    if robot.collision_matrix is None:
        return []
    differ = [link.name for link in robot.links
              if any(link.collisions_for(fmt) != link.collisions_for("mjcf") for fmt in ("urdf", "sdf"))]
    if not differ:
        return []
    return [f"link{joints_phrase(differ)[len('joint'):]}: the self-collision matrix (srdf, model.sdf's masks) "
            "was sampled on the MJCF's collision geometry, which differs from the URDF's and SDF's here"]


def consumers(robot: Robot) -> dict:
    """What each program will see, from the model alone (``robotkit check`` loads them all)."""
    parent = {j.child: j for j in robot.joints}

    def lumped_into(name: str) -> str:  # libsdformat and Pinocchio merge fixed joints
        while name in parent and parent[name].type == "fixed" and parent[name].parent != "world":
            name = parent[name].parent
        return name

    massless = sorted(link.name for link in robot.links if massless_mass(robot, link) is not None)
    frames = sorted(robot.frame_links())
    renamed = {k: v for k, v in sdf.joint_names(robot).items() if k != v}
    mass = sum(link.inertial.mass for link in robot.links if link.inertial is not None)
    return {
        "mass": mass,
        "Gazebo (URDF)": {"links": sorted({lumped_into(link.name) for link in robot.links} - {"world"}),
                          "lumped": {link.name: lumped_into(link.name) for link in robot.links
                                     if lumped_into(link.name) != link.name}},
        "Gazebo (model.sdf)": {"frames": {f: host_of(robot, f)[0] for f in frames}, "renamed_joints": renamed},
        "URDF massless links": {"links": massless, "note": "explicit <inertial> of 1e-300 kg (0 for a root fixed "
                                "to the world): no 1 kg default in PyBullet, lumpable by libsdformat"},
        "MuJoCo (MJCF)": {"base": "welded to the world" if robot.base == "fixed" or robot.root == "world"
                          else "free joint", "standing": robot.root != "world"},
    }


def summary(robot: Robot, facts: dict) -> dict:
    """The content of ``report.json``: losses, consumers, mesh facts, inertials, collision pieces."""
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
    every = losses(robot, facts)
    out = {"robot": robot.name, "losses": {fmt: [x for x in items if not isinstance(x, Limit)]
                                           for fmt, items in every.items()},
           "limits": {fmt: limits for fmt, items in every.items()
                      if (limits := [str(x) for x in items if isinstance(x, Limit)])},
           "consumers": consumers(robot), "meshes": meshes, "inertials": links, "collision": collision}
    lost = {f.name: why for f in mjcf.FORMATS if f.limit is not None and (why := f.limit(robot))}
    if lost:  # the formats the build leaves out at their own limits (robotkit.emit.formats.Outputs.lost)
        out["left_out"] = lost
    if robot.drive_report:  # the tuner's gains, their reasons and checks (robotkit.model.gains)
        out["actuators"] = json.loads(robot.drive_report)
    if robot.metadata.ledger:  # what an import could not carry (robotkit.importer)
        out["ledger"] = list(robot.metadata.ledger)
    if robot.poses:
        out["poses"] = {p.name: dict(p.values) for p in robot.poses}
    if robot.collision_matrix is not None:  # robotkit.model.selfcollision
        out["self_collision"] = robot.collision_matrix.to_json()
    return out


def render_summary(robot: Robot, facts: dict | None = None) -> str:
    return json.dumps(summary(robot, facts or {}), indent=1, sort_keys=True) + "\n"


FORMATS = [Format("report", render_summary, layout.SUMMARY, reads="summary")]
