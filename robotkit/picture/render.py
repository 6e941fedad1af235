"""Offscreen pictures of a robot from its MJCF: MuJoCo's renderer (OSMesa by default, no
display needed), overlays added to the scene with ``mjv_initGeom``.

robotkit's MJCF puts visual geoms in group 2 and collision geoms in group 3; a body is a link.
Overlays: the equivalent inertia box of each link (a uniform box with the link's mass and
principal moments, at its centre of mass along its principal axes, as Gazebo draws it),
centres of mass, link frames, joint axes, sensor frames and fields of view.
"""

from __future__ import annotations

import functools
import io
import math
import os
import re
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "osmesa")  # before mujoco is imported: software GL, no display

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from robotkit.check.lints import equivalent_box  # noqa: E402
from robotkit.errors import Problem, RendererUnavailable, RobotkitError  # noqa: E402
from robotkit.ioutil import write_if_changed  # noqa: E402

VISUAL, COLLISION, SENSOR = 2, 3, 4  # MuJoCo geom/site groups in robotkit's MJCF
HINGE, SLIDE = int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)
BACKGROUND = (235, 238, 242)
GHOST = 0.25  # alpha of the visual behind collision geometry and overlays
COLLISION_RGBA = (0.1, 0.55, 0.95, 0.6)
FLAGGED = (0.9, 0.1, 0.1)  # links a lint fired on
PALETTE = [  # no red or brown: red is for flagged links
(0.12, 0.47, 0.71), (1.0, 0.5, 0.05), (0.17, 0.63, 0.17), (0.58, 0.4, 0.74),
           (0.89, 0.47, 0.76), (0.5, 0.5, 0.5), (0.74, 0.74, 0.13), (0.09, 0.75, 0.81)]
# (file stem, title, azimuth, elevation)
SIDES = [("front", "front", 180.0, -5.0), ("left", "left side", 270.0, -5.0),
         ("top", "top", 180.0, -89.0), ("iso", "three-quarter view", 135.0, -25.0)]


@dataclass(frozen=True)
class Picture:
    file: str  # below the report folder
    title: str
    caption: str
    kind: str  # view | collision | inertia | frames | joint


def bounds(model, data) -> tuple[np.ndarray, float]:
    """Centre and radius of the drawn robot."""
    lo, hi = box(model, data)
    return (lo + hi) / 2, max(float(np.linalg.norm(hi - lo)) / 2, 0.05)


def box(model, data) -> tuple[np.ndarray, np.ndarray]:
    """World bounding box of the drawn robot: the corners of its visual geoms' boxes (all
    geoms when it has none)."""
    pts = corners(model, data)
    return pts.min(0), pts.max(0)


def corners(model, data) -> np.ndarray:
    """The corners of the drawn geoms' boxes and the body origins, in the world (N x 3)."""
    drawn = model.geom_type != int(mujoco.mjtGeom.mjGEOM_PLANE)
    visual = model.geom_group == VISUAL
    ids = np.flatnonzero((visual if visual.any() else np.ones_like(visual)) & drawn)
    origins = data.xpos[1:] if model.nbody > 1 else np.zeros((1, 3))
    local = model.geom_aabb[ids, None, :3] + SIGNS[None] * model.geom_aabb[ids, None, 3:]  # (n, 8, 3)
    world = data.geom_xpos[ids, None, :] + np.einsum("nkj,nij->nki", local, data.geom_xmat[ids].reshape(-1, 3, 3))
    return np.concatenate([origins, world.reshape(-1, 3)]).astype(float)


SIGNS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)  # a box's corners


