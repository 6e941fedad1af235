"""Physics lints: is the description physically plausible, not just parseable?

Every rule reads a neutral :class:`LinkFacts` view (mass, centre of mass, inertia about it
in link axes, and the link's geometry measured from its primitives and mesh files), so the
same rules run on robotkit's own builds and on any URDF a user already has.  Each finding
names the link or joint and says how to fix it.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robotkit import urdfxml
from robotkit.check.findings import Finding
from robotkit.check.kinematics import NEGLIGIBLE
from robotkit.errors import Problem, RobotkitError
from robotkit.geometry import rpy_matrix
from robotkit.mesh.inertia import closed_and_wound, density_volume, solid_as_written  # noqa: F401 (tests read closed_and_wound here)
from robotkit.mesh.io import load_mesh
from robotkit.model import inertia_policy
from robotkit.model.inertia_policy import equivalent_box
from robotkit.model import massprops as mi
from robotkit.model.plausible import PART_SIZE_RANGE
from robotkit.model.rigidbody import WELDED_HINT, Part, RigidBody, implied_density, rigid_bodies

# thresholds (documented in docs/checks.md)
MIN_MASS = 1e-6  # kg: sdformat drops lighter links (sdformat #199)
FACE_BUDGET = 200_000  # visual faces per link before rendering rates suffer
COLLISION_VOLUME_RANGE = (0.5, 2.0)  # collision / visual volume
MASS_TOLERANCE = 0.10  # declared total mass vs computed
MARKER = 1e-3  # m: geometry no larger marks a frame (an IMU's 1 mm box) and says nothing of the part


@dataclass
class GeomFacts:
    role: str  # visual | collision
    kind: str  # mesh | box | cylinder | sphere
    name: str  # file name or primitive
    points: np.ndarray  # (n, 3) representative points in the link frame (vertices or box corners)
    volume: float | None  # closed volume in m^3 (None: open mesh or unknown)
    extent: float  # largest size of the part in metres
    faces: int = 0
    com: np.ndarray | None = None  # centroid of the volume, link frame (closed geometry only)
    inertia: np.ndarray | None = None  # unit-density inertia about ``com``, link axes


@dataclass
class LinkFacts:
    name: str
    mass: float | None = None
    com: np.ndarray | None = None
    inertia: np.ndarray | None = None  # about com, link axes
    geoms: list[GeomFacts] = field(default_factory=list)
    unread: set[str] = field(default_factory=set)  # roles with a shape that could not be read (PyBullet's capsule)
    zero_inertial: bool = False  # an explicit <inertial> of mass 0 and no inertia (read as a frame)

    def role(self, role: str) -> list[GeomFacts]:
        return [g for g in self.geoms if g.role == role]

    def shape(self, role: str) -> list[GeomFacts]:
        """The role's geometry when it shows the part: all of it read, and larger than a marker."""
        geoms = self.role(role)
        if role in self.unread or not geoms or max(float(np.ptp(g.points, axis=0).max()) for g in geoms) <= MARKER:
            return []
        return geoms


@dataclass
class JointFacts:
    name: str
    type: str
    lower: float | None = None
    upper: float | None = None
    effort: float | None = None
    velocity: float | None = None
    mimic: str | None = None
    parent: str | None = None
    child: str | None = None
    driven_by: str | None = None  # what drives it: "transmission 'T'" or "ros2_control 'R'"; None: passive


# ---------------------------------------------------------------- reading a URDF


def _floats(text: str | None, n: int, default: float = 0.0) -> list[float]:
    if not text:
        return [default] * n
    return [float(v) for v in text.split()]


def _origin(el) -> np.ndarray:
    T = np.eye(4)
    o = el.find("origin") if el is not None else None
    if o is not None:
        T[:3, :3] = rpy_matrix(_floats(o.get("rpy"), 3))
        T[:3, 3] = _floats(o.get("xyz"), 3)
    return T


