"""The resolved robot model: plain frozen data in SI units, independent of any format.

Every frame is explicit:

- a joint's ``origin`` is the pose of the child link frame in the parent link frame;
- a geometry's pose in its link frame is ``origin`` composed with a translation
  by ``offset`` (the recentering shift, metres, in the geometry frame);
- an :class:`Inertial` holds the mass, the centre of mass in the link frame and
  the inertia tensor about the centre of mass, expressed in the link axes.

Values that need mesh work (mesh facts, recentering offsets, computed
inertials) are filled in by :func:`robotkit.model.resolve.finalize`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from robotkit.geometry import matrix_rpy, rpy_matrix
from robotkit.model.inertia_policy import MIN_MOMENT, mujoco_ready
from robotkit.model.selfcollision import Matrix, Settings

Vec3 = tuple[float, float, float]

MJCF_MAX_DEPTH = 496  # bodies MuJoCo 4.0's XML reader nests (tinyxml2's element depth), measured


@dataclass(frozen=True)
class Pose:
    xyz: Vec3 = (0.0, 0.0, 0.0)
    rpy: Vec3 = (0.0, 0.0, 0.0)

    def matrix(self) -> np.ndarray:
        T = np.eye(4)
        T[:3, :3] = rpy_matrix(self.rpy)
        T[:3, 3] = self.xyz
        return T

    def then(self, offset: Vec3) -> "Pose":
        """This pose followed by a translation ``offset`` in its own frame."""
        if not any(offset):
            return self
        t = np.asarray(self.xyz) + rpy_matrix(self.rpy) @ np.asarray(offset, dtype=float)
        return Pose(tuple(float(v) for v in t), self.rpy)


@dataclass(frozen=True)
class Strategy:
    """How collision geometry is made from a visual mesh (see the recipe's ``collision``)."""

    kind: str  # mesh | hull | decompose | box | cylinder | sphere | capsule | none
    max_vertices: int | None = None
    decimate: tuple | None = None  # ("faces", n) or ("ratio", r)
    coacd: tuple = ()  # sorted (name, value) pairs
    repair: bool = True

    def params(self) -> dict:
        return {"kind": self.kind, "max_vertices": self.max_vertices,
                "decimate": list(self.decimate) if self.decimate else None,
                "coacd": dict(self.coacd), "repair": self.repair}


@dataclass(frozen=True)
class MeshRef:
    """A mesh file and how its coordinates map to metres."""

    source: str
    """Absolute path of the source file."""
    scale: Vec3
    """Per-axis factor from file units to metres (of the file the outputs reference)."""
    file_name: str
    """Output name under ``meshes/<folder>/``."""
    key: str
    """Unit-of-work key: one mesh task per (file, scale, open-mesh policy)."""
    open_mesh: str = "error"
    folder: str = "visual"
    """``visual``, ``collision``; the output is ``meshes/<folder>/<file_name>``."""
    decimate: tuple | None = None
    """A processed visual: ("faces", n), ("ratio", r) or ("none", 0) (only mirrored); written as a binary STL in metres."""
    repair: bool = False

    @property
    def path(self) -> str:
        """Path below the robot's ``meshes/`` folder."""
        return f"{self.folder}/{self.file_name}"

    @property
    def processed(self) -> bool:
        return self.decimate is not None

    @property
    def out_scale(self) -> Vec3:
        """The scale an output file needs: processed meshes and collision pieces are in metres."""
        return (1.0, 1.0, 1.0) if self.processed or self.folder != "visual" else self.scale


@dataclass(frozen=True)
class Shape:
    kind: str  # mesh | box | cylinder | sphere | capsule | proxy (expanded into pieces by finalize)
    size: Vec3 | None = None  # box
    radius: float | None = None  # cylinder, sphere, capsule
    length: float | None = None  # cylinder, capsule
    mesh: MeshRef | None = None
    strategy: Strategy | None = None  # proxy: made from ``mesh`` by a collision task
    proxy_key: str | None = None


@dataclass(frozen=True)
class Geom:
    shape: Shape
    origin: Pose = Pose()
    offset: Vec3 = (0.0, 0.0, 0.0)
    material: str | None = None
    recenter: str = "none"  # none | bbox | com: how ``offset`` is derived

    @property
    def pose(self) -> Pose:
        return self.origin.then(self.offset)


@dataclass(frozen=True)
class Inertial:
    mass: float
    com: Vec3
    inertia: tuple[float, float, float, float, float, float]
    """ixx, ixy, ixz, iyy, iyz, izz about the centre of mass, link axes."""

    def tensor(self) -> np.ndarray:
        ixx, ixy, ixz, iyy, iyz, izz = self.inertia
        return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])

    @staticmethod
    def from_tensor(mass: float, com, I: np.ndarray) -> "Inertial":
        I = 0.5 * (np.asarray(I, dtype=float) + np.asarray(I, dtype=float).T)
        return Inertial(float(mass), tuple(float(c) for c in com),
                        (float(I[0, 0]), float(I[0, 1]), float(I[0, 2]),
                         float(I[1, 1]), float(I[1, 2]), float(I[2, 2])))