def fit(points: np.ndarray, azimuth: float, elevation: float, fovy: float, aspect: float,
        margin: float = 0.9) -> tuple[np.ndarray, float]:
    """(look-at point, distance) of MuJoCo's free camera at ``azimuth``/``elevation`` (degrees)
    that frames ``points`` with a ``margin`` of the picture to spare: the robot fills the
    picture from every side, whatever its shape."""
    az, el = math.radians(azimuth), math.radians(elevation)
    forward = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    up = np.array([-math.sin(el) * math.cos(az), -math.sin(el) * math.sin(az), math.cos(el)])
    right = np.cross(forward, up)
    ty = math.tan(math.radians(fovy) / 2) * margin
    tx = ty * aspect
    x, y, z = points @ right, points @ up, points @ forward
    # the camera (cx, cy, cz in the right/up/forward basis) is behind each side plane of the
    # picture through the point furthest out on that side: both sides touched, centred
    lo_x, hi_x = np.max(x - tx * z), np.min(x + tx * z)
    lo_y, hi_y = np.max(y - ty * z), np.min(y + ty * z)
    cx, cy = (lo_x + hi_x) / 2, (lo_y + hi_y) / 2
    cz = min((hi_x - lo_x) / (2 * tx), (hi_y - lo_y) / (2 * ty))
    distance = max(float((z.min() + z.max()) / 2 - cz), 0.05)
    lookat = cx * right + cy * up + (cz + distance) * forward
    return lookat, distance


def load_model(mjcf: str | os.PathLike):
    """The MJCF compiled by MuJoCo, with a plain light background (a flat skybox) unless it has
    a skybox of its own; a file MuJoCo cannot load is a RobotkitError naming it."""
    try:
        spec = mujoco.MjSpec.from_file(str(mjcf))
        if not any(t.type == mujoco.mjtTexture.mjTEXTURE_SKYBOX for t in spec.textures):
            rgb = [c / 255 for c in BACKGROUND]
            spec.add_texture(name="robotkit_background", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
                             builtin=mujoco.mjtBuiltin.mjBUILTIN_FLAT, rgb1=rgb, rgb2=rgb, width=8, height=8)
        return spec.compile()
    except ValueError as exc:
        raise RobotkitError(Problem(f"MuJoCo cannot load it: {str(exc).strip()}", file=str(mjcf))) from None


def renderer(model, height: int, width: int):
    """MuJoCo's offscreen renderer, or a RobotkitError that says how to get one."""
    try:
        return mujoco.Renderer(model, height, width)
    except Exception as exc:  # noqa: BLE001  (no GL context: the backend is missing or needs a display)
        raise RendererUnavailable.because(exc) from None


class Canvas:
    """An offscreen framebuffer of ``width`` x ``height`` pixels drawn in panels side by side and
    read once (a joint's strip: its poses in one read; with OSMesa the drawing happens in the read,
    and each read costs a fixed wait on the rasteriser's threads besides).  MuJoCo's own GL context
    and render context, as ``mujoco.Renderer`` makes them; a RendererUnavailable without GL."""

    def __init__(self, model, width: int, height: int, max_geom: int = 10000):
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, height)
        self.width, self.height = width, height
        self.gl = self.context = None
        try:
            self.gl = mujoco.GLContext(width, height)
            self.gl.make_current()
            self.context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150.value)
        except Exception as exc:  # noqa: BLE001  (no GL context: the backend is missing or needs a display)
            self.close()
            raise RendererUnavailable.because(exc) from None
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self.context)
        self.scene = mujoco.MjvScene(model=model, maxgeom=max_geom)

    def draw(self, left: int, width: int) -> None:
        """The scene into the panel of ``width`` pixels from ``left``, the framebuffer's height."""
        self.gl.make_current()
        mujoco.mjr_render(mujoco.MjrRect(left, 0, width, self.height), self.scene, self.context)

    def read(self, width: int) -> np.ndarray:
        """The framebuffer's ``width`` leftmost pixels, top row first (height x width x 3)."""
        self.gl.make_current()
        out = np.empty((self.height, width, 3), dtype=np.uint8)
        mujoco.mjr_readPixels(out, None, mujoco.MjrRect(0, 0, width, self.height), self.context)
        return np.flipud(out)

    def close(self) -> None:
        if self.context is not None:
            self.context.free()
            self.context = None
        if self.gl is not None:
            self.gl.free()
            self.gl = None