def resolve_uri(uri: str, base: Path, package_paths: dict[str, str]) -> Path | None:
    if uri.startswith("package://") or uri.startswith("model://"):
        pkg, _, rest = uri.split("://", 1)[1].lstrip("/").partition("/")
        if pkg in package_paths:
            return Path(package_paths[pkg]) / rest
        for parent in [base, *base.parents][:4]:  # the URDF inside its own package (pkg/urdf/x.urdf)
            if parent.name == pkg:
                return parent / rest
        return None
    if uri.startswith("file://"):
        return Path(uri[7:])
    return base / uri


def _box_points(size) -> np.ndarray:
    s = np.asarray(size, dtype=float) / 2
    return np.array([[x, y, z] for x in (-s[0], s[0]) for y in (-s[1], s[1]) for z in (-s[2], s[2])])


def _geom_facts(el, role: str, base: Path, package_paths: dict[str, str], subject: str,
                problems: list[Finding], cache: dict) -> GeomFacts | None:
    g = el.find("geometry")
    if g is None or len(g) == 0:
        return None
    shape = g[0]
    T = _origin(el)
    kind = shape.tag
    props = None
    if kind == "box":
        size = _floats(shape.get("size"), 3)
        pts, extent, name, faces, props = _box_points(size), max(size), "box", 12, mi.box_props(size)
    elif kind == "cylinder":
        r, h = float(shape.get("radius")), float(shape.get("length"))
        angles = np.linspace(0, 2 * np.pi, 16, endpoint=False)
        ring = np.stack([r * np.cos(angles), r * np.sin(angles)], axis=1)
        pts = np.vstack([np.column_stack([ring, np.full(16, z)]) for z in (-h / 2, h / 2)])
        extent, name, faces, props = max(2 * r, h), "cylinder", 0, mi.cylinder_props(r, h)
    elif kind == "sphere":
        r = float(shape.get("radius"))
        pts, extent, name, faces = _box_points([2 * r] * 3) * 0.577, 2 * r, "sphere", 0
        props = mi.sphere_props(r)
    elif kind == "mesh":
        uri = shape.get("filename", "")
        if uri.startswith("package:///"):  # read by robotkit (and the consumers here) as package://PKG/
            problems.append(Finding("error", "mesh-uri", subject,
                                    f"{role} mesh '{uri}' names no package ('package:///' leaves the package name "
                                    "empty): ROS's resource retriever, RViz, Drake and PyBullet cannot find it",
                                    "write package://PKG/...; robotkit import reads it so"))
        path = resolve_uri(uri, base, package_paths)
        name = os.path.basename(uri)
        if path is None or not path.is_file():
            problems.append(Finding("warning", "mesh-file", subject,
                                    f"{role} mesh '{uri}' cannot be found, so its geometry is not checked",
                                    "give --package-path PKG=DIR"))
            return None
        scale = np.asarray(_floats(shape.get("scale"), 3, 1.0))
        key = (str(path), tuple(scale))
        if key not in cache:
            cache[key] = mesh_facts(path, scale)
        mesh_pts, props, faces = cache[key]
        if mesh_pts is None:
            problems.append(Finding("warning", "mesh-file", subject, f"{role} mesh '{name}' cannot be read"))
            return None
        pts = mesh_pts
        extent = float((pts.max(axis=0) - pts.min(axis=0)).max())
    else:
        return None
    R, t = T[:3, :3], T[:3, 3]
    pts = pts @ R.T + t
    if props is None:
        return GeomFacts(role, kind, name, pts, None, extent, faces)
    return GeomFacts(role, kind, name, pts, props.volume, extent, faces, R @ props.com + t, R @ props.inertia @ R.T)


def mesh_facts(path: Path, scale: np.ndarray):
    """(points, mass properties if a closed volume, faces) of a mesh file; (None, None, 0) if unreadable.

    The points are its vertices: the lints use only their extremes along directions (which the
    convex hull's vertices share).  Binary STL and plain OBJ (what a build writes) are read here
    with numpy, as trimesh would read them (:func:`plain_mesh`); anything else through trimesh."""
    plain = plain_mesh(path) if (scale == 1.0).all() else None
    if plain is not None:
        V, F = plain
    else:
        try:
            mesh = load_mesh(str(path), tuple(scale))
        except (RobotkitError, ValueError, OSError):
            return None, None, 0
        V, F = np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)
    return V, solid_as_written(V, F), len(F)


