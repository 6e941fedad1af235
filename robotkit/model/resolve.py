"""Recipe -> resolved :class:`Robot`, collecting every problem with its location.

Two steps:

- :func:`resolve` turns a validated recipe into a structural robot (names,
  frames, geometry, joints, how each inertial is obtained) and checks the
  kinematic tree.  It reads no mesh, so it is cheap enough for every build.
- :func:`finalize` fills in what needs mesh work: recentering offsets and
  computed inertials, from the mesh facts the mesh tasks wrote.
"""

from __future__ import annotations

import hashlib
import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from robotkit import presets
from robotkit.errors import Problem, RecipeError, display_path
from robotkit.geometry import matrix_rpy
from robotkit.model import inertia_policy, massprops
from robotkit.model.drives import resolve_actuators, resolve_poses, resolve_settings, unknown_name
from robotkit.model.massprops import Bounding, bounding_primitive, combine
from robotkit.model.robot import (
    Author, Contact, Dynamics, Geom, Inertial, InertialSpec, Joint, Limit, Link, Material, MeshRef,
    Loop, Metadata, Mimic, Pose, Robot, Sensor, Shape, Strategy, World,
)
from robotkit.paths import ReadPolicy, file_stem, recipe_policy
from robotkit.recipe import schema
from robotkit.recipe.load import LoadedRecipe, sort_problems
from robotkit.recipe.schema import UNITS, Collision


def _h(text: str, n: int = 8) -> str:
    return hashlib.sha1(text.encode()).hexdigest()[:n]


def _ident(path: str, base_dir: str) -> str:
    """A mesh file's identity in task keys: its path relative to the recipe's folder (robotkit's
    own preset meshes by name), so keys never depend on where the recipe or robotkit sit."""
    presets = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "presets")
    if os.path.commonpath([os.path.abspath(path), presets]) == presets:
        return "robotkit:" + Path(os.path.relpath(path, presets)).as_posix()
    return Path(os.path.relpath(path, base_dir)).as_posix()


def _t(v) -> tuple[float, ...]:
    return tuple(float(x) for x in v)


def resolve_checked(loaded: LoadedRecipe, ros: str | None = None, moveit: bool = False) -> Robot:
    """The resolved robot; RecipeError with the loading problems and resolution's own, all together."""
    if not loaded.problems:
        return resolve(loaded, ros, moveit)
    problems = list(loaded.problems)
    if loaded.recipe is not None:
        try:
            resolve(loaded, ros)
        except RecipeError as exc:
            problems.extend(p for p in exc.problems if p not in problems)
    raise RecipeError(sort_problems(problems, loaded.file))


@dataclass
class _Context:
    """What resolving one recipe reads and collects: the recipe, its line marks and folder, where
    it may read, each mesh source's output file name, and the problems found so far."""

    r: object  # robotkit.recipe.schema.Recipe
    marks: object  # robotkit.recipe.load.Marks
    base_dir: str
    reads: ReadPolicy
    sources: dict[str, str]
    material_names: set[str]
    problems: list[Problem] = field(default_factory=list)

    def report(self, path: tuple, message: str) -> None:
        self.problems.append(self.marks.problem(path, message))

    def make_geom(self, g, path: tuple, policy, role: str = "visual") -> Geom | None:
        """A recipe geometry as a model Geom; None (reported) when its mesh cannot be used."""
        r = self.r
        if g.material is not None and g.material not in self.material_names:
            self.report(path + ("material",), unknown_name("material", g.material, self.material_names))
        origin = Pose(_t(g.origin.xyz), _t(g.origin.rpy))
        if g.box is not None:
            shape = Shape("box", size=_t(g.box.size))
        elif g.cylinder is not None:
            shape = Shape("cylinder", radius=float(g.cylinder.radius), length=float(g.cylinder.length))
        elif g.sphere is not None:
            shape = Shape("sphere", radius=float(g.sphere.radius))
        else:
            if (why := self._mesh_refusal(g.mesh)) is not None:
                self.report(path + ("mesh",), f"mesh file '{_show(g.mesh)}' {why}")
                return None
            self.sources.setdefault(g.mesh, _safe_name(g.mesh))
            if g.scale is not None:
                s = g.scale if isinstance(g.scale, list) else [g.scale] * 3
                scale = _t(s)
            else:
                f = UNITS[g.units or r.units]
                scale = (f, f, f)
            dec = (g.decimate or r.meshes.decimate) if role == "visual" else g.decimate
            dec = (("faces", dec.faces) if dec.faces is not None else ("ratio", dec.ratio)) if dec else None
            # a mirroring scale (a mirrored part): consumers render negative scales inside out, so
            # the outputs get a mirrored copy in metres with its faces flipped (robotkit.pipeline.actions)
            mirrored = scale[0] * scale[1] * scale[2] < 0
            if mirrored and dec is None:
                dec = ("none", 0)
            key = f"{os.path.splitext(os.path.basename(g.mesh))[0]}-{_h(repr((_ident(g.mesh, self.base_dir), scale, policy, dec)))}"
            file_name = self.sources[g.mesh] if dec is None else (
                os.path.splitext(self.sources[g.mesh])[0] + ("_mirrored" if mirrored else "") + ".stl")
            shape = Shape("mesh", mesh=MeshRef(g.mesh, scale, file_name, key, policy, decimate=dec,
                                               repair=dec is not None and dec[0] != "none" and r.meshes.repair))
        return Geom(shape, origin, (0.0, 0.0, 0.0), g.material, g.recenter)

    def _mesh_refusal(self, mesh: str) -> str | None:
        """Why a mesh file cannot be used (outside the readable folders, missing, a format robotkit
        does not read), or None."""
        if (why := self.reads.refusal(mesh)) is not None:
            return why
        if not os.path.isfile(mesh):
            return "does not exist"
        if os.path.splitext(mesh)[1].lower() not in (".stl", ".obj", ".dae"):
            return "has an unsupported format (use STL, OBJ or DAE)"
        return None