@dataclass(frozen=True)
class InertialSpec:
    """How a link's inertial is obtained (see the recipe's ``inertial``)."""

    mode: str  # density | mass | explicit | none
    density: float | None = None
    mass: float | None = None
    source: str = "visual"
    explicit: Inertial | None = None


@dataclass(frozen=True)
class Contact:
    mu1: float | None = None
    mu2: float | None = None
    kp: float | None = None
    kd: float | None = None


@dataclass(frozen=True)
class Link:
    name: str
    visuals: tuple[Geom, ...] = ()
    collisions: tuple[Geom, ...] = ()
    inertial_spec: InertialSpec = InertialSpec("none")
    inertial: Inertial | None = None
    contact: Contact | None = None
    format_collisions: tuple = ()  # (("mjcf", (Geom, ...)), ...): per-format collision geometry

    def collisions_for(self, fmt: str) -> tuple[Geom, ...]:
        return dict(self.format_collisions).get(fmt, self.collisions)

    def source_geoms(self) -> tuple[Geom, ...]:
        return self.collisions if self.inertial_spec.source == "collision" else self.visuals


@dataclass(frozen=True)
class Limit:
    lower: float | None = None
    upper: float | None = None
    effort: float | None = None
    velocity: float | None = None


@dataclass(frozen=True)
class Dynamics:
    damping: float = 0.0
    friction: float = 0.0
    armature: float = 0.0


@dataclass(frozen=True)
class Mimic:
    joint: str
    multiplier: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True)
class Joint:
    name: str
    type: str
    parent: str
    child: str
    origin: Pose = Pose()
    axis: Vec3 = (1.0, 0.0, 0.0)
    limit: Limit | None = None
    dynamics: Dynamics | None = None
    mimic: Mimic | None = None


@dataclass(frozen=True)
class Material:
    name: str
    rgba: tuple[float, float, float, float]
    gazebo: str | None = None


@dataclass(frozen=True)
class Author:
    name: str
    email: str | None = None


@dataclass(frozen=True)
class Metadata:
    version: str = "1.0"
    description: str = ""
    authors: tuple[Author, ...] = ()
    license: str | None = None
    maintainers: tuple[Author, ...] = ()
    """Given ones, else the authors with an e-mail address; may be empty (the build warns)."""
    urls: tuple[tuple[str, str], ...] = ()
    """(type, address) pairs: website, repository, bugtracker."""
    ledger: tuple[str, ...] = ()
    """What an import could not carry from the original (report.json's ``ledger``)."""


@dataclass(frozen=True)
class Sensor:
    """A sensor sitting at the origin of frame link ``link`` (x forward, z up, as in Gazebo)."""

    name: str
    type: str  # camera | depth | lidar | sonar | imu | contact
    link: str
    update_rate: float
    topic: str
    params: dict = field(default_factory=dict)
    optical_frame: str | None = None  # the ROS optical frame of a camera (z forward, y down)


@dataclass(frozen=True)
class Actuator:
    joint: str
    interface: str  # position | velocity | effort
    p: float = 0.0
    i: float = 0.0
    d: float = 0.0
    auto: bool = False  # gains derived from the robot's inertia (robotkit.model.gains), p and d filled then
    bandwidth: float | None = None  # Hz, with auto: None = chosen by the tuner
    damping_ratio: float = 1.0
    armature: float = 0.0  # the motor's reflected inertia (already inside the joint's dynamics.armature)
    gravcomp: bool = False  # the drive compensates gravity (MJCF actuatorgravcomp), set by the tuner


@dataclass(frozen=True)
class Loop:
    """A closed loop: ``pose1`` on ``link1`` and ``pose2`` on ``link2`` held together (``connect``:
    their points; ``weld``: their frames)."""

    name: str
    type: str
    link1: str
    pose1: Pose
    link2: str
    pose2: Pose
    solref: tuple[float, ...] | None = None  # MuJoCo's softness; None: its defaults
    solimp: tuple[float, ...] | None = None
    torquescale: float | None = None  # a weld's


@dataclass(frozen=True)
class NamedPose:
    """A named joint configuration: (joint, value) for the joints it names (the others at zero)."""

    name: str
    values: tuple[tuple[str, float], ...]


@dataclass(frozen=True)
class World:
    name: str
    map: str  # absolute path of the map_server YAML
    height: float = 2.0
    unknown_as_wall: bool = False
    spawn: Pose | None = None