PLAIN_MESH_BYTES = 64 * 2**20
"""Largest mesh file :func:`plain_mesh` reads (larger ones go through trimesh, with its limits)."""


def plain_mesh(path: Path) -> tuple[np.ndarray, np.ndarray] | None:
    """(vertices, faces) of a binary STL or of an OBJ of ``v x y z`` and ``f i j k`` lines only,
    merged as trimesh merges them (vertices equal to 8 decimals, first kept), or None when the
    file is anything else or anything about it is unusual (then trimesh reads it, and says why
    it cannot).  No trimesh import: 0.8 s less on check's main path."""
    ext = path.suffix.lower()
    try:
        size = path.stat().st_size
        if ext not in (".stl", ".obj") or not 0 < size <= PLAIN_MESH_BYTES:
            return None
        data = path.read_bytes()
    except OSError:
        return None
    if ext == ".stl":
        if data[:5].lower() == b"solid" and b"facet" in data[:4096]:
            return None  # ASCII
        count = int.from_bytes(data[80:84], "little") if size >= 84 else 0
        if count == 0 or size != 84 + 50 * count:
            return None
        rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", (3,)), ("v", "<f4", (3, 3)), ("a", "<u2")]),
                            count=count, offset=84)
        V = rec["v"].reshape(-1, 3).astype(np.float64)
        F = np.arange(len(V), dtype=np.int64).reshape(-1, 3)
    else:
        V, F = _plain_obj(data)
        if V is None:
            return None
    if not np.isfinite(V).all() or (len(F) and not (0 <= F.min() and F.max() < len(V))):
        return None
    if not float(np.abs(V).max()) <= 1e4:  # robotkit.mesh.io.MAX_EXTENT: trimesh's path refuses it
        return None
    used = np.unique(F)  # trimesh merges the referenced vertices only; a plain mesh has no others
    if len(used) != len(V):
        return None
    keys = np.round(V * 1e8).astype(np.int64)
    by_key = np.lexsort(keys.T[::-1])  # stable: a group's first row is its first appearance
    k = keys[by_key]
    starts = np.r_[True, (k[1:] != k[:-1]).any(axis=1)]
    inverse = np.empty(len(V), dtype=np.int64)
    inverse[by_key] = np.cumsum(starts) - 1
    first = by_key[starts]
    order = np.argsort(first)  # keep_order: the merged vertices in order of first appearance
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return V[first[order]], rank[inverse][F]


def _plain_obj(data: bytes):
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        return None, None
    v, f = [], []
    for line in text.splitlines():
        head = line[:2]
        if head == "v ":
            v.append(line[2:])
        elif head == "f ":
            f.append(line[2:])
        elif line and not line.startswith(("#", "o ")):
            return None, None  # normals, textures, groups, materials...: trimesh's reading
    try:
        V = np.array(" ".join(v).split(), dtype=np.float64).reshape(-1, 3)
        F = np.array(" ".join(f).split(), dtype=np.int64).reshape(-1, 3) - 1
    except ValueError:  # "f 1/1 2/2 3/3", quads, a short line
        return None, None
    if any(len(line.split()) != 3 for line in f) or any(len(line.split()) != 3 for line in v) or not len(F):
        return None, None
    return V, F