def resolve(loaded: LoadedRecipe, ros: str | None = None, moveit: bool = False) -> Robot:
    """The structural robot of a loaded recipe; ``ros`` overrides the recipe's ``ros``, ``moveit``
    turns its ``moveit`` on.

    Every problem is collected (links, joints, sensors, actuators, worlds, the ROS and Gazebo
    pair, the kinematic tree) and raised together as one RecipeError."""
    r = loaded.recipe
    base_dir = os.path.dirname(str(loaded.file))
    materials = tuple(Material(name, _t(m.rgba), m.gazebo) for name, m in r.materials.items())
    cx = _Context(r, loaded.marks, base_dir, recipe_policy(loaded.file), _mesh_file_names(r, base_dir),
                  {m.name for m in materials})
    links = [_link(cx, name, link) for name, link in r.links.items()]
    joints = [_joint(cx, name, j, [link.name for link in links]) for name, j in r.joints.items()]
    extra_links, extra_joints, sensors = _sensors(cx)
    known_links = {link.name for link in links}
    for link in extra_links:
        if link.name in known_links:
            cx.report(("sensors",), f"sensor frame '{link.name}' is also a link's name; "
                                    "give the sensor another name or 'frame'")
        known_links.add(link.name)
    links += extra_links
    joints += extra_joints
    actuators, joints = resolve_actuators(cx.report, cx.r.actuators, joints)
    poses = resolve_poses(cx.report, cx.r.poses, joints)
    collision = resolve_settings(cx.report, cx.r.self_collision, [link.name for link in links])
    worlds = _worlds(cx)
    ros, gazebo = _ros_and_gazebo(cx, ros)
    link_names = [link.name for link in links]
    links = _share_mesh_tasks(links)
    if loaded.partial != "tree":  # joints dropped as invalid would show as false tree problems
        cx.problems.extend(_check_tree(link_names, joints, cx.marks))
    loops = _loops(cx, set(link_names))
    if cx.problems:
        raise RecipeError(cx.problems)
    return Robot(r.robot, tuple(links), tuple(joints), materials, _metadata(r.metadata), r.self_collide,
                 tuple(r.urdf_extras), tuple(worlds), tuple(sensors), tuple(actuators), gazebo, ros, r.base, tuple(poses),
                 self_collision=collision, moveit=r.moveit or moveit, mjcf_extras=tuple(r.mjcf_extras),
                 loops=loops)


def _loops(cx, links: set[str]) -> tuple[Loop, ...]:
    out = []
    for name, loop in cx.r.loops.items():
        for end in ("link1", "link2"):
            if getattr(loop, end) not in links:
                cx.report(("loops", name, end), unknown_name("link", getattr(loop, end), sorted(links)))
        if loop.link1 == loop.link2:
            cx.report(("loops", name, "link2"), f"a loop cannot close link '{loop.link1}' on itself")
        out.append(Loop(name, loop.type, loop.link1, Pose(_t(loop.origin1.xyz), _t(loop.origin1.rpy)),
                        loop.link2, Pose(_t(loop.origin2.xyz), _t(loop.origin2.rpy)),
                        None if loop.solref is None else tuple(loop.solref),
                        None if loop.solimp is None else tuple(loop.solimp), loop.torquescale))
    return tuple(out)


def _safe_name(src: str) -> str:
    """A mesh file's own name, safe as an output file name."""
    stem, ext = os.path.splitext(os.path.basename(src))
    return file_stem(stem) + (ext if file_stem(ext[1:]) == ext[1:] else "")


def _mesh_file_names(r, base_dir: str) -> dict[str, str]:
    """Output file names of the links' meshes by source: the file's own name, made unique when
    two different sources share it."""
    sources: dict[str, str] = {}
    for link in r.links.values():
        for kind in ("visual", "collision"):
            for geom in _geoms(getattr(link, kind)):
                if geom.mesh:
                    sources.setdefault(geom.mesh, "")
    taken: dict[str, int] = {}
    for src in sources:
        taken[_safe_name(src)] = taken.get(_safe_name(src), 0) + 1
    for src in sources:
        name = _safe_name(src)
        if taken[name] > 1:
            stem, ext = os.path.splitext(name)
            name = f"{stem}-{_h(os.path.relpath(src, base_dir))}{ext}"
        sources[src] = name
    return sources