@dataclass(frozen=True)
class Robot:
    name: str
    links: tuple[Link, ...]
    joints: tuple[Joint, ...] = ()
    materials: tuple[Material, ...] = ()
    metadata: Metadata = field(default_factory=Metadata)
    self_collide: bool | None = None  # None: on where the format expresses the matrix
    urdf_extras: tuple[str, ...] = ()
    worlds: tuple[World, ...] = ()
    sensors: tuple[Sensor, ...] = ()
    actuators: tuple[Actuator, ...] = ()
    gazebo: str = "sim"  # sim | classic
    ros: str = "ros2"  # ros2 | ros1: the package type, ros_control flavour, launch files
    base: str = "fixed"
    poses: tuple[NamedPose, ...] = ()
    drive_report: str = ""  # JSON: robotkit.model.gains.tune's report, once the build has tuned the drives
    self_collision: Settings = Settings()
    collision_matrix: Matrix | None = None  # once the build has sampled it (robotkit.model.selfcollision)
    moveit: bool = False  # write the MoveIt 2 configuration (robotkit.emit.moveit)
    mjcf_extras: tuple[str, ...] = ()  # MJCF section elements, verbatim (robotkit.emit.mjcf)
    loops: tuple[Loop, ...] = ()

    def home(self) -> NamedPose | None:
        """The pose the robot starts in: ``home``, else the first pose, else None (all zero)."""
        by_name = {p.name: p for p in self.poses}
        return by_name.get("home") or (self.poses[0] if self.poses else None)

    def frame_links(self) -> set[str]:
        """Massless links fixed to another link: SDF writes them as ``<frame>`` (an SDF link
        without an inertial would weigh 1 kg in Gazebo and Drake) and moves their geometry and
        sensors into the link that carries them, as libsdformat lumps them in a URDF.

        A massless root with a fixed child is a frame too, attached to that child
        (:meth:`anchor`).  Call after ``finalize`` (inertials known)."""
        parent_joint = {j.child: j for j in self.joints}
        out = set()
        for link in self.links:
            if link.inertial is not None or link.name == "world":
                continue
            j = parent_joint.get(link.name)
            if j is None:
                if self.anchor() is not None:
                    out.add(link.name)
            elif j.type == "fixed" and j.parent != "world":
                out.add(link.name)
        return out

    def anchor(self) -> str | None:
        """The link a massless root is attached to when the root is only a frame (the nearest
        link with mass welded to it by fixed joints, e.g. ``base_link`` below
        ``base_footprint``); None otherwise."""
        root = self.root
        if root == "world" or self.link(root).inertial is not None:
            return None
        by_name = {link.name: link for link in self.links}
        todo = [root]  # breadth first: the nearest link with mass welded to the root
        while todo:
            below = [j.child for name in todo for j in self.joints if j.parent == name and j.type == "fixed"]
            found = next((c for c in below if by_name[c].inertial is not None), None)
            if found is not None:
                return found
            todo = below
        return None

    def anchor_pose(self) -> Pose:
        """The pose of :meth:`anchor` in the massless root's frame: every fixed joint between
        them (the PhantomX arm's ``base_link`` -> ``arm_base_link`` -> first servo)."""
        parent_joint = {j.child: j for j in self.joints}
        T, name = np.eye(4), self.anchor()
        while name != self.root:
            j = parent_joint[name]
            T = j.origin.matrix() @ T
            name = j.parent
        return Pose(tuple(float(v) for v in T[:3, 3]), matrix_rpy(T[:3, :3]))

    def body_mass(self, name: str) -> float:
        """Mass of ``name`` and of everything welded to it by fixed joints below it: what a
        simulator moves as one body."""
        by_name = {link.name: link for link in self.links}
        total, todo = 0.0, [name]
        while todo:
            link = by_name[todo.pop()]
            total += link.inertial.mass if link.inertial is not None else 0.0
            todo += [j.child for j in self.joints if j.parent == link.name and j.type == "fixed"]
        return total

    def consumer_problems(self) -> list[tuple[str, str, tuple[str, ...]]]:
        """(link, message, formats) for what a program loading a format refuses: a moving
        link without mass (MuJoCo rejects the model; libsdformat drops the link and everything
        below it; an SDF link without inertial weighs 1 kg), a massless root with no mass welded to
        it (libsdformat's URDF conversion gives an empty model), and a chain nested deeper
        than MuJoCo's XML reader goes."""
        out = []
        moving = {"revolute", "continuous", "prismatic", "planar", "floating"}
        for j in self.joints:
            if j.type in moving and not self.body_mass(j.child) > 0:
                out.append((j.child, f"link '{j.child}' moves (joint '{j.name}') but has no mass: MuJoCo refuses "
                            "to load it and Gazebo drops it with everything below it; give it an inertial "
                            f"(links.{j.child}.inertial: {{mass: ...}}, or geometry and a density)",
                            ("urdf", "sdf", "mjcf")))
        root = self.root
        welded = self.welded(root)  # the root and the links fixed to it: one body in a simulator
        empty = (root != "world" and self.link(root).inertial is None and self.anchor() is None
                 and any(j.parent == root for j in self.joints))
        for link in self.links:  # libsdformat weighs a welded link with the links welded below it only
            up = next((j for j in self.joints if j.child == link.name), None)
            moves = next((j for j in self.joints if j.parent == link.name and j.type in moving), None)
            if (up is not None and up.type == "fixed" and moves is not None and not self.body_mass(link.name) > 0
                    and not (empty and link.name in welded)):  # that is the root's problem, below
                out.append((link.name, f"link '{link.name}' has no mass, nor the links welded below it, and joint "
                            f"'{moves.name}' moves below it: Gazebo's URDF conversion drops everything that moves "
                            f"below it; give links.{link.name} an inertial", ("urdf",)))
        if empty:
            what = (f"link '{root}' is the root and has no mass, nor the links welded to it "
                    f"({', '.join(repr(n) for n in welded[1:])})" if len(welded) > 1 else
                    f"link '{root}' is the root, has no mass and only moving joints below it")
            out.append((root, f"{what}: Gazebo's URDF conversion drops it and everything below it (an empty model); "
                        f"name the root 'world' to fix the robot to the world, or give links.{root} an inertial",
                        ("urdf", "sdf")))
        for link in self.links:
            if link.inertial is not None and link.inertial.mass > 0 and \
                    mujoco_ready(link.inertial.tensor()) is None:
                moments = ", ".join(f"{v:.6g}" for v in np.linalg.eigvalsh(link.inertial.tensor()))
                out.append((link.name, f"link '{link.name}': MuJoCo refuses its inertia (principal moments {moments} "
                            f"kg m^2; it needs each at least {MIN_MOMENT:g} and the two smaller summing to the "
                            f"largest); give links.{link.name} an inertia it accepts (inertial.policy: repair "
                            "raises the moments)", ("mjcf",)))
        depth, deepest = self.depth()
        if depth > MJCF_MAX_DEPTH:
            out.append((deepest, f"link '{deepest}' sits {depth} links deep: MuJoCo's XML reader stops at "
                        f"{MJCF_MAX_DEPTH} nested bodies, so it could not load the MJCF (a body per link); "
                        "make the chain shorter", ("mjcf",)))
        return out

    def welded(self, name: str) -> list[str]:
        """``name`` and the links fixed to it below, breadth first."""
        out, i = [name], 0
        while i < len(out):
            out += [j.child for j in self.joints if j.parent == out[i] and j.type == "fixed"]
            i += 1
        return out

    def depth(self) -> tuple[int, str]:
        """(number of links on the longest root-to-leaf path, the leaf)."""
        parent = {j.child: j.parent for j in self.joints}
        known: dict[str, int] = {}
        for link in self.links:
            chain, name = [], link.name
            while name not in known and name in parent:
                chain.append(name)
                name = parent[name]
            base = known.setdefault(name, 1)
            for i, n in enumerate(reversed(chain)):
                known[n] = base + i + 1
        leaf = max(known, key=lambda n: (known[n], n))
        return known[leaf], leaf

    def link(self, name: str) -> Link:
        for link in self.links:
            if link.name == name:
                return link
        raise KeyError(name)

    def joint(self, name: str) -> Joint:
        for joint in self.joints:
            if joint.name == name:
                return joint
        raise KeyError(name)

    @property
    def root(self) -> str:
        children = {j.child for j in self.joints}
        return next(link.name for link in self.links if link.name not in children)

    def all_geoms(self, link: Link) -> tuple[Geom, ...]:
        return link.visuals + link.collisions + tuple(g for _, geoms in link.format_collisions for g in geoms)

    def meshes(self) -> dict[str, MeshRef]:
        """Every distinct mesh file unit of work (incl. the sources of collision proxies), by key."""
        out: dict[str, MeshRef] = {}
        for link in self.links:
            for geom in self.all_geoms(link):
                if geom.shape.mesh is not None:
                    out.setdefault(geom.shape.mesh.key, geom.shape.mesh)
        return dict(sorted(out.items()))

    def proxies(self) -> dict[str, Shape]:
        """Every distinct collision-proxy unit of work, by key."""
        out: dict[str, Shape] = {}
        for link in self.links:
            for geom in self.all_geoms(link):
                if geom.shape.kind == "proxy":
                    out.setdefault(geom.shape.proxy_key, geom.shape)
        return dict(sorted(out.items()))

    def to_dict(self) -> dict:
        return asdict(self)