def read_urdf_facts(path: Path, package_paths: dict[str, str] | None = None,
                    text: str | None = None) -> tuple[list[LinkFacts], list[JointFacts], list[Finding]]:
    package_paths = package_paths or {}
    try:
        root = urdfxml.parse_text(text if text is not None else path.read_text(encoding="utf-8")).getroot()
    except urdfxml.MalformedXML as exc:  # in the words of expat, which read it before lxml
        raise RobotkitError(Problem(f"not well-formed XML: {exc.expat or exc}", file=str(path))) from None
    if root.tag != "robot":
        raise RobotkitError(Problem(f"not a URDF (the root element is <{root.tag}>, not <robot>)", file=str(path)))
    problems: list[Finding] = []
    cache: dict = {}
    links = []
    for el in root.findall("link"):
        name = el.get("name")
        subject = f"link '{name}'"
        facts = LinkFacts(name)
        inertial = el.find("inertial")
        if inertial is not None:
            T = _origin(inertial)
            m = inertial.find("mass")
            facts.mass = float(m.get("value")) if m is not None else 0.0
            i = inertial.find("inertia")
            a = {k: float(i.get(k, 0)) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")} if i is not None else {}
            I = np.array([[a.get("ixx", 0), a.get("ixy", 0), a.get("ixz", 0)],
                          [a.get("ixy", 0), a.get("iyy", 0), a.get("iyz", 0)],
                          [a.get("ixz", 0), a.get("iyz", 0), a.get("izz", 0)]])
            R = T[:3, :3]
            facts.com, facts.inertia = T[:3, 3], R @ I @ R.T
            if 0 <= facts.mass < NEGLIGIBLE and not I.any():  # an explicitly massless link (a frame)
                facts.mass = facts.com = facts.inertia = None
                facts.zero_inertial = m is not None and float(m.get("value")) == 0
        for role in ("visual", "collision"):
            for g in el.findall(role):
                gf = _geom_facts(g, role, path.parent, package_paths, subject, problems, cache)
                if gf is not None:
                    facts.geoms.append(gf)
                elif g.find("geometry") is not None and len(g.find("geometry")):
                    facts.unread.add(role)
        links.append(facts)
    joints = []
    for el in root.findall("joint"):
        lim = el.find("limit")
        mimic = el.find("mimic")

        def num(attr):
            return float(lim.get(attr)) if lim is not None and lim.get(attr) is not None else None

        ends = {end: (el.find(end).get("link") if el.find(end) is not None else None) for end in ("parent", "child")}
        joints.append(JointFacts(el.get("name"), el.get("type"), num("lower"), num("upper"), num("effort"),
                                 num("velocity"), mimic.get("joint") if mimic is not None else None,
                                 ends["parent"], ends["child"]))
    drivers = _drivers(root)
    for j in joints:
        j.driven_by = drivers.get(j.name)
    names = {j.name for j in joints}
    for el in root.findall("transmission"):  # the Jackal's name 'front_left_wheel' for 'front_left_wheel_joint'
        for j in el.findall("joint"):
            if j.get("name") not in names:
                problems.append(Finding("error", "transmission", f"transmission '{el.get('name')}'",
                                        f"names joint '{j.get('name')}', which the robot does not have: Drake "
                                        "refuses the URDF and ros_control the transmission",
                                        "name one of the robot's joints; robotkit import leaves it out"))
    return links, joints, problems


def _drivers(root) -> dict[str, str]:
    """Joint -> what drives it: a <transmission> naming it, or a <ros2_control> joint with a
    command interface (one with state interfaces only is read, not driven)."""
    out: dict[str, str] = {}
    for el in root.findall("transmission"):
        for j in el.findall("joint"):
            out.setdefault(j.get("name"), f"transmission '{el.get('name')}'")
    for el in root.findall("ros2_control"):
        for j in el.findall("joint"):
            if j.find("command_interface") is not None:
                out.setdefault(j.get("name"), f"ros2_control '{el.get('name')}'")
    return out


# ---------------------------------------------------------------- the rules


def lint(links: list[LinkFacts], joints: list[JointFacts], declared_mass: float | None = None) -> list[Finding]:
    out: list[Finding] = []
    bodies = rigid_bodies_of(links, joints)
    for link in links:
        out += lint_link(link, bodies.get(link.name))
    out += lint_joints(joints)
    out += lint_massless_moving(links, joints)
    if declared_mass is not None:
        total = sum(l.mass or 0.0 for l in links)
        if abs(total - declared_mass) > MASS_TOLERANCE * declared_mass:
            out.append(Finding("error", "total-mass", "robot",
                               f"the links weigh {total:.4g} kg in total, the declared mass is {declared_mass:.4g} kg "
                               f"({(total / declared_mass - 1) * 100:+.0f}%)",
                               "check densities and which links have inertials; or update measured_mass"))
    return out


def lint_link(link: LinkFacts, body: RigidBody | None = None) -> list[Finding]:
    """The rules on one link; ``body``: the rigid body it is welded to (:func:`rigid_bodies_of`),
    on which its implied density is judged when its own is out of range (None: the link alone)."""
    out: list[Finding] = []
    s = f"link '{link.name}'"

    def add(sev, check, msg, hint=""):
        out.append(Finding(sev, check, s, msg, hint))

    parts = [g for g in link.geoms]
    for g in parts:
        if g.extent > PART_SIZE_RANGE[1]:
            add("error", "part-size", f"{g.role} {g.name} is {g.extent:.4g} m across",
                "a mesh in millimetres used as metres? set units: mm (URDF: scale=\"0.001 0.001 0.001\")")
        elif 0 < g.extent < PART_SIZE_RANGE[0]:
            add("error", "part-size", f"{g.role} {g.name} is {g.extent * 1000:.3g} mm across",
                "a mesh in metres scaled as millimetres? check its units or scale")
        if g.role == "visual" and g.faces > FACE_BUDGET:
            add("warning", "face-budget", f"visual mesh {g.name} has {g.faces} faces (budget {FACE_BUDGET})",
                "decimate it for rendering")
    if link.mass is None:
        return out
    if not math.isfinite(link.mass) or link.mass <= 0:
        add("error", "mass", f"mass is {link.mass!r}", "a body needs a positive mass")
        return out
    if link.mass < MIN_MASS:
        add("warning", "tiny-mass", f"mass {link.mass:.3g} kg is below {MIN_MASS:g} kg",
            "URDF->SDF conversion drops such links with their frames (sdformat #199)")
    I = link.inertia
    if I is None or not np.all(np.isfinite(I)):
        add("error", "inertia", "inertia is not a finite tensor")
        return out
    eig = np.linalg.eigvalsh(0.5 * (I + I.T))
    if inertia_policy.defects(link.mass, I):  # the rules the import's repair follows
        fixed = inertia_policy.repair(link.mass, I, link.mass)
        hint = ("inertia policy 'repair' (robotkit import's default) makes the smallest change: "
                + "; ".join(fixed.changes) + "; 'recompute' or 'estimate' derive it from the link's geometry "
                "(robotkit import --inertia-policy, or inertial.policy in a recipe)")
        if eig.min() <= 0:
            add("error", "inertia", "inertia is not positive definite (principal moments "
                + ", ".join(f"{e:.4g}" for e in eig) + ")", hint)
        else:
            a, b, c = eig
            add("error", "triangle-inequality", f"principal moments {a:.4g}, {b:.4g}, {c:.4g} violate "
                "the triangle inequality (I1 + I2 >= I3): no real body has them", hint)
        return out
    out += _density_check(link, body, s)
    geometry = _geometry_props(link)
    if geometry is not None:
        out += _box_check_geometry(link, geometry, s)
        out += _com_check(link, geometry, s)
    points = _geometry_points(link)
    if points is not None:
        if geometry is None:
            out += _box_check(link, eig, points, s)
        lo, hi = points.min(axis=0), points.max(axis=0)
        margin = 1e-3 * max(float((hi - lo).max()), 1e-9)
        if np.any(link.com < lo - margin) or np.any(link.com > hi + margin):
            add("warning", "com-outside", f"centre of mass {np.round(link.com, 6).tolist()} lies outside the "
                f"link's geometry (box {np.round(lo, 6).tolist()} .. {np.round(hi, 6).tolist()})",
                "an inertial origin in the wrong frame or left out")
    vis, col = _volume(link.shape("visual")), _volume(link.shape("collision"))
    if vis and col and not (COLLISION_VOLUME_RANGE[0] <= col / vis <= COLLISION_VOLUME_RANGE[1]):
        add("warning", "collision-volume", f"collision geometry has {col / vis:.3g}x the visual volume",
            "the collision proxy is far from the visual shape")
    return out


def _density_check(link: LinkFacts, body: RigidBody | None, s: str) -> list[Finding]:
    """The implied-density rule (robotkit.model.rigidbody.implied_density, which the import's
    density warning follows too): an error when the link's density is out of range, a warning when
    the rigid body it is welded to is in range."""
    volume = link_volume(link)
    found = implied_density(link.mass, volume, body)
    if found is None:
        return []
    return [Finding(found.severity, "implied-density", s,
                    f"implied density {found.figure} kg/m^3 (mass {link.mass:.4g} kg, volume {volume:.4g} m^3) is "
                    f"{found.side} {found.bound:g}{found.welded()}", WELDED_HINT if found.body else found.cause)]


def rigid_bodies_of(links: list[LinkFacts], joints: list[JointFacts]) -> dict[str, RigidBody]:
    """The rigid body each link belongs to (robotkit.model.rigidbody.rigid_bodies): the links
    welded to it by fixed joints, with the volumes :func:`link_volume` reads."""
    parts = {link.name: Part(link.mass, link_volume(link),
                             bool(link.unread or link.shape("visual") or link.shape("collision")))
             for link in links}
    return rigid_bodies(parts, [(j.parent, j.child) for j in joints if j.type == "fixed"])


def _volume(geoms: list[GeomFacts]) -> float | None:
    if not geoms or any(g.volume is None for g in geoms):
        return None
    return sum(g.volume for g in geoms)


def link_volume(link: LinkFacts) -> float | None:
    """The volume of the link's closed geometry (visual, else collision), None when open or unknown
    (robotkit.mesh.inertia.density_volume: the rule the import's density warning follows too)."""
    return density_volume([g.volume for g in link.shape("visual")], [g.volume for g in link.shape("collision")])


def _geometry_points(link: LinkFacts) -> np.ndarray | None:
    geoms = link.shape("visual") or link.shape("collision")
    if not geoms:
        return None
    return np.vstack([g.points for g in geoms])


def _geometry_props(link: LinkFacts):
    """(volume, com, unit-density inertia) of the link's closed geometry, or None."""
    geoms = link.shape("visual") or link.shape("collision")
    if not geoms or any(g.inertia is None for g in geoms):
        return None
    volume, com, I = mi.combine([(g.volume, g.com, g.inertia) for g in geoms])
    return volume, com, I


def _box_check_geometry(link: LinkFacts, geometry, s: str) -> list[Finding]:
    """The equivalent inertia box (what Gazebo draws with View > Inertia) of the declared
    inertia against that of the geometry at uniform density with the same mass
    (robotkit.model.inertia_policy.box_fit_geometry: the rule ``robotkit import`` uses too)."""
    volume, _, I_geom = geometry
    fit = inertia_policy.box_fit_geometry(link.mass, link.inertia, volume, I_geom)
    if fit.severity is None:
        return []
    return [Finding(fit.severity, "inertia-box", s,
                    f"the equivalent inertia box ({_sides(fit.declared)} m) is {fit.ratio:.3g}x "
                    f"{'larger' if fit.larger else 'smaller'} than the geometry's at uniform density "
                    f"({_sides(fit.geometry)} m), along {fit.axes}",
                    "the inertia does not fit the part: hand-typed, rotated, or in the wrong units?")]


def _sides(sides) -> str:
    return " x ".join(f"{d:.3g}" for d in sides)


def _com_check(link: LinkFacts, geometry, s: str) -> list[Finding]:
    volume, centroid, I_geom = geometry
    vals, vecs = np.linalg.eigh(I_geom)
    size = equivalent_box(volume, vals * 1.0)  # the geometry's own equivalent box, along its principal axes
    offset = np.abs(vecs.T @ (link.com - centroid))
    rel = offset / np.maximum(size, 1e-12)
    if rel.max() <= 0.1:
        return []
    return [Finding("warning", "com-offset", s,
                    f"centre of mass {np.round(link.com, 6).tolist()} is {float(np.linalg.norm(link.com - centroid)):.4g} m "
                    f"from the geometry's centroid {np.round(centroid, 6).tolist()}",
                    "fine for a part with dense components inside; otherwise an origin left out or in the wrong frame")]


def _box_check(link: LinkFacts, eig, points: np.ndarray, s: str) -> list[Finding]:
    """Without a closed geometry: the equivalent inertia box against the geometry's extent
    along the same principal axes (robotkit.model.inertia_policy.box_fit_extent).  A uniform
    body's box can exceed its extent by up to sqrt(3) (mass at the ends), so only larger boxes
    beyond that are flagged."""
    fit = inertia_policy.box_fit_extent(link.mass, link.com, link.inertia, points)
    if fit.severity is None:
        return []
    return [Finding(fit.severity, "inertia-box", s,
                    f"the equivalent inertia box ({_sides(fit.declared)} m) is {fit.ratio:.3g}x "
                    f"larger than the geometry ({_sides(fit.geometry)} m), along {fit.axes}",
                    "the inertia does not fit the part: hand-typed or in the wrong units?")]


MOVING = ("revolute", "continuous", "prismatic", "planar", "floating")


def lint_massless_moving(links: list[LinkFacts], joints: list[JointFacts]) -> list[Finding]:
    """A link that moves with no mass on it or on the links welded to it: MuJoCo refuses the
    robot and Gazebo drops the link with everything below it."""
    mass = {link.name: (link.mass or 0.0) for link in links}
    given = {link.name for link in links if link.mass is not None}  # a mass <= 0 is the mass rule's
    fixed_below: dict[str, list[str]] = {}
    for j in joints:
        if j.type == "fixed" and j.parent is not None and j.child is not None:
            fixed_below.setdefault(j.parent, []).append(j.child)

    def body_mass(name: str) -> float:
        total, todo, seen = 0.0, [name], set()
        while todo:
            n = todo.pop()
            if n in seen:
                continue
            seen.add(n)
            total += mass.get(n, 0.0)
            todo += fixed_below.get(n, [])
        return total

    out = []
    for j in joints:
        if j.type in MOVING and j.child in mass and j.child not in given and not body_mass(j.child) > 0:
            out.append(Finding("error", "massless-moving", f"link '{j.child}'",
                               f"moves (joint '{j.name}') but has no mass: MuJoCo refuses to load the robot and "
                               "Gazebo drops the link with everything below it",
                               "give it an <inertial>; robotkit import computes one from its geometry"))
    welded = {j.child for j in joints if j.type == "fixed"}
    welded_flagged = set()
    for name in sorted(welded & set(mass)):  # libsdformat weighs a welded link with the links welded below it only
        moves = next((j for j in joints if j.parent == name and j.type in MOVING), None)
        if moves is not None and name not in given and not body_mass(name) > 0:
            welded_flagged.add(name)
            out.append(Finding("error", "massless-moving", f"link '{name}'",
                               f"joint '{moves.name}' moves below it but it has no mass, nor the links welded "
                               "below it: Gazebo's URDF conversion drops everything that moves below it, though "
                               "it is welded to a link with mass",
                               "give it an <inertial>; robotkit import computes one from its geometry"))
    # libsdformat drops a link without mass inside the tree with everything below it, even when
    # it is welded to a link with mass (iCub's l_hip_3, between the hip and the leg)
    flagged = {j.child for j in joints if j.type in MOVING} | welded_flagged
    roots = {j.parent for j in joints} - {j.child for j in joints}

    def carries(name: str, seen: frozenset = frozenset()) -> str | None:
        for j in joints:
            if j.parent == name and j.child not in seen and (
                    j.type in MOVING or mass.get(j.child, 0.0) > 0 or carries(j.child, seen | {name})):
                return j.name
        return None

    zero = {link.name for link in links if link.zero_inertial}
    for j in joints:  # libsdformat lumps the two into a centre of mass of 0 / 0 (Talos's camera frames)
        if j.type == "fixed" and j.child in zero and j.parent in zero:
            out.append(Finding("error", "zero-mass-welded", f"link '{j.child}'",
                               f"has an <inertial> of mass 0 and is welded (joint '{j.name}') to '{j.parent}', "
                               "which has one too: libsdformat lumps them into a centre of mass of 0/0 and Gazebo "
                               "refuses the robot (\"Pose values must be finite\")",
                               "leave the <inertial> out of a frame; robotkit's build writes none"))
    massless_roots = [r for r in roots if not body_mass(r) > 0]  # the whole robot hangs on them: Gazebo reads none
    welded_to_them, todo = set(), massless_roots
    while todo:
        welded_to_them |= set(todo)
        todo = [c for n in todo for c in fixed_below.get(n, []) if c not in welded_to_them]
    for link in links:
        below = None if link.name in flagged | welded_to_them or body_mass(link.name) > 0 else carries(link.name)
        if below:
            out.append(Finding("error", "massless-parent", f"link '{link.name}'",
                               f"has no mass and joint '{below}' below it: Gazebo's URDF conversion drops the "
                               "link with everything below it, even welded to a link with mass",
                               "give it an <inertial>; robotkit import gives it a point mass"))
    return out


def _zero_limits(j: JointFacts, s: str) -> list[Finding]:
    """An effort or velocity limit that is not positive.  A limit of 0 on a joint that nothing
    drives (no transmission, no ros2_control command) is a statement: a passive joint, moved by
    what it carries (the SolidWorks exporter and ROS-Industrial's kinematic files write 0); on a
    driven joint it is an error, as is a negative one anywhere."""
    out = []
    for key, v in (("effort", j.effort), ("velocity", j.velocity)):
        if v is None or v > 0:
            continue
        if v < 0:
            out.append(Finding("error", "joint-limits", s, f"{key} limit {v:g} is not positive"))
        elif j.driven_by is not None:
            out.append(Finding("error", "joint-limits", s, f"{key} limit 0 is not positive, and {j.driven_by} "
                               f"drives it: a driven joint with zero {key} cannot move",
                               f"give it the motor's {key} limit"))
        else:
            out.append(Finding("warning", "passive-joint", s, f"{key} limit 0: nothing drives it (no transmission "
                               "or ros2_control command names it), a passive joint",
                               f"give it the motor's {key} limit if a motor drives it"))
    return out


def lint_joints(joints: list[JointFacts]) -> list[Finding]:
    out = []
    by_name = {j.name: j for j in joints}
    for j in joints:
        s = f"joint '{j.name}'"
        if j.type in ("revolute", "prismatic"):
            if j.lower is not None and j.upper is not None and j.lower >= j.upper:
                out.append(Finding("error", "joint-limits", s, f"lower limit {j.lower:g} is not below upper {j.upper:g}"))
            out += _zero_limits(j, s)
        if j.mimic is not None and j.mimic not in by_name:  # check_urdf accepts it (Alex's hands)
            out.append(Finding("error", "mimic-missing", s, f"mimics joint '{j.mimic}', which the robot does not "
                               "have: Drake refuses the URDF", "name one of the robot's joints; robotkit import "
                               "drops the mimic"))
        seen = [j.name]
        node = j
        while node.mimic is not None and node.mimic in by_name:
            if node.mimic in seen:
                if j.name == min(seen[seen.index(node.mimic):]):
                    out.append(Finding("error", "mimic-loop", s, "mimic joints form a loop: "
                                       + " -> ".join(seen[seen.index(node.mimic):] + [node.mimic])))
                break
            seen.append(node.mimic)
            node = by_name[node.mimic]
    return out