def _link(cx: _Context, name: str, link) -> Link:
    """One recipe link: its geometry, how its inertial is obtained, which meshes are only drawn."""
    lp = ("links", name)
    ispec = link.inertial
    policy = (ispec.open_mesh if ispec and ispec != "none" and ispec.open_mesh else None) or cx.r.open_mesh
    unusable: set[str] = set()  # roles with a geometry already reported (a missing mesh): no second line
    visuals = _visuals(cx, lp, link, policy, unusable)
    collisions, format_collisions = _collisions(cx, lp, link, visuals, policy, unusable)
    spec = _link_inertial(cx, lp, link, visuals, collisions, unusable)
    visuals, collisions, format_collisions = _drawn_only(spec, visuals, collisions, format_collisions, cx.base_dir)
    contact = None
    if link.contact is not None:
        c = link.contact
        contact = Contact(c.mu1, c.mu2 if c.mu2 is not None else c.mu1, c.kp, c.kd)
    return Link(name, tuple(visuals), tuple(collisions), spec,
                spec.explicit if spec.mode == "explicit" else None, contact, tuple(format_collisions))


def _visuals(cx: _Context, lp: tuple, link, policy, unusable: set[str]) -> list[Geom]:
    visuals = []
    for i, g in _indexed(link.visual):
        geom = cx.make_geom(g, lp + ("visual",) + i, policy)
        if geom is not None:
            visuals.append(geom)
        else:
            unusable.add("visual")
    return visuals


def _collisions(cx: _Context, lp: tuple, link, visuals: list[Geom], policy, unusable: set[str]):
    """(collision geometry, [(format, its own collision geometry)]) of a link: given, the visual
    geometry, or made by a strategy from the visual (or the strategy's source) geometry."""
    r = cx.r
    collisions: list[Geom] = []
    format_collisions: list = []
    strategy = link.collision if isinstance(link.collision, Collision) else (
        r.meshes.collision if link.collision == "visual" else None)
    if isinstance(link.collision, Collision) and r.meshes.collision is not None:
        # what the link does not say comes from the project default
        strategy = r.meshes.collision.model_copy(
            update={k: getattr(link.collision, k) for k in link.collision.model_fields_set})
    if strategy is not None:
        made_from = visuals
        if isinstance(link.collision, Collision) and link.collision.source is not None:
            made_from = []
            for i, g in _indexed(link.collision.source):
                geom = cx.make_geom(g, lp + ("collision", "source") + i, "error", "collision")
                if geom is not None:
                    made_from.append(_display_only(geom, cx.base_dir))
        collisions = _proxies(made_from, strategy, r.meshes.repair, cx.base_dir)
        for fmt in ("urdf", "sdf", "mjcf"):
            if getattr(strategy, fmt) is not None:
                format_collisions.append((fmt, tuple(_proxies(made_from, getattr(strategy, fmt),
                                                              r.meshes.repair, cx.base_dir))))
    elif link.collision == "visual":
        collisions = [replace(v, material=None) for v in visuals]
    elif link.collision != "none":
        for i, g in _indexed(link.collision):
            if g.material is not None:
                cx.report(lp + ("collision",) + i + ("material",), "collision geometry has no material")
            geom = cx.make_geom(g, lp + ("collision",) + i, policy, "collision")
            if geom is not None:
                collisions.append(geom)
            else:
                unusable.add("collision")
    return collisions, format_collisions


def _link_inertial(cx: _Context, lp: tuple, link, visuals, collisions, unusable: set[str]) -> InertialSpec:
    """How the link's inertial is obtained, with the inertia policy applied (the recipe's
    ``inertia_policy``, or the link's ``inertial.policy``)."""
    r, ispec = cx.r, link.inertial
    spec = InertialSpec("none") if ispec == "none" else _inertial_spec(ispec, r.density)
    source = visuals if spec.source == "visual" else collisions
    asked = ispec.policy if ispec not in (None, "none") else None
    use = asked or r.inertia_policy
    if use in ("recompute", "estimate") and spec.mode in ("explicit", "mass"):
        if source:
            spec = InertialSpec("mass" if use == "recompute" else "estimate", mass=spec.mass, source=spec.source)
        elif asked and spec.source not in unusable:
            cx.report(lp + ("inertial", "policy"), f"'{use}' needs the link's {spec.source} geometry, and the "
                                                   "link has none (give the inertia with 'policy: repair')")
            spec = InertialSpec("none")
        else:
            use = "repair"  # recipe-wide: the given tensor is all there is
    if spec.mode in ("density", "mass") and not source:
        if ispec is None or spec.source in unusable:
            spec = InertialSpec("none")
        else:
            cx.report(lp + ("inertial",), f"computing the inertial needs {spec.source} geometry, and the link has none")
    if spec.mode == "explicit":
        if use == "repair":
            fixed = inertia_policy.repair(spec.explicit.mass, spec.explicit.tensor(), spec.explicit.mass)
            if fixed.changes:
                spec = replace(spec, explicit=Inertial.from_tensor(fixed.mass, spec.explicit.com, fixed.inertia))
        else:
            cx.problems.extend(_check_explicit(spec.explicit, cx.marks, lp + ("inertial",)))
    return spec


