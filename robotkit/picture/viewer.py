"""`robotkit view PATH`: the robot in the browser (viser), rebuilt live.

viser's ViserUrdf (through yourdfpy) draws the built URDF's visual and collision geometry;
on top of it, one frame per link carries the overlays the report draws too: the equivalent
inertia box, the centre of mass, the link frame and joint axis, sensor frames and camera
fields of view. A slider per joint moves it within its limits, in degrees for a hinge and
millimetres for a slide (the robot is posed in radians and metres; yourdfpy moves mimic joints
with their leader). A floor grid under the robot (its cell size in the status line) and the
world axes give scale and orientation; the links a lint fires on are red, as in the report.
A recipe and every file it reads (includes, meshes) are watched: on a save the recipe is
rebuilt through the same build (robotkit.pipeline.runner) and the view updated in place; a
build error is shown in the page, and the last good robot stays on screen. A recipe with
variants shows each (a "Robot" selector switches between them).
"""

from __future__ import annotations

import math
import sys
import threading
import time
import warnings
import webbrowser
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robotkit import urdfxml
from robotkit.check.lints import equivalent_box, lint, read_urdf_facts, resolve_uri
from robotkit.errors import RobotkitError
from robotkit.picture.page import flagged_links

POLL = 0.3  # seconds between looks at the watched files
CAMERA_TYPES = {"camera", "depth", "depth_camera", "rgbd_camera", "multicamera", "wideanglecamera"}
FLAGGED = (230, 25, 25)  # links a lint fired on (the report's red)
UNITS = {"revolute": ("°", 180 / np.pi, 0.1), "continuous": ("°", 180 / np.pi, 0.1),
         "prismatic": ("mm", 1000.0, 0.1)}  # slider unit, per SI unit, step


@dataclass
class Built:
    """What the view shows: a URDF and where its package:// meshes are."""
    urdf: Path
    packages: dict[str, str]
    watch: list[Path] = field(default_factory=list)
    name: str = ""  # the robot's (a recipe's variants are told apart by it)


def load_urdf(built: Built):
    import yourdfpy  # heavy (trimesh): viser and yourdfpy load only when viewing

    def handler(fname: str) -> str:
        found = resolve_uri(fname, built.urdf.parent, built.packages)
        return str(found) if found is not None else fname

    return yourdfpy.URDF.load(str(built.urdf), filename_handler=handler, load_meshes=True,
                              build_collision_scene_graph=True, load_collision_meshes=True)


def sensors_of(urdf_file: Path) -> list[tuple[str, str, str, float, float]]:
    """(name, type, link, horizontal fov, aspect) of each <gazebo reference><sensor> block."""
    out = []
    root = urdfxml.parse_file(urdf_file).getroot()
    for g in root.findall("gazebo"):
        for s in g.findall("sensor"):
            link = g.get("reference")
            if not link:
                continue
            fov = s.findtext("camera/horizontal_fov")
            w, h = s.findtext("camera/image/width"), s.findtext("camera/image/height")
            aspect = float(w) / float(h) if w and h else 4 / 3
            out.append((s.get("name", link), s.get("type", ""), link, float(fov) if fov else 0.0, aspect))
    return out


def lint_flagged(built: Built) -> set[str]:
    """The links the report's lints fire on (robotkit.check.lints), drawn red."""
    links, joints, notes = read_urdf_facts(built.urdf, built.packages)
    return flagged_links(notes + lint(links, joints))


def paint_flagged(urdf, flagged: set[str]) -> None:
    """Colour the visual meshes of the ``flagged`` links red (before viser draws them)."""
    import trimesh  # heavy: see load_urdf

    scene = urdf.scene
    parents = scene.graph.transforms.parents
    for name, mesh in scene.geometry.items():
        if parents.get(name) in flagged:
            mesh.visual = trimesh.visual.ColorVisuals(mesh, face_colors=[*FLAGGED, 255])


def slider_scale(joint) -> tuple[str, float, float, float, float]:
    """(label, slider units per radian or metre, min, max, step) of a joint's slider: degrees
    for a hinge, millimetres for a slide, its limits rounded inwards to the step (a continuous
    joint: a turn either way of zero)."""
    lo, hi = -np.pi, np.pi
    limit = joint.limit
    if limit is not None and joint.type != "continuous" and limit.lower is not None and limit.upper is not None \
            and limit.lower < limit.upper:
        lo, hi = float(limit.lower), float(limit.upper)
    unit, per, step = UNITS.get(joint.type, ("", 1.0, None))
    if step is None:
        return joint.name, per, lo, hi, (hi - lo) / 1000
    low, high = math.ceil(lo * per / step - 1e-9) * step, math.floor(hi * per / step + 1e-9) * step
    if low >= high:  # a range narrower than a step
        low, high = lo * per, hi * per
    return f"{joint.name} ({unit})", per, low, high, step


