"""`robotkit view PATH`: the robot in the browser (viser), rebuilt live.

viser's ViserUrdf (through yourdfpy) draws the built URDF's visual and collision geometry;
on top of it, one frame per link carries the overlays the report draws too: the equivalent
inertia box, the centre of mass, the link frame and joint axis, sensor frames and camera
fields of view. A slider per joint moves it within its limits (yourdfpy moves mimic joints
with their leader). A recipe and every file it reads (includes, meshes) are watched: on a
save the recipe is rebuilt through the same build (robotkit.pipeline.runner) and the view updated in
place; a build error is shown in the page, and the last good robot stays on screen.
"""

from __future__ import annotations

import sys
import threading
import time
import warnings
import webbrowser
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robotkit import urdfxml
from robotkit.check.lints import equivalent_box, resolve_uri
from robotkit.errors import RobotkitError

POLL = 0.3  # seconds between looks at the watched files
CAMERA_TYPES = {"camera", "depth", "depth_camera", "rgbd_camera", "multicamera", "wideanglecamera"}


@dataclass
class Built:
    """What the view shows: a URDF and where its package:// meshes are."""
    urdf: Path
    packages: dict[str, str]
    watch: list[Path] = field(default_factory=list)


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
        self.sliders: dict[str, object] = {}
        self.values: dict[str, float] = {}
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
            built = self.make()
            urdf = load_urdf(built)
        except RobotkitError as exc:
            self._watch(getattr(exc, "watch", None) or [])
            self._error("\n".join(exc.lines()))
            return False
        except Exception as exc:  # noqa: BLE001  (a broken file must not end the viewer)
            self._error(f"{type(exc).__name__}: {exc}")
            return False
        self._watch(built.watch)
        with self.lock:
            self._show(urdf, built)
        name = urdf.robot.name
        self.status.content = f"**{name}**: {len(self.sliders)} joints; shown in {time.perf_counter() - start:.2f} s"
        print(f"view: {name} updated ({time.perf_counter() - start:.2f} s)", file=sys.stderr, flush=True)
        return True

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
        self.viser_urdf = ViserUrdf(self.server, urdf, root_node_name="/robot", load_meshes=True,
                                    load_collision_meshes=urdf.collision_scene is not None)
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

    def _joint_sliders(self, urdf) -> None:
        for name, s in self.sliders.items():
            self.values[name] = s.value
        if self.joint_folder is not None:
            self.joint_folder.remove()
        self.sliders = {}
        gui = self.server.gui
        with gui.add_folder("Joints", order=2) as folder:
            self.joint_folder = folder
            for name in urdf.actuated_joint_names:
                j = urdf.joint_map[name]
                lo, hi = -np.pi, np.pi
                if j.limit is not None and j.type != "continuous" and j.limit.lower is not None \
                        and j.limit.upper is not None and j.limit.lower < j.limit.upper:
                    lo, hi = float(j.limit.lower), float(j.limit.upper)
                value = float(np.clip(self.values.get(name, 0.0 if lo <= 0 <= hi else lo), lo, hi))
                slider = gui.add_slider(name, min=lo, max=hi, step=(hi - lo) / 1000, initial_value=value)
                slider.on_update(lambda _: self._update_cfg())
                self.sliders[name] = slider

    def _update_cfg(self) -> None:
        with self.lock:
            if self.urdf is None:
                return
            cfg = np.array([self.sliders[n].value for n in self.urdf.actuated_joint_names], dtype=float)
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
            colour = palette[i % len(palette)]
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