def _drawn_only(spec: InertialSpec, visuals, collisions, format_collisions, base_dir: str):
    """Meshes no inertial is computed from may be open: they are only drawn and collided (an
    estimate only needs their hull).  Proxies follow their visual mesh's new key (they read its
    facts for recentering)."""
    computed = spec.mode in ("density", "mass")
    old = [g.shape.mesh for g in visuals]
    visuals = [g if computed and spec.source == "visual" else _display_only(g, base_dir) for g in visuals]
    collisions = [g if computed and spec.source == "collision" else _display_only(g, base_dir)
                  for g in collisions]
    renamed = {m.key: g.shape.mesh for m, g in zip(old, visuals) if m is not None}

    def follow(g: Geom) -> Geom:
        if g.shape.kind != "proxy":
            return g
        return replace(g, shape=replace(g.shape, mesh=renamed.get(g.shape.mesh.key, g.shape.mesh)))

    collisions = [follow(g) for g in collisions]
    format_collisions = [(f, tuple(follow(g) for g in gs)) for f, gs in format_collisions]
    return visuals, collisions, format_collisions


def _joint(cx: _Context, name: str, j, link_names: list[str]) -> Joint:
    """One recipe joint, its ends, limit and mimic checked."""
    jp = ("joints", name)
    for end in ("parent", "child"):
        value = getattr(j, end)
        if value not in cx.r.links:
            cx.report(jp + (end,), unknown_name("link", value, link_names))
    if j.parent == j.child:
        cx.report(jp + ("child",), f"a joint cannot connect link '{j.child}' to itself")
    axis = np.asarray(j.axis, dtype=float)
    norm = float(np.linalg.norm(axis))
    axis = _t(axis / norm) if norm > 0 else (1.0, 0.0, 0.0)
    limit = None
    if j.limit is not None:
        limit = Limit(j.limit.lower, j.limit.upper, j.limit.effort, j.limit.velocity)
        if j.type in ("continuous",):
            limit = Limit(None, None, j.limit.effort, j.limit.velocity)
            if j.limit.lower is not None or j.limit.upper is not None:
                cx.report(jp + ("limit",), "a continuous joint has no lower or upper limit (use revolute)")
        if j.type in ("fixed", "floating", "planar"):
            cx.report(jp + ("limit",), f"a {j.type} joint takes no limit")
    dyn = Dynamics(j.dynamics.damping, j.dynamics.friction, j.dynamics.armature) if j.dynamics else None
    mimic = _mimic(cx, jp, name, j) if j.mimic is not None else None
    return Joint(name, j.type, j.parent, j.child, Pose(_t(j.origin.xyz), _t(j.origin.rpy)), axis, limit, dyn, mimic)


def _mimic(cx: _Context, jp: tuple, name: str, j) -> Mimic:
    joints = cx.r.joints
    if j.mimic.joint not in joints:
        cx.report(jp + ("mimic", "joint"), unknown_name("joint", j.mimic.joint, list(joints)))
    elif j.mimic.joint == name:
        cx.report(jp + ("mimic", "joint"), "a joint cannot mimic itself")
    elif joints[j.mimic.joint].type in ("fixed", "floating", "planar"):
        cx.report(jp + ("mimic", "joint"),
                  f"joint '{j.mimic.joint}' is {joints[j.mimic.joint].type} and cannot be mimicked")
    if j.type not in ("revolute", "continuous", "prismatic"):
        cx.report(jp + ("mimic",), f"a {j.type} joint cannot mimic another joint")
    return Mimic(j.mimic.joint, j.mimic.multiplier, j.mimic.offset)


def _worlds(cx: _Context) -> list[World]:
    worlds = []
    for name, w in cx.r.worlds.items():
        if (why := cx.reads.refusal(w.map)) is not None:
            cx.report(("worlds", name, "map"), f"map file '{_show(w.map)}' {why}")
        elif not os.path.isfile(w.map):
            cx.report(("worlds", name, "map"), f"map file '{_show(w.map)}' does not exist")
        spawn = Pose(_t(w.spawn.xyz), _t(w.spawn.rpy)) if w.spawn is not None else None
        worlds.append(World(name, w.map, float(w.height), w.unknown_as_wall, spawn))
    return worlds