def length(metres: float) -> str:
    """A grid's cell size in words: 1 mm, 10 cm, 1 m."""
    if metres >= 1:
        return f"{metres:g} m"
    return f"{metres * 100:.3g} cm" if metres >= 0.01 else f"{metres * 1000:.3g} mm"


def _wxyz(R: np.ndarray) -> np.ndarray:
    import viser.transforms as tf  # heavy: see load_urdf

    if np.linalg.det(R) < 0:
        R = R.copy()
        R[:, 2] *= -1
    return tf.SO3.from_matrix(R).wxyz


class Viewer:
    def __init__(self, server, kind: str, make):
        self.server, self.kind, self.make = server, kind, make
        self.lock = threading.RLock()
        self.urdf = None
        self.viser_urdf = None
        self.robots: list[Built] = []  # what make() returned: a recipe's variants, or one robot
        self.choice: str | None = None  # the robot shown, among several
        self.selector = None
        self.flagged: set[str] = set()
        self.grid = None
        self.notes: list[str] = []  # below the status line: the grid's scale, the flagged links
        self.sliders: dict[str, object] = {}
        self.per_si: dict[str, float] = {}  # slider units per radian or metre
        self.values: dict[str, float] = {}  # radians and metres
        self.joint_folder = None
        self.overlay_nodes: dict[str, list] = {"inertia": [], "com": [], "frames": [], "sensors": []}
        self.link_frames: dict[str, object] = {}
        self.watch: dict[Path, float] = {}
        gui = server.gui
        self.status = gui.add_markdown("Building…", order=0)
        with gui.add_folder("Show", order=1):
            self.toggles = {
                "visual": gui.add_checkbox("Visual", True),
                "collision": gui.add_checkbox("Collision", False),
                "grid": gui.add_checkbox("Floor grid and world axes", True),
                "inertia": gui.add_checkbox("Inertia boxes", False),
                "com": gui.add_checkbox("Centres of mass", False),
                "frames": gui.add_checkbox("Frames and joint axes", False),
                "sensors": gui.add_checkbox("Sensors", False),
            }
        for key, box in self.toggles.items():
            box.on_update(lambda _, key=key: self._apply_toggle(key))

    # ---------------------------------------------------------------- (re)loading
    def reload(self) -> bool:
        """Build and show; on a build error keep the last robot and show the error."""
        start = time.perf_counter()
        try:
            robots = self.make()
            robots = [robots] if isinstance(robots, Built) else list(robots)
            built = next((b for b in robots if b.name == self.choice), robots[0])
            urdf, flagged = load_urdf(built), lint_flagged(built)
        except RobotkitError as exc:
            self._watch(getattr(exc, "watch", None) or [])
            self._error("\n".join(exc.lines()))
            return False
        except Exception as exc:  # noqa: BLE001  (a broken file must not end the viewer)
            self._error(f"{type(exc).__name__}: {exc}")
            return False
        self._watch(built.watch)
        self.robots = robots
        self._selector()
        self._present(built, urdf, flagged, start)
        return True

    def select(self, name: str) -> None:
        """Show robot ``name`` of the last build (the "Robot" selector)."""
        start = time.perf_counter()
        built = next((b for b in self.robots if b.name == name), None)
        if built is None or name == self.choice:
            return
        try:
            urdf, flagged = load_urdf(built), lint_flagged(built)
        except Exception as exc:  # noqa: BLE001  (a broken file must not end the viewer)
            self._error("\n".join(exc.lines()) if isinstance(exc, RobotkitError) else f"{type(exc).__name__}: {exc}")
            return
        self._present(built, urdf, flagged, start)

    def _present(self, built: Built, urdf, flagged: set[str], start: float) -> None:
        with self.lock:
            self.choice, self.flagged = built.name or None, flagged
            self._show(urdf, built)
        name = urdf.robot.name
        self.status.content = (f"**{name}**: {len(self.sliders)} joints; shown in {time.perf_counter() - start:.2f} s"
                               + "".join(f"\n\n{note}" for note in self.notes))
        print(f"view: {name} updated ({time.perf_counter() - start:.2f} s)", file=sys.stderr, flush=True)

    def _selector(self) -> None:
        """The "Robot" selector when there are several robots (a recipe's variants)."""
        names = [b.name for b in self.robots]
        if self.selector is not None and (len(names) < 2 or list(self.selector.options) != names):
            self.selector.remove()
            self.selector = None
        if self.selector is None and len(names) > 1:
            initial = self.choice if self.choice in names else names[0]
            self.selector = self.server.gui.add_dropdown("Robot", names, initial_value=initial, order=0.5,
                                                         hint="the recipe's variants")
            self.selector.on_update(lambda _: self.select(self.selector.value))

    def _error(self, text: str) -> None:
        self.status.content = "**Build failed** (the last good robot is shown):\n\n```\n" + text + "\n```"
        print(f"view: build failed:\n{text}", file=sys.stderr, flush=True)

    def _watch(self, files) -> None:
        files = list(files)
        self.watch = {Path(f): _mtime(Path(f)) for f in files} or self.watch

    def changed(self) -> bool:
        return any(_mtime(f) != t for f, t in self.watch.items())

    def _show(self, urdf, built: Built) -> None:
        from viser.extras import ViserUrdf  # heavy: see load_urdf

        if self.viser_urdf is not None:
            with warnings.catch_warnings():  # ViserUrdf removes meshes whose frames went first
                warnings.simplefilter("ignore", UserWarning)
                self.viser_urdf.remove()
        for f in self.link_frames.values():  # their overlays go with them
            f.remove()
        self.overlay_nodes = {k: [] for k in self.overlay_nodes}
        self.link_frames = {}
        self.urdf = urdf
        paint_flagged(urdf, self.flagged)
        self.viser_urdf = ViserUrdf(self.server, urdf, root_node_name="/robot", load_meshes=True,
                                    load_collision_meshes=urdf.collision_scene is not None)
        self.notes = [self._floor(urdf)]
        if self.flagged:
            self.notes.append("Red: links a lint fired on (see the report): " + ", ".join(sorted(self.flagged)))
        self._overlays(urdf, built)
        self._joint_sliders(urdf)
        self._update_cfg()
        for key in self.toggles:
            self._apply_toggle(key)
        if not getattr(self, "_camera_set", False):
            lo, hi = urdf.scene.bounds
            centre, size = (lo + hi) / 2, float(np.linalg.norm(hi - lo))
            self.server.initial_camera.look_at = centre
            self.server.initial_camera.position = centre + np.array([1.0, 0.8, 0.6]) * max(size, 0.1) * 1.5
            self._camera_set = True

    def _floor(self, urdf) -> str:
        """A grid on the floor (z = 0, or under the robot when it reaches below), centred on the
        world origin and wide enough for the robot, with the world axes; its scale, in words."""
        lo, hi = urdf.scene.bounds
        size = max(float(np.linalg.norm(hi - lo)), 0.01)
        cell = 10.0 ** math.floor(math.log10(size)) / 10
        section = cell * 10
        reach = max(float(np.max(np.abs(np.concatenate([lo[:2], hi[:2]])))) + size / 2, section)
        width = 2 * math.ceil(reach / section) * section
        self.grid = self.server.scene.add_grid("/floor", width=width, height=width, cell_size=cell,
                                               section_size=section, position=(0.0, 0.0, min(0.0, float(lo[2]))))
        axes = self.server.scene.world_axes
        axes.axes_length, axes.axes_radius = size * 0.15, size * 0.004
        return f"Floor grid: {length(cell)} squares, a line every {length(section)}; world axes x red, y green, z blue"

    def _joint_sliders(self, urdf) -> None:
        for name, s in self.sliders.items():
            self.values[name] = s.value / self.per_si[name]
        if self.joint_folder is not None:
            self.joint_folder.remove()
        self.sliders, self.per_si = {}, {}
        gui = self.server.gui
        with gui.add_folder("Joints", order=2) as folder:
            self.joint_folder = folder
            for name in urdf.actuated_joint_names:
                label, per, low, high, step = slider_scale(urdf.joint_map[name])
                si_low, si_high = low / per, high / per
                value = float(np.clip(self.values.get(name, 0.0 if si_low <= 0 <= si_high else si_low) * per, low, high))
                slider = gui.add_slider(label, min=round(low, 6), max=round(high, 6), step=step,
                                        initial_value=float(np.clip(round(value / step) * step, low, high)))
                slider.on_update(lambda _: self._update_cfg())
                self.sliders[name], self.per_si[name] = slider, per

    def _update_cfg(self) -> None:
        with self.lock:
            if self.urdf is None:
                return
            cfg = np.array([self.sliders[n].value / self.per_si[n] for n in self.urdf.actuated_joint_names],
                           dtype=float)  # radians and metres
            self.viser_urdf.update_cfg(cfg)  # also updates self.urdf (yourdfpy; mimic joints follow)
            for link, frame in self.link_frames.items():
                T = self.urdf.get_transform(link)
                frame.wxyz, frame.position = _wxyz(T[:3, :3]), T[:3, 3]

    def _apply_toggle(self, key: str) -> None:
        on = self.toggles[key].value
        with self.lock:
            if self.viser_urdf is None:
                return
            if key == "visual":
                self.viser_urdf.show_visual = on
            elif key == "collision":
                if self.urdf.collision_scene is not None:
                    self.viser_urdf.show_collision = on
            elif key == "grid":
                self.grid.visible = self.server.scene.world_axes.visible = on
            else:
                for n in self.overlay_nodes[key]:
                    n.visible = on

    # ---------------------------------------------------------------- overlays
    def _overlays(self, urdf, built: Built) -> None:
        scene = self.server.scene
        lo, hi = urdf.scene.bounds
        size = max(float(np.linalg.norm(hi - lo)), 0.05)
        palette = [(31, 119, 180), (255, 127, 14), (44, 160, 44), (148, 103, 189), (140, 86, 75),
                   (227, 119, 194), (127, 127, 127), (188, 189, 34), (23, 190, 207)]
        child_joint = {j.child: j for j in urdf.joint_map.values()}
        for i, (name, link) in enumerate(urdf.link_map.items()):
            frame = scene.add_frame(f"/overlays/{name}", show_axes=False)
            self.link_frames[name] = frame
            axes = scene.add_frame(f"/overlays/{name}/axes", show_axes=True, axes_length=size * 0.08,
                                   axes_radius=size * 0.003)
            self.overlay_nodes["frames"].append(axes)
            j = child_joint.get(name)
            if j is not None and j.type in ("revolute", "continuous", "prismatic") and j.axis is not None:
                axis = np.asarray(j.axis, dtype=float)
                arrow = scene.add_arrows(f"/overlays/{name}/joint_axis", np.array([[[0, 0, 0], axis * size * 0.2]]),
                                         (255, 200, 0), shaft_radius=size * 0.006, head_radius=size * 0.015,
                                         head_length=size * 0.03)
                self.overlay_nodes["frames"].append(arrow)
            inertial = link.inertial
            if inertial is None or inertial.mass is None or inertial.mass <= 0 or inertial.inertia is None:
                continue
            T = inertial.origin if inertial.origin is not None else np.eye(4)
            I = T[:3, :3] @ np.asarray(inertial.inertia, dtype=float) @ T[:3, :3].T
            moments, axes_R = np.linalg.eigh(I)
            sides = np.maximum(equivalent_box(inertial.mass, moments), size * 0.002)
            colour = FLAGGED if name in self.flagged else palette[i % len(palette)]
            box = scene.add_box(f"/overlays/{name}/inertia", colour, tuple(sides), opacity=0.5,
                                wxyz=_wxyz(axes_R), position=T[:3, 3], cast_shadow=False)
            self.overlay_nodes["inertia"].append(box)
            com = scene.add_icosphere(f"/overlays/{name}/com", radius=size * 0.012, color=colour,
                                      position=T[:3, 3], cast_shadow=False)
            self.overlay_nodes["com"].append(com)
        # a camera looks along +x of its link (Gazebo); viser's frustum along +z, image y down
        cam_R = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
        for name, kind, link, fov, aspect in sensors_of(built.urdf):
            if link not in self.link_frames:
                continue
            node = f"/overlays/{link}/sensor_{name}"
            if kind in CAMERA_TYPES and fov > 0:
                vfov = 2 * np.arctan(np.tan(fov / 2) / aspect)
                h = scene.add_camera_frustum(node, fov=float(vfov), aspect=float(aspect), scale=size * 0.12,
                                             color=(0, 170, 220), wxyz=_wxyz(cam_R), thickness=size * 0.002)
            else:
                h = scene.add_frame(node, show_axes=True, axes_length=size * 0.06, axes_radius=size * 0.003)
            self.overlay_nodes["sensors"].append(h)
            self.overlay_nodes["sensors"].append(scene.add_label(f"{node}/label", f"{name} ({kind})"))


def _mtime(path: Path) -> float:
    try:
        return path.stat().st_mtime_ns
    except OSError:
        return -1


def serve(label: str, kind: str, make, port: int = 8080, open_browser: bool = True,
          stop: threading.Event | None = None) -> int:
    """Serve the viewer of ``make()`` (a :class:`Built`, rebuilt when what it watches changes)
    until interrupted (or ``stop`` is set); ``kind`` is what PATH was (recipe, build, urdf)."""
    import viser  # heavy: see load_urdf

    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    server.gui.configure_theme(control_width="large")
    viewer = Viewer(server, kind, make)
    viewer.reload()
    url = f"http://127.0.0.1:{server.get_port()}"
    print(f"viewing {label} at {url} (Ctrl-C stops)", flush=True)
    if open_browser:
        webbrowser.open(url)
    stop = stop or threading.Event()
    try:
        while not stop.wait(POLL):
            if viewer.changed():
                time.sleep(0.1)  # let an editor finish writing
                viewer.reload()
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
    return 0