class Painter:
    """One MuJoCo model and an offscreen renderer; draws the pictures of a report."""

    def __init__(self, model, width: int = 640, height: int = 480, data=None, panels: int = 0):
        """``panels``: draw strips of up to that many pictures of ``width`` x ``height`` (a
        :class:`Canvas`, :meth:`strip`) instead of single pictures (0)."""
        self.model = model
        self.data = data if data is not None else mujoco.MjData(model)
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, height)
        model.vis.headlight.ambient[:] = 0.45
        model.vis.headlight.diffuse[:] = 0.6
        model.vis.headlight.specular[:] = 0.1
        self.width, self.height = width, height
        self.renderer = Canvas(model, width * panels, height) if panels else renderer(model, height, width)
        self.flagged: set[str] = set()
        self.aspect = width / height
        mujoco.mj_forward(model, self.data)
        self.center, self.radius = bounds(model, self.data)
        self.points = corners(model, self.data)  # what the camera frames

    def close(self):
        self.renderer.close()

    # ---------------------------------------------------------------- scene
    def _camera(self, azimuth: float, elevation: float):
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        lookat, cam.distance = fit(self.points, azimuth, elevation, self.model.vis.global_.fovy, self.aspect)
        cam.lookat[:] = lookat
        cam.azimuth, cam.elevation = azimuth, elevation
        return cam

    def _option(self, groups: dict[int, bool]):
        opt = mujoco.MjvOption()
        for g in range(len(opt.geomgroup)):
            opt.geomgroup[g] = 0
            opt.sitegroup[g] = 0
        for g, on in groups.items():
            opt.geomgroup[g] = on
        return opt

    def _draw(self, azimuth, elevation, groups, ghost: bool, overlays=()) -> np.ndarray:
        m = self.model
        saved = m.geom_rgba.copy(), m.mat_rgba.copy()
        if ghost:  # visual geoms faint, so what is drawn inside them shows
            m.geom_rgba[:, 3] = np.where(m.geom_group == VISUAL, GHOST, m.geom_rgba[:, 3])
            m.mat_rgba[:, 3] = GHOST
            m.geom_rgba[m.geom_group == COLLISION] = COLLISION_RGBA
        try:
            self._scene(self.renderer.scene, azimuth, elevation, groups, overlays)
            return self.renderer.render().copy()
        finally:
            m.geom_rgba[:], m.mat_rgba[:] = saved

    def _scene(self, scn, azimuth, elevation, groups, overlays=()) -> None:
        """``scn``: the robot as posed, seen from ``azimuth``/``elevation``, ``groups`` drawn, no
        shadows or reflections, the ``overlays`` added."""
        mujoco.mjv_updateScene(self.model, self.data, self._option(groups), None, self._camera(azimuth, elevation),
                               mujoco.mjtCatBit.mjCAT_ALL.value, scn)
        scn.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0
        scn.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
        for overlay in overlays:
            overlay(scn)

    def strip(self, poses, azimuth, elevation, groups, overlays=()) -> np.ndarray:
        """The robot at each of ``poses`` (qpos), side by side: drawn into one framebuffer (a
        :class:`Canvas`, ``panels`` of this painter) and read once."""
        canvas = self.renderer
        for i, q in enumerate(poses):
            self.pose(q)
            self._scene(canvas.scene, azimuth, elevation, groups, overlays)
            canvas.draw(i * self.width, self.width)
        return canvas.read(len(poses) * self.width)

    # ---------------------------------------------------------------- overlays
    def _add(self, scn, type_, size, pos, mat, rgba):
        if scn.ngeom >= scn.maxgeom:
            return None
        g = scn.geoms[scn.ngeom]
        mujoco.mjv_initGeom(g, type_, np.asarray(size, float), np.asarray(pos, float),
                            np.asarray(mat, float).reshape(9), np.asarray(rgba, np.float32))
        scn.ngeom += 1
        return g

    def _line(self, scn, a, b, width, rgba, type_=mujoco.mjtGeom.mjGEOM_CAPSULE):
        g = self._add(scn, type_, np.zeros(3), np.zeros(3), np.eye(3), rgba)
        if g is not None:
            mujoco.mjv_connector(g, type_, width, np.asarray(a, float), np.asarray(b, float))

    def colour(self, body: int) -> tuple:
        name = self.model.body(body).name
        return FLAGGED if name in self.flagged else PALETTE[body % len(PALETTE)]

    def inertia_boxes(self, scn):
        m, d = self.model, self.data
        for b in range(1, m.nbody):
            if m.body_mass[b] <= 0:
                continue
            sides = equivalent_box(m.body_mass[b], m.body_inertia[b])
            half = np.maximum(sides / 2, self.radius * 0.002)
            self._add(scn, mujoco.mjtGeom.mjGEOM_BOX, half, d.xipos[b], d.ximat[b], (*self.colour(b), 0.55))

    def centres_of_mass(self, scn):
        m, d = self.model, self.data
        r = self.radius * 0.025
        for b in range(1, m.nbody):
            if m.body_mass[b] > 0:
                self._add(scn, mujoco.mjtGeom.mjGEOM_SPHERE, [r, r, r], d.xipos[b], np.eye(3), (*self.colour(b), 1))

    def frames(self, scn, bodies=None, scale: float = 0.12):
        """The frames of ``bodies`` (default: every body), ``scale`` times the robot's radius long."""
        m, d = self.model, self.data
        length, width = self.radius * scale, self.radius * scale / 20
        for b in range(1, m.nbody) if bodies is None else bodies:
            R = d.xmat[b].reshape(3, 3)
            for k, rgb in enumerate(((0.9, 0.1, 0.1), (0.1, 0.8, 0.1), (0.1, 0.2, 0.95))):
                self._line(scn, d.xpos[b], d.xpos[b] + R[:, k] * length, width, (*rgb, 1))

    def joint_axes(self, scn, joints=None):
        """The axes of ``joints`` (default: every hinge and slide), as yellow arrows."""
        m, d = self.model, self.data
        length, width = self.radius * 0.3, self.radius * 0.012
        for j in range(m.njnt) if joints is None else joints:
            if int(m.jnt_type[j]) not in (HINGE, SLIDE):
                continue
            a = d.xanchor[j]
            self._line(scn, a, a + d.xaxis[j] * length, width, (1.0, 0.85, 0.0, 1), mujoco.mjtGeom.mjGEOM_ARROW)

    def sensors(self, scn):
        """Sensor sites (frames, rangefinder rays, contact boxes) and camera frusta."""
        m, d = self.model, self.data
        length, width = self.radius * 0.08, self.radius * 0.004
        ray = self.radius * 0.35
        rangefinders = {int(m.sensor_objid[s]) for s in range(m.nsensor)
                        if int(m.sensor_type[s]) == int(mujoco.mjtSensor.mjSENS_RANGEFINDER)}
        for s in range(m.nsite):
            if m.site_group[s] != SENSOR:
                continue
            R, p = d.site_xmat[s].reshape(3, 3), d.site_xpos[s]
            if s in rangefinders:
                self._line(scn, p, p + R[:, 2] * ray, width * 0.5, (1.0, 0.2, 0.6, 0.7), mujoco.mjtGeom.mjGEOM_LINE)
            elif int(m.site_type[s]) == int(mujoco.mjtGeom.mjGEOM_BOX):
                self._add(scn, mujoco.mjtGeom.mjGEOM_BOX, m.site_size[s], p, R, (1.0, 0.5, 0.0, 0.25))
            else:
                for k, rgb in enumerate(((0.9, 0.1, 0.1), (0.1, 0.8, 0.1), (0.1, 0.2, 0.95))):
                    self._line(scn, p, p + R[:, k] * length, width, (*rgb, 1))
        for c in range(m.ncam):
            R, p = d.cam_xmat[c].reshape(3, 3), d.cam_xpos[c]
            fovy = math.radians(m.cam_fovy[c])
            w, h = m.cam_resolution[c] if m.cam_resolution[c][1] > 0 else (4, 3)
            ty = math.tan(fovy / 2)
            tx = ty * w / h
            far = self.radius * 0.25
            corners = [p + far * (R @ np.array([sx * tx, sy * ty, -1.0])) for sx in (-1, 1) for sy in (-1, 1)]
            for q in corners:
                self._line(scn, p, q, width, (0.0, 0.7, 0.9, 1), mujoco.mjtGeom.mjGEOM_LINE)
            for i, j in ((0, 1), (1, 3), (3, 2), (2, 0)):
                self._line(scn, corners[i], corners[j], width, (0.0, 0.7, 0.9, 1), mujoco.mjtGeom.mjGEOM_LINE)

    # ---------------------------------------------------------------- configurations
    def pose(self, qpos=None):
        d = self.data
        d.qpos[:] = self.model.qpos0 if qpos is None else qpos
        mujoco.mj_kinematics(self.model, d)
        mujoco.mj_comPos(self.model, d)
        mujoco.mj_camlight(self.model, d)

    def joint_poses(self) -> list[tuple[str, str, list[tuple[str, np.ndarray]], str]]:
        """(joint, kind, [(label, qpos)], caption) for each hinge and slide joint: at its lower
        limit, zero and its upper limit; a joint with no limits, or limits a full turn or more
        apart (each limit the same pose as zero), at sample angles of -90 and +90 degrees instead,
        labelled as samples. Mimic joints follow.  A robot of more than :data:`BRIEF_JOINTS`
        such joints is drawn without the small positive move (:func:`joint_samples`, ``brief``)."""
        m = self.model
        out = []
        followers = self._mimics()
        drawn = [j for j in range(m.njnt) if int(m.jnt_type[j]) in (HINGE, SLIDE) and j not in followers]
        brief = len(drawn) > BRIEF_JOINTS
        for j in drawn:
            t = int(m.jnt_type[j])
            adr = m.jnt_qposadr[j]
            values, caption = joint_samples(t == HINGE, bool(m.jnt_limited[j]), *(float(v) for v in m.jnt_range[j]),
                                            self.radius, brief)
            poses = []
            for label, value in values:
                q = m.qpos0.copy()
                q[adr] = value
                for f, (leader, coef) in followers.items():
                    q[m.jnt_qposadr[f]] = sum(c * q[m.jnt_qposadr[leader]] ** k for k, c in enumerate(coef))
                poses.append((label, q))
            out.append((m.joint(j).name, "hinge" if t == HINGE else "slide", poses, caption))
        return out

    def _mimics(self) -> dict[int, tuple[int, np.ndarray]]:
        m = self.model
        out = {}
        for e in range(m.neq):
            if int(m.eq_type[e]) == int(mujoco.mjtEq.mjEQ_JOINT) and m.eq_obj2id[e] >= 0:
                out[int(m.eq_obj1id[e])] = (int(m.eq_obj2id[e]), np.array(m.eq_data[e][:5]))
        return out