def _ros_and_gazebo(cx: _Context, ros: str | None) -> tuple[str, str]:
    """(ros, gazebo): the override or the recipe's ROS, and the Gazebo it implies unless given."""
    ros = ros or cx.r.ros
    gazebo = cx.r.gazebo or ("classic" if ros == "ros1" else "sim")
    if ros == "ros1" and gazebo == "sim":
        cx.report(("gazebo",), "ROS 1 has no Gazebo Sim plugins (gz_ros2_control, ros_gz): "
                               "use gazebo: classic, or ros: ros2")
    return ros, gazebo


def _metadata(md) -> Metadata:
    authors = tuple(Author(a.name, a.email) for a in md.authors)
    maintainers = tuple(Author(m.name, m.email) for m in md.maintainers) or tuple(a for a in authors if a.email)
    urls = tuple((k, v) for k, v in md.urls.model_dump().items() if v)
    return Metadata(md.version, md.description, authors, md.license, maintainers, urls, tuple(md.ledger))


OPTICAL = (-math.pi / 2, 0.0, -math.pi / 2)


def _sensors(cx: _Context):
    """Sensor frames (links + fixed joints) and Sensor records; presets expanded."""
    r, base_dir = cx.r, cx.base_dir
    links: list[Link] = []
    joints: list[Joint] = []
    sensors: list[Sensor] = []
    for name, s in r.sensors.items():
        sp = ("sensors", name)
        if s.parent not in r.links:
            cx.report(sp + ("parent",), unknown_name("link", s.parent, list(r.links)))
            continue
        origin = Pose(_t(s.origin.xyz), _t(s.origin.rpy))
        topic = s.topic or name
        if s.type == "contact":
            sensors.append(Sensor(name, "contact", s.parent, float(s.update_rate), topic, {}))
            continue
        if s.type == "d435":
            frames, fjoints, fsensors = presets.d435_frames(name)
            (mesh, vxyz, vrpy), (box, bxyz) = presets.d435_body()
            screw = frames[0][0]
            links.append(Link(screw))
            joints.append(Joint(f"{name}_joint", "fixed", s.parent, screw, origin))
            for lname, kind in frames[1:]:
                if kind == "frame":
                    links.append(Link(lname))
                    continue
                key = f"d435-{_h(_ident(mesh, base_dir))}"
                cx.sources.setdefault(mesh, "d435.dae")
                visual = Geom(Shape("mesh", mesh=MeshRef(mesh, (1.0, 1.0, 1.0), "d435.dae", key, "visual-only")),
                              Pose(vxyz, vrpy))
                collision = Geom(Shape("box", size=box), Pose(bxyz))
                links.append(Link(lname, (visual,), (collision,),
                                  InertialSpec("mass", mass=presets.D435["mass"], source="collision")))
            for jname, parent, child, xyz, rpy in fjoints:
                joints.append(Joint(jname, "fixed", parent, child, Pose(tuple(xyz), tuple(rpy))))
            given = {k: getattr(s.camera, k) for k in s.camera.model_fields_set} if s.camera else {}
            for sname, stype, link, optical, hfov in fsensors:
                params = {**_defaults("camera"), "near": 0.1, "far": 10.0, "hfov": hfov, **given}
                sensors.append(Sensor(sname, stype, link, float(s.update_rate), f"{topic}/{sname[len(name) + 1:]}",
                                      params, optical))
            continue
        frame = s.frame or f"{name}_link"
        visuals, collisions, spec = (), (), InertialSpec("none")
        if s.body is not None:
            geoms = []
            for i, g in _indexed(s.body.visual):
                geom = cx.make_geom(g, sp + ("body", "visual") + i, r.open_mesh)
                if geom is not None:
                    geoms.append(geom)
            visuals = tuple(geoms)
            collisions = tuple(replace(g, material=None) for g in geoms)
            spec = InertialSpec("mass", mass=float(s.body.mass))
        links.append(Link(frame, visuals, collisions, spec))
        joints.append(Joint(f"{frame}_joint", "fixed", s.parent, frame, origin))
        given = getattr(s, "camera" if s.type in ("camera", "depth") else s.type)
        params = given.model_dump() if given is not None else _defaults(s.type)
        optical = None
        if s.type in ("camera", "depth"):
            optical = f"{name}_optical_frame"
            links.append(Link(optical))
            joints.append(Joint(f"{optical}_joint", "fixed", frame, optical, Pose((0.0, 0.0, 0.0), OPTICAL)))
        sensors.append(Sensor(name, s.type, frame, float(s.update_rate), topic, params, optical))
    return links, joints, sensors


def _defaults(kind: str) -> dict:
    model = {"camera": schema.CameraParams, "depth": schema.CameraParams, "lidar": schema.LidarParams,
             "sonar": schema.SonarParams, "imu": schema.ImuParams}[kind]
    return model().model_dump()


def _strategy(model, repair: bool) -> Strategy:
    dec = model.decimate
    dec = (("faces", dec.faces) if dec.faces is not None else ("ratio", dec.ratio)) if dec else None
    return Strategy(model.strategy, model.max_vertices, dec, tuple(sorted(model.coacd.model_dump().items())), repair)


def _proxies(visuals: list[Geom], model, repair: bool, base_dir: str) -> list[Geom]:
    """Collision geometry made from the visual geometry by a strategy (mesh parts become proxies
    that the collision tasks turn into pieces; primitives stay as they are)."""
    if model.strategy == "none":
        return []
    strategy = _strategy(model, repair)
    out = []
    for g in visuals:
        m = g.shape.mesh
        if m is None:
            out.append(replace(g, material=None))
            continue
        ident = _h(repr((_ident(m.source, base_dir), m.scale, strategy)))
        key = f"proxy-{os.path.splitext(os.path.basename(m.source))[0]}-{ident}"
        out.append(replace(g, material=None, shape=Shape("proxy", mesh=m, strategy=strategy, proxy_key=key)))
    return out


def _share_mesh_tasks(links: list[Link]) -> list[Link]:
    """A display-only mesh whose file and scale an inertial also uses shares that (stricter)
    mesh task instead of a second one."""
    strict = {}
    for link in links:
        for g in link.visuals + link.collisions:
            m = g.shape.mesh
            if m is not None and m.open_mesh != "visual-only" and not m.processed:
                strict.setdefault((m.source, m.scale), m)

    def share(g: Geom) -> Geom:
        m = g.shape.mesh
        if m is None or m.open_mesh != "visual-only" or (m.source, m.scale) not in strict or m.processed:
            return g
        return replace(g, shape=replace(g.shape, mesh=strict[(m.source, m.scale)]))

    return [replace(link, visuals=tuple(map(share, link.visuals)), collisions=tuple(map(share, link.collisions)),
                    format_collisions=tuple((f, tuple(map(share, gs))) for f, gs in link.format_collisions))
            for link in links]


def _display_only(geom: Geom, base_dir: str) -> Geom:
    m = geom.shape.mesh
    if m is None or m.open_mesh == "visual-only" or geom.shape.kind == "proxy":
        return geom
    ident = _h(repr((_ident(m.source, base_dir), m.scale, "visual-only", m.decimate)))
    key = f"{os.path.splitext(os.path.basename(m.source))[0]}-{ident}"
    return replace(geom, shape=replace(geom.shape, mesh=replace(m, open_mesh="visual-only", key=key)))


def _indexed(value):
    if value is None:
        return []
    if isinstance(value, list):
        return [((i,), g) for i, g in enumerate(value)]
    return [((), value)]


def _geoms(value):
    if value is None or isinstance(value, (str, Collision)):
        return []
    return value if isinstance(value, list) else [value]


def _show(path: str) -> str:
    if "\0" in path:  # display_path cannot resolve it; show the escape, not the byte
        return repr(path)[1:-1]
    return display_path(path)


def _inertial_spec(spec, default_density: float) -> InertialSpec:
    if spec is None:
        return InertialSpec("density", density=default_density)
    if spec.inertia is not None:
        t = spec.inertia
        com = _t(spec.com) if spec.com is not None else (0.0, 0.0, 0.0)
        explicit = Inertial(float(spec.mass), com, (t.ixx, t.ixy, t.ixz, t.iyy, t.iyz, t.izz))
        return InertialSpec("explicit", mass=float(spec.mass), source=spec.source, explicit=explicit)
    if spec.mass is not None:
        return InertialSpec("mass", mass=float(spec.mass), source=spec.source)
    return InertialSpec("density", density=float(spec.density or default_density), source=spec.source)


FIXES = "'policy: repair', 'recompute' or 'estimate' gives the link a physical one"
"""What a build error on an explicit tensor suggests (the recipe's ``inertial.policy``)."""


def _check_explicit(inertial: Inertial, marks, path) -> list[Problem]:
    out = []
    I = inertial.tensor()
    eig = np.linalg.eigvalsh(I)
    if not np.all(np.isfinite(I)):
        out.append(marks.problem(path + ("inertia",), "inertia must be finite"))
    elif eig.min() <= 0:
        out.append(marks.problem(path + ("inertia",), "inertia is not positive definite (principal moments "
                                 f"{', '.join(f'{e:.6g}' for e in eig)}; no real body has them; {FIXES})"))
    else:
        a, b, c = eig
        if a + b < c * (1 - 1e-9):
            out.append(marks.problem(path + ("inertia",),
                                     f"principal moments {a:.6g}, {b:.6g}, {c:.6g} violate the triangle inequality "
                                     f"(no real body has them; {FIXES})"))
    return out