def _amount(value: float, hinge: bool, sign: bool = False) -> str:
    """A joint position as the page writes it: radians and degrees, or metres."""
    if not hinge:
        return f"{value:{'+' if sign else ''}.3g} m"
    degrees = f"{math.degrees(value):+.0f}°" if round(math.degrees(value)) else "0°"
    return f"{value:{'+' if sign else ''}.3g} rad ({degrees})"


BRIEF_JOINTS = 24
"""A robot with more drawn joints than this has three pictures per joint's strip, not four: no
small positive move (the upper limit shows the positive direction), each of BRIEF_STRIP_SIZE; a
long chain's report stays cheap (a 100-link chain's strip cost 25 ms of CPU with OSMesa, 13 ms so)."""


def joint_samples(hinge: bool, limited: bool, lo: float, hi: float, radius: float,
                  brief: bool = False) -> tuple[list, str]:
    """([(label, value)], caption) of the positions a joint is drawn at: its limits, zero and a
    small positive move (the direction, when the upper limit is further); a joint without limits,
    or a hinge whose limits are a full turn or more apart, at labelled sample positions.
    ``brief``: without the small positive move (:data:`BRIEF_JOINTS`)."""
    full_turn = hinge and limited and hi - lo >= 2 * math.pi - 1e-6
    if limited and not full_turn:
        step = min(hi, 0.6 if hinge else (hi - lo) / 4) if hi > 0 and not brief else None
        values = [(f"lower {_amount(lo, hinge)}", lo), ("zero", 0.0)]
        if step is not None and step < hi:
            values.append((f"{_amount(step, hinge, True)}", step))
        values.append((f"upper {_amount(hi, hinge)}", hi))
        if brief:
            return values, "at its lower limit, zero and its upper limit"
        return values, "at its lower limit, zero, a small positive move (when the upper limit is further) and its " \
                       "upper limit"
    hinge_samples = (-math.pi / 2, 0.0, math.pi / 2) if brief else (-math.pi / 2, 0.0, 0.6, math.pi / 2)
    if full_turn:
        why = f"with limits {_amount(lo, True)} and {_amount(hi, True)}, a full turn or more apart,"
        samples = sorted({min(max(v, lo), hi) for v in hinge_samples})
    elif hinge:
        why, samples = "with no limits (continuous),", list(hinge_samples)
    else:
        why, samples = "with no limits,", [-radius / 2, 0.0, radius / 2]
    values = [("zero" if v == 0 else f"sample {_amount(v, hinge, True)}", v) for v in samples]
    shown = ", ".join("zero" if v == 0 else _amount(v, hinge, True) for v in samples)
    return values, f"{why} drawn at the sample positions {shown}"


def _save(img: np.ndarray, path: Path) -> None:
    """A PNG file (Pillow, its default zlib level; the joints' strips: :func:`png_bytes`)."""
    from PIL import Image  # only when a picture is saved

    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG")
    write_if_changed(path, buf.getvalue())


STRIP_SIZE = (256, 192)  # pixels of each picture of a strip
BRIEF_STRIP_SIZE = (192, 144)  # the same past BRIEF_JOINTS joints
STRIP_SAMPLES = 0  # no multisampling in the joints' strips: half their drawing time (OSMesa draws on the CPU)
LABEL_BAND = 28  # pixels above each picture of a strip, for its label
LABEL_FONT = 17


def png_bytes(img: np.ndarray, level: int = 1) -> bytes:
    """An RGB image (height x width x 3, uint8) as PNG bytes: rows unfiltered, zlib ``level``.
    For the joints' strips: four times as fast as Pillow's encoder (which tries every row filter)
    and about as small on flat-shaded pictures; byte-reproducible."""
    h, w = img.shape[:2]
    raw = np.empty((h, w * 3 + 1), dtype=np.uint8)
    raw[:, 0] = 0  # filter type none
    raw[:, 1:] = np.ascontiguousarray(img, dtype=np.uint8).reshape(h, w * 3)

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)  # 8 bits, RGB, deflate, no filter choice, no interlace
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw.tobytes(), level))
            + chunk(b"IEND", b""))