def _check_tree(link_names: list[str], joints: list[Joint], marks) -> list[Problem]:
    problems: list[Problem] = []
    if not link_names:
        return [marks.problem(("links",), "no link: a robot needs at least one")]
    known = set(link_names)
    parent_of: dict[str, str] = {}
    for j in joints:
        if j.child in parent_of and j.child in known:
            problems.append(marks.problem(("joints", j.name, "child"),
                                          f"link '{j.child}' already has a parent (joint '{parent_of[j.child]}'); "
                                          "a link has at most one"))
        else:
            parent_of.setdefault(j.child, j.name)
    roots = [n for n in link_names if n not in parent_of]
    dangling = any(j.parent not in known or j.child not in known for j in joints)
    if len(roots) > 1 and not dangling:  # a joint naming a missing link is reported already
        problems.append(marks.problem(("links",), f"the links form {len(roots)} separate trees with roots "
                                      f"{', '.join(repr(n) for n in roots)}; connect them with joints so one root remains"))
    # cycles: follow parents from every link
    by_child = {j.child: j for j in joints if j.child in known and j.parent in known}
    reported: set[frozenset] = set()
    for start in link_names:
        seen: list[str] = []
        node = start
        while node in by_child and node not in seen:
            seen.append(node)
            node = by_child[node].parent
        if node in seen:
            cycle = seen[seen.index(node):]
            key = frozenset(cycle)
            if key not in reported:
                reported.add(key)
                names = sorted(by_child[n].name for n in cycle)
                problems.append(marks.problem(("joints", names[0]),
                                              f"joints {', '.join(repr(n) for n in names)} form a cycle"))
    if not roots and not reported and link_names:
        problems.append(marks.problem(("links",), "every link is some joint's child: there is no root link"))
    return problems


# ---------------------------------------------------------------- mesh-dependent values


def geom_mass_props(geom: Geom, facts: dict) -> tuple[float, np.ndarray, np.ndarray]:
    """(volume, com, inertia at unit density) of a geometry in its link frame."""
    s = geom.shape
    if s.kind == "box":
        p = massprops.box_props(s.size)
    elif s.kind == "cylinder":
        p = massprops.cylinder_props(s.radius, s.length)
    elif s.kind == "sphere":
        p = massprops.sphere_props(s.radius)
    else:
        f = facts[s.mesh.key]
        p = massprops.MassProps(f["volume"], np.asarray(f["com"]), np.asarray(f["inertia"]))
    T = geom.pose.matrix()
    R = T[:3, :3]
    return p.volume, R @ p.com + T[:3, 3], R @ p.inertia @ R.T


def recenter_offset(geom: Geom, facts: dict) -> tuple[float, float, float]:
    if geom.shape.kind != "mesh" or geom.recenter == "none":
        return (0.0, 0.0, 0.0)
    f = facts[geom.shape.mesh.key]
    c = np.asarray(f["com"]) if geom.recenter == "com" else 0.5 * (np.asarray(f["bbox_min"]) + np.asarray(f["bbox_max"]))
    return tuple(float(-v) + 0.0 for v in c)


def compute_inertial(link: Link, facts: dict) -> Inertial | None:
    """The link's inertial from its spec and the (recentered) source geometry."""
    spec = link.inertial_spec
    if spec.mode == "explicit":
        return spec.explicit
    if spec.mode == "none":
        return None
    if spec.mode == "estimate":
        return _estimate(link, facts)
    parts = [geom_mass_props(g, facts) for g in link.source_geoms()]
    volume = sum(v for v, _, _ in parts)
    density = spec.density if spec.mode == "density" else spec.mass / volume
    mass, com, I = combine([(v * density, c, Ic * density) for v, c, Ic in parts])
    return Inertial.from_tensor(mass, _snap(com, _size(link, facts)), _snap(I, float(np.abs(I).max())))


def _estimate(link: Link, facts: dict) -> Inertial:
    """The link's mass as its bounding primitive (robotkit.model.massprops.bounding_primitive) of
    its source geometry, in the link frame; a link of one primitive is its own.  A flat or thin
    primitive's tensor (a plate's, a rod's) gets the repair's floor."""
    geoms = link.source_geoms()
    s = geoms[0].shape
    if len(geoms) == 1 and s.kind in ("box", "cylinder", "sphere"):
        size = {"box": s.size, "cylinder": (s.radius, s.length), "sphere": (s.radius,)}[s.kind]
        bounds = Bounding(s.kind, tuple(size), geoms[0].pose.matrix())
    else:
        bounds = bounding_primitive(np.vstack([_points(g, facts) for g in geoms]))
    mass = link.inertial_spec.mass
    com, I = bounds.inertia(mass)
    fixed = inertia_policy.repair(mass, I, mass)
    return Inertial.from_tensor(mass, _snap(com, _size(link, facts)), _snap(fixed.inertia, float(np.abs(I).max())))


def _points(geom: Geom, facts: dict) -> np.ndarray:
    """Points whose hull encloses a geometry, in its link frame: a mesh's hull vertices, a box's
    corners, a cylinder's and a sphere's circumscribed polyhedra (64 sections; an icosphere of
    642 vertices), so an enclosure of them encloses the geometry."""
    import trimesh  # late: 0.8 s to import, and only an estimate of a primitive's mass needs it

    s = geom.shape
    if s.kind == "box":
        P = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * 0.5 * np.asarray(s.size)
    elif s.kind == "cylinder":
        n = 64
        P = trimesh.creation.cylinder(radius=s.radius / math.cos(math.pi / n), height=s.length, sections=n).vertices
    elif s.kind == "sphere":
        ico = trimesh.creation.icosphere(subdivisions=3)
        inner = float(np.min(np.abs(np.einsum("ij,ij->i", ico.face_normals, ico.triangles_center))))
        P = ico.vertices * (s.radius / inner)
    else:  # a mesh, or a collision proxy made from one
        P = np.asarray(facts[s.mesh.key]["hull"], dtype=float)
    T = geom.pose.matrix()
    return P @ T[:3, :3].T + T[:3, 3]