@functools.lru_cache(maxsize=256)
def _label(text: str, width: int, first: bool) -> np.ndarray:
    """The band above one picture of a strip: ``text``, and a separator on its left unless
    ``first`` (LABEL_BAND x width x 3; drawn once per text: a long chain's joints share labels)."""
    from PIL import Image, ImageDraw  # only when a picture is saved

    band = Image.new("RGB", (width, LABEL_BAND), (255, 255, 255))
    draw = ImageDraw.Draw(band)
    draw.text((6, LABEL_BAND // 2), text, fill=(0, 0, 0), font=_font(), anchor="lm")
    if not first:
        draw.line([(0, 0), (0, LABEL_BAND - 1)], fill=(200, 200, 200))
    return np.asarray(band)


@functools.lru_cache(maxsize=1)
def _font():
    from PIL import ImageFont

    return ImageFont.load_default(size=LABEL_FONT)


def _strip(pictures: np.ndarray, labels: list[str]) -> np.ndarray:
    """``pictures`` (as many side by side as ``labels``), each under its label (on a band of its
    own: it hides nothing)."""
    w = pictures.shape[1] // len(labels)
    band = np.concatenate([_label(label, w, i == 0) for i, label in enumerate(labels)], axis=1)
    return np.concatenate([band, pictures])


def render_pictures(mjcf: str | os.PathLike, out_dir: str | os.PathLike, flagged: set[str] = frozenset(),
                    joints: bool = True) -> list[Picture]:
    """Write the report's PNG pictures of the MJCF model into ``out_dir``; return them in order."""
    out = Path(out_dir)
    model = load_model(mjcf)
    p = Painter(model)
    p.flagged = set(flagged)
    pics: list[Picture] = []
    iso = SIDES[3]
    visual = {VISUAL: True}
    has_visual = bool((model.geom_group == VISUAL).any())
    if not has_visual:  # an MJCF not written by robotkit: draw what it has
        visual = {g: True for g in range(6)}
    try:
        for stem, title, az, el in SIDES:
            _save(p._draw(az, el, visual, ghost=False), out / f"{stem}.png")
            pics.append(Picture(f"{stem}.png", f"Visual, {title}", "the visual meshes and primitives", "view"))
        _save(p._draw(iso[2], iso[3], {VISUAL: True, COLLISION: True}, ghost=True), out / "collision.png")
        pics.append(Picture("collision.png", "Collision over the visual",
                            "collision geometry (blue) inside a ghost of the visual", "collision"))
        _save(p._draw(iso[2], iso[3], visual, ghost=True, overlays=(p.inertia_boxes, p.centres_of_mass)),
              out / "inertia.png")
        pics.append(Picture("inertia.png", "Inertia boxes and centres of mass",
                            "each link's equivalent inertia box (uniform box with its mass and principal "
                            "moments) and its centre of mass; red: a lint fired on the link", "inertia"))
        _save(p._draw(iso[2], iso[3], visual, ghost=True, overlays=(p.frames, p.joint_axes, p.sensors)),
              out / "frames.png")
        pics.append(Picture("frames.png", "Frames, joint axes and sensors",
                            "link frames (x red, y green, z blue), joint axes (yellow arrows), sensor "
                            "frames, rangefinder rays and camera fields of view", "frames"))
        if joints:
            pics += _joint_pictures(p, out, visual)
    finally:
        p.close()
    return pics


def _joint_pictures(p: Painter, out: Path, visual: dict) -> list[Picture]:
    pics = []
    joints = p.joint_poses()
    if not joints:
        return pics
    samples = p.model.vis.quality.offsamples
    p.model.vis.quality.offsamples = STRIP_SAMPLES  # read when the strips' renderer is made
    try:
        # the same model, smaller pictures for the strips, each strip drawn in one framebuffer
        size = BRIEF_STRIP_SIZE if len(joints) > BRIEF_JOINTS else STRIP_SIZE
        small = Painter(p.model, *size, data=p.data, panels=max(len(poses) for _, _, poses, _ in joints))
    finally:
        p.model.vis.quality.offsamples = samples
    small.flagged = p.flagged
    try:
        for name, kind, poses, caption in joints:
            points = []
            for _, q in poses:  # frame the joint's whole motion
                small.pose(q)
                points.append(corners(small.model, small.data))
            small.points = np.concatenate(points)
            lo, hi = small.points.min(0), small.points.max(0)
            small.center, small.radius = (lo + hi) / 2, max(float(np.linalg.norm(hi - lo)) / 2, 0.05)
            joint = small.model.joint(name)
            moved = [int(joint.bodyid[0])]  # its frame turns even where a round link looks the same
            # this joint's axis only: a strip draws one joint (and a long chain's strips stay cheap)
            overlays = (lambda scn: small.joint_axes(scn, [int(joint.id)]), lambda scn: small.frames(scn, moved, 0.3))
            pictures = small.strip([q for _, q in poses], 135.0, -25.0, visual, overlays)
            small.pose()
            file = "joint-" + re.sub(r"[^A-Za-z0-9_.-]", "_", name) + ".png"
            write_if_changed(out / file, png_bytes(_strip(pictures, [label for label, _ in poses])))
            pics.append(Picture(file, f"Joint {name}", f"{kind} joint {caption}; the link it moves shows its frame "
                                "(x red, y green, z blue)", "joint"))
    finally:
        small.renderer.close()
    return pics