def _snap(values, scale: float, rel: float = 1e-12):
    """Zero out float round-off (below ``rel`` of the quantity's scale), e.g. products of
    inertia of a symmetric part that come out as 1e-18 instead of 0."""
    values = np.array(values, dtype=float)
    values[np.abs(values) < rel * scale] = 0.0
    return values


def _size(link: Link, facts: dict) -> float:
    sizes = [1e-3]
    for g in link.source_geoms():
        s = g.shape
        if s.kind == "mesh":
            f = facts[s.mesh.key]
            sizes.append(float(np.max(np.abs(f["bbox_max"] + f["bbox_min"]))))
        sizes.append(float(np.max(np.abs(g.pose.xyz))))
    return max(sizes)


def finalize(robot: Robot, facts: dict, inertials: dict | None = None) -> Robot:
    """Fill recentering offsets and inertials; ``inertials`` (by link) wins when given."""
    links = []
    for link in robot.links:
        link = _with_offsets(link, facts)
        if inertials is not None and link.name in inertials:
            inertial = inertials[link.name]
        else:
            inertial = compute_inertial(link, facts)
        links.append(replace(link, inertial=_mujoco_ready(inertial)))
    return replace(robot, links=tuple(links))


def _mujoco_ready(inertial: Inertial | None) -> Inertial | None:
    """The inertial with a tensor MuJoCo accepts as printed, when only rounding stands in the way
    (inertia_policy.mujoco_ready), so that every format states the same numbers; as it is
    otherwise (Robot.consumer_problems refuses the MJCF for it)."""
    if inertial is None or not inertial.mass > 0:
        return inertial
    tensor = inertial.tensor()
    ready = inertia_policy.mujoco_ready(tensor)
    if ready is None or ready is tensor:
        return inertial
    return Inertial.from_tensor(inertial.mass, inertial.com, ready)


def inertial_to_json(inertial: Inertial | None):
    if inertial is None:
        return None
    return {"mass": inertial.mass, "com": list(inertial.com), "inertia": list(inertial.inertia)}


def inertial_from_json(data) -> Inertial | None:
    if data is None:
        return None
    return Inertial(data["mass"], tuple(data["com"]), tuple(data["inertia"]))


__all__ = ["resolve", "finalize", "compute_inertial"]


def finalize_link_inertial(link: Link, facts: dict) -> Inertial | None:
    """One link's inertial, with recentering offsets applied to its source geometry first."""
    def fix(geoms):
        return tuple(replace(g, offset=recenter_offset(g, facts)) for g in geoms)

    if link.inertial_spec.source == "collision":
        link = replace(link, collisions=fix(link.collisions))
    else:
        link = replace(link, visuals=fix(link.visuals))
    return compute_inertial(link, facts)


def _with_offsets(link: Link, facts: dict) -> Link:
    def fix(geoms):
        return tuple(replace(g, offset=recenter_offset(g, facts)) for g in geoms)

    def expand(geoms):
        return tuple(piece for g in fix(geoms) for piece in _pieces(g, facts))

    return replace(link, visuals=fix(link.visuals), collisions=expand(link.collisions),
                   format_collisions=tuple((f, expand(gs)) for f, gs in link.format_collisions))


def _pieces(geom: Geom, facts: dict) -> list[Geom]:
    """A collision proxy as the pieces its collision task made (meshes or fitted primitives)."""
    if geom.shape.kind != "proxy":
        return [geom]
    if geom.shape.proxy_key not in facts:  # a task that reads no collision facts
        return [geom]
    pose = geom.pose
    out = []
    for p in facts[geom.shape.proxy_key]["pieces"]:
        if p["kind"] == "mesh":
            folder, name = p["file"].split("/", 1)
            ref = MeshRef(geom.shape.mesh.source, (1.0, 1.0, 1.0), name, geom.shape.proxy_key, "visual-only", folder)
            out.append(Geom(Shape("mesh", mesh=ref), pose))
            continue
        T = pose.matrix() @ Pose(tuple(p["xyz"]), tuple(p["rpy"])).matrix()
        piece_pose = Pose(tuple(float(v) for v in T[:3, 3]), matrix_rpy(T[:3, :3]))
        if p["kind"] == "box":
            shape = Shape("box", size=tuple(p["size"]))
        elif p["kind"] == "sphere":
            shape = Shape("sphere", radius=p["radius"])
        else:  # cylinder, capsule
            shape = Shape(p["kind"], radius=p["radius"], length=p["length"])
        out.append(Geom(shape, piece_pose))
    return out
