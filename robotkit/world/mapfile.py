"""Read a ROS map_server occupancy map: the YAML file and the PGM or PNG image it names.

The meaning follows nav2's ``nav2_map_server/src/map_io.cpp`` (ROS 2), which itself
keeps the ROS 1 map_server meaning:

* ``image`` is relative to the YAML file's folder (or absolute).
* The shade of a pixel is the mean of its R, G, B channels on a 0..1 scale (a grey
  image has R = G = B).  In ``trinary`` mode an alpha channel, when the image has one,
  is averaged in with the colours (255 = opaque), as nav2 does.
* ``occ = 1 - shade`` (``occ = shade`` when ``negate``).
* ``trinary``: ``occ > occupied_thresh`` -> occupied (100), ``occ < free_thresh`` ->
  free (0), else unknown (-1).
* ``scale``: a pixel that is not fully opaque is unknown; otherwise the same thresholds,
  and in between ``rint((occ - free) / (occupied - free) * 100)``.
* ``raw``: the grid value is the pixel value itself, ``round(shade * 255)``, when it is in
  0..100 and unknown otherwise (nav2 ignores ``negate`` in raw mode).

nav2 only publishes these values; which of them are walls is robotkit's reading:
a cell is *occupied* when its grid value is 100 (``trinary``, ``scale``) or, in ``raw``
mode, when ``value / 100 > occupied_thresh``; *free* when the value is 0 (``raw``:
``value / 100 < free_thresh``); anything else (-1, and the in-between values of ``scale``
and ``raw``) is *unknown*.

Every problem with the YAML and the image is collected and raised as one
:class:`~robotkit.errors.MapError`, each problem naming the file, the line of the key
and the key.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from robotkit.errors import MapError, Problem, display_path, yaml_syntax_problem
from robotkit.emit.env import fmt
from robotkit.paths import ReadPolicy
from robotkit.recipe.yamlsafe import yaml_limits

MODES = ("trinary", "scale", "raw")
REQUIRED = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")

OCCUPIED, FREE, UNKNOWN = 100, 0, -1
MAX_CELLS = 100_000_000  # largest image read (10,000 x 10,000): checked from the header, before decoding
IMAGE_SUFFIXES = (".pgm", ".png", ".bmp", ".ppm", ".pbm", ".jpg", ".jpeg", ".gif", ".tif", ".tiff")


@dataclass(frozen=True, eq=False)
class OccupancyMap:
    """A map_server map, read and checked.

    ``grid`` holds the nav_msgs/OccupancyGrid values nav2's map_server would publish
    (int8: 100 occupied, 0 free, -1 unknown, 1..99 in-between in ``scale``/``raw`` mode),
    in *image* order: ``grid[r, c]`` is the pixel in image row ``r`` (row 0 at the top),
    column ``c``.
    """

    yaml_path: Path
    image_path: Path
    resolution: float
    origin: tuple[float, float, float]  # x, y, yaw of the lower-left corner of the lower-left pixel
    negate: bool
    occupied_thresh: float
    free_thresh: float
    mode: str
    grid: np.ndarray
    image_name: str = ""  # the ``image`` value as written in the YAML
    image_line: int | None = None  # line of the ``image`` key in the YAML (for messages)

    @property
    def rows(self) -> int:
        return int(self.grid.shape[0])

    @property
    def cols(self) -> int:
        return int(self.grid.shape[1])

    @property
    def occupied(self) -> np.ndarray:
        """Boolean mask of occupied cells (image order)."""
        if self.mode == "raw":
            g = self.grid.astype(np.float64)
            return (self.grid >= 0) & (g / 100.0 > self.occupied_thresh)
        return self.grid == OCCUPIED

    @property
    def free(self) -> np.ndarray:
        """Boolean mask of free cells (image order)."""
        if self.mode == "raw":
            g = self.grid.astype(np.float64)
            return (self.grid >= 0) & (g / 100.0 < self.free_thresh)
        return self.grid == FREE

    @property
    def unknown(self) -> np.ndarray:
        """Cells that are neither occupied nor free."""
        return ~(self.occupied | self.free)

    def walls(self, unknown_as_wall: bool = False) -> np.ndarray:
        """The cells that become walls (image order)."""
        return ~self.free if unknown_as_wall else self.occupied

    def grid_to_map(self) -> np.ndarray:
        """3x3 affine matrix: grid coordinates (x = column, y = rows - image row, in cells) -> map frame (m).

        Grid point (0, 0) is the lower-left corner of the lower-left pixel, i.e. the
        map origin; the yaw of the origin rotates the grid about that point.
        """
        x, y, yaw = self.origin
        c, s = math.cos(yaw), math.sin(yaw)
        r = self.resolution
        return np.array([[r * c, -r * s, x], [r * s, r * c, y], [0.0, 0.0, 1.0]])

    def cell_centres(self, rows, cols) -> np.ndarray:
        """Map-frame (x, y) of the centres of the cells in image rows ``rows``, columns ``cols``.

        ``origin + R(yaw) . ((c + 0.5) res, (rows - 1 - r + 0.5) res)``.
        """
        rows = np.asarray(rows, dtype=np.float64)
        cols = np.asarray(cols, dtype=np.float64)
        gx = cols + 0.5
        gy = (self.rows - 1 - rows) + 0.5
        m = self.grid_to_map()
        return np.stack([m[0, 0] * gx + m[0, 1] * gy + m[0, 2], m[1, 0] * gx + m[1, 1] * gy + m[1, 2]], axis=-1)

    def problem(self, message: str) -> Problem:
        """A problem with the map's image, located at the YAML's ``image`` key."""
        return Problem(message, file=str(self.yaml_path), line=self.image_line, key="image")


# ---------------------------------------------------------------- YAML


def _read_yaml(yaml_path: Path, problems: list[Problem]):
    """Return ({key: value}, {key: line}) or (None, {}) after recording the problem."""
    import yaml

    file = str(yaml_path)
    try:
        text = yaml_path.read_text(encoding="utf-8")
    except FileNotFoundError:
        problems.append(Problem("file does not exist", file=file))
        return None, {}
    except IsADirectoryError:
        problems.append(Problem("is a folder, not a map YAML file", file=file))
        return None, {}
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        problems.append(Problem(f"cannot read file: {reason}", file=file))
        return None, {}
    limit = yaml_limits(text)  # nesting and alias bombs, before the (recursive) composer sees them
    if limit is not None:
        problems.append(Problem(limit[0], file=file, line=limit[1]))
        return None, {}
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError as exc:
        problems.append(yaml_syntax_problem(exc, file))
        return None, {}
    if not isinstance(node, yaml.MappingNode):
        problems.append(Problem("a map YAML file must be a mapping of map_server keys "
                                f"({', '.join(REQUIRED)}, mode)", file=file, line=1))
        return None, {}
    constructor = yaml.SafeLoader("")
    data: dict = {}
    lines: dict = {}
    for key_node, value_node in node.value:
        key = str(key_node.value) if isinstance(key_node, yaml.ScalarNode) else None
        line = key_node.start_mark.line + 1
        if key is None:
            problems.append(Problem("mapping keys must be plain names", file=file, line=line))
            continue
        if key in data:
            problems.append(Problem(f"duplicate key (first given on line {lines[key]})", file=file, line=line, key=key))
            continue
        try:
            data[key] = constructor.construct_object(value_node, deep=True)
        except yaml.YAMLError as exc:
            problems.append(Problem(f"invalid value: {getattr(exc, 'problem', exc)}", file=file, line=line, key=key))
            data[key] = None
        lines[key] = line
    return data, lines


def _number(value) -> float | None:
    """A YAML scalar as a float the way yaml-cpp's ``as<double>`` reads it (``1e-2`` too), or None."""
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return float(value)
    if isinstance(value, str):
        try:
            return float(value.strip())
        except ValueError:
            return None
    return None


def _show(value) -> str:
    text = repr(value) if isinstance(value, str) else str(value)
    if isinstance(value, bool):
        text = "true" if value else "false"
    elif value is None:
        text = "null"
    return text if len(text) <= 40 else text[:37] + "..."


def load_map(map_yaml: str | os.PathLike) -> OccupancyMap:
    """Read and check a map_server YAML file and its image; raise MapError with every problem."""
    yaml_path = Path(map_yaml)
    file = str(yaml_path)
    problems: list[Problem] = []
    data, lines = _read_yaml(yaml_path, problems)
    if data is None:
        raise MapError(problems)

    def bad(key: str, message: str):
        problems.append(Problem(message, file=file, line=lines.get(key), key=key))

    for key in REQUIRED:
        if key not in data:
            problems.append(Problem("missing (map_server requires this key)", file=file, key=key))
    image = data.get("image")
    image_path = _image_path(data, yaml_path, bad)  # decoded below, once the other keys are read
    resolution = _resolution(data, bad)
    origin = _origin(data, bad)
    negate = _negate(data, bad)
    occ_th, free_th = _thresholds(data, bad)
    mode = _mode(data, bad)
    pixels = None
    if image_path is not None:
        pixels = _read_image(image_path, image, lambda msg: bad("image", msg))
    if problems:
        raise MapError(problems)
    grid = classify(pixels, mode=mode, negate=negate, occupied_thresh=occ_th, free_thresh=free_th)
    return OccupancyMap(yaml_path=yaml_path, image_path=image_path, resolution=resolution, origin=origin,
                        negate=negate, occupied_thresh=occ_th, free_thresh=free_th, mode=mode, grid=grid,
                        image_name=image, image_line=lines.get("image"))


# Each key's reading below: its value, or None after ``bad(key, message)`` (or when absent).


def _image_path(data: dict, yaml_path: Path, bad) -> Path | None:
    """The image file ``image`` names (relative to the YAML file's folder), where it may be read."""
    if "image" not in data:
        return None
    image = data["image"]
    if not isinstance(image, str) or not image.strip():
        bad("image", f"must be the image file name (PGM or PNG), not {_show(image)}")
        return None
    image_path = Path(image) if os.path.isabs(image) else yaml_path.parent / image
    if (why := ReadPolicy.for_file(yaml_path).refusal(image_path)) is not None:
        bad("image", f"image file '{image}' {why}")
        return None
    return image_path


def _resolution(data: dict, bad) -> float | None:
    if "resolution" not in data:
        return None
    resolution = _number(data["resolution"])
    if resolution is None:
        bad("resolution", f"must be a number (metres per cell), not {_show(data['resolution'])}")
    elif not math.isfinite(resolution):
        bad("resolution", "must be a finite number")
        resolution = None
    elif resolution <= 0:
        bad("resolution", "must be > 0")
        resolution = None
    return resolution


def _origin(data: dict, bad) -> tuple | None:
    if "origin" not in data:
        return None
    raw = data["origin"]
    values = [_number(v) for v in raw] if isinstance(raw, list) else None
    if values is None or len(values) != 3 or any(v is None or not math.isfinite(v) for v in values):
        bad("origin", f"must be [x, y, yaw]: three numbers, not {_show(raw)}")
        return None
    return tuple(values)


def _negate(data: dict, bad) -> bool | None:
    if "negate" not in data:
        return None
    raw = data["negate"]
    if isinstance(raw, bool):
        return raw
    if isinstance(raw, int) and raw in (0, 1):
        return bool(raw)
    bad("negate", f"must be 0 or 1, not {_show(raw)}")
    return None


def _thresholds(data: dict, bad) -> tuple[float | None, float | None]:
    """(occupied_thresh, free_thresh), each between 0 and 1, free below occupied."""
    thresholds = {}
    for key in ("occupied_thresh", "free_thresh"):
        if key not in data:
            continue
        value = _number(data[key])
        if value is None:
            bad(key, f"must be a number between 0 and 1, not {_show(data[key])}")
        elif not 0.0 <= value <= 1.0:
            bad(key, "must be between 0 and 1")
        else:
            thresholds[key] = value
    occ_th, free_th = thresholds.get("occupied_thresh"), thresholds.get("free_thresh")
    if occ_th is not None and free_th is not None and not free_th < occ_th:
        bad("free_thresh", f"must be below occupied_thresh ({fmt(occ_th)})")
    return occ_th, free_th


def _mode(data: dict, bad) -> str | None:
    """``mode``: trinary when absent."""
    if "mode" not in data:
        return "trinary"
    raw = data["mode"]
    if raw not in MODES:
        bad("mode", f"must be trinary, scale or raw, not {_show(raw)}")
        return None
    return raw


# ---------------------------------------------------------------- image


def _read_image(path: Path, name: str, bad) -> tuple[np.ndarray, np.ndarray | None] | None:
    """Decode ``path``: (colour channels as float64 (rows, cols, n), alpha (rows, cols) or None)."""
    from PIL import Image, UnidentifiedImageError

    if not path.exists():
        folder = display_path(path.parent).rstrip("/") + "/"
        bad(f"file '{name}' does not exist (looked in {folder}{_did_you_mean(path)})")
        return None
    if not path.is_file():
        bad(f"'{name}' is not a file")
        return None
    size = None
    try:
        if path.stat().st_size == 0:
            bad(f"cannot read '{name}': the file is empty")
            return None
        with _open_header(Image, path) as im:
            size = im.size
            if size[0] * size[1] > MAX_CELLS:
                bad(f"'{name}' is {size[0]} x {size[1]} pixels, more than robotkit reads "
                    f"({MAX_CELLS:,} pixels; crop or downsample the map)")
                return None
            colours, alpha, mode = _raw_grey(im, path), None, ""  # a binary PGM: nearly every map
            if colours is None:
                im.load()
                mode = im.mode
            if mode == "L":  # other 8-bit grey images: the bytes as they are (classify's table)
                colours = np.asarray(im)[..., None]
                mode = ""
            if mode in ("1", "P", "PA", "CMYK", "YCbCr", "LAB", "HSV", "La", "RGBa", "RGBX"):
                has_alpha = mode in ("PA", "La", "RGBa") or "transparency" in im.info
                im = im.convert("RGBA" if has_alpha else ("L" if mode == "1" else "RGB"))
                mode = im.mode
            if not mode:
                pass
            elif mode.startswith("I;16") or mode == "I":
                colours = np.asarray(im, dtype=np.float64)[..., None] / 65535.0
                alpha = None
            elif mode == "F":
                colours = np.asarray(im, dtype=np.float64)[..., None] / 255.0
                alpha = None
            else:
                a = np.asarray(im, dtype=np.float64) / 255.0
                if a.ndim == 2:
                    a = a[..., None]
                if mode in ("LA", "RGBA"):
                    colours, alpha = a[..., :-1], a[..., -1]
                else:
                    colours, alpha = a, None
    except UnidentifiedImageError:
        bad(f"cannot read '{name}': not an image (map_server reads PGM or PNG)")
        return None
    except (OSError, ValueError, SyntaxError) as exc:
        reason = str(exc).replace(str(path), f"'{name}'") or type(exc).__name__
        if "truncated" in reason and size is not None:
            reason = f"the pixel data is truncated (its header announces {size[0]} x {size[1]} pixels)"
        elif isinstance(exc, PermissionError):
            reason = "permission denied"
        bad(f"cannot read '{name}': {reason}")
        return None
    if colours.shape[0] == 0 or colours.shape[1] == 0:
        bad(f"'{name}' has no pixels")
        return None
    return colours, alpha


def _raw_grey(im, path: Path) -> np.ndarray | None:
    """The pixels of an uncompressed 8-bit grey image (a binary PGM: nearly every map) as
    (rows, cols, 1) uint8, read straight from the file at the offset Pillow's header parser
    found; None for any other image, or a file shorter than its header says (Pillow then
    decodes it and reports what is wrong).

    Pillow would map the file and copy it into a ``bytes`` for numpy; one read into a numpy
    array costs 12 times fewer page faults on a 5000 x 5000 map (numpy's large arrays get
    huge pages).
    """
    if im.mode != "L" or len(im.tile) != 1:
        return None
    codec, extents, offset, args = tuple(im.tile[0])[:4]
    rawmode, layout = (args, ()) if isinstance(args, str) else (args[0] if args else None, tuple(args[1:]))
    cols, rows = im.size
    if codec != "raw" or tuple(extents) != (0, 0, cols, rows) or rawmode != "L" or layout not in ((), (0,), (0, 1)):
        return None
    data = np.fromfile(path, dtype=np.uint8, count=rows * cols, offset=offset)
    return data.reshape(rows, cols, 1) if data.size == rows * cols else None


def _open_header(Image, path: Path):
    """``Image.open`` (which reads the header only) without Pillow's decompression-bomb check:
    the size is checked against :data:`MAX_CELLS` before decoding, into one clean problem."""
    import warnings

    limit = Image.MAX_IMAGE_PIXELS
    Image.MAX_IMAGE_PIXELS = None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            return Image.open(path)
    finally:
        Image.MAX_IMAGE_PIXELS = limit


def _did_you_mean(path: Path) -> str:
    """``; did you mean 'x.pgm'?`` naming the closest image file in the same folder, if any."""
    import difflib

    try:
        names = [p.name for p in path.parent.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES and p.is_file()]
    except OSError:
        return ""
    close = difflib.get_close_matches(path.name, sorted(names), n=1, cutoff=0.6)
    return f"; did you mean '{close[0]}'?" if close else ""


def classify(pixels, *, mode: str, negate: bool, occupied_thresh: float, free_thresh: float) -> np.ndarray:
    """nav2 map_io: pixels -> OccupancyGrid values (int8, image order).

    8-bit single-channel pixels without alpha (``uint8``) go through a table of the 256
    values, made by this same function on the 256 shades as floats: the same result, one
    byte per cell instead of several float64 arrays.
    """
    colours, alpha = pixels
    if colours.dtype == np.uint8 and colours.shape[-1] == 1 and alpha is None:
        shades = (np.arange(256, dtype=np.float64) / 255.0).reshape(256, 1, 1)
        table = classify((shades, None), mode=mode, negate=negate, occupied_thresh=occupied_thresh,
                         free_thresh=free_thresh).reshape(256)
        return table[colours[..., 0]]
    channels = colours.shape[-1]
    rgb_mean = colours.mean(axis=-1) if channels > 1 else colours[..., 0]
    if mode == "raw":
        value = np.round(rgb_mean * 255.0)
        return np.where((value >= 0) & (value <= 100), value, UNKNOWN).astype(np.int8)
    if mode == "trinary" and alpha is not None:
        # nav2 averages alpha in with R, G, B (a grey image counts as three equal channels)
        shade = (rgb_mean * 3.0 + alpha) / 4.0
    else:
        shade = rgb_mean
    occ = shade if negate else 1.0 - shade
    grid = np.full(occ.shape, UNKNOWN, dtype=np.int8)
    if mode == "scale":
        between = np.rint((occ - free_thresh) / (occupied_thresh - free_thresh) * 100.0)
        grid[:] = np.clip(between, 0, 100).astype(np.int8)
    grid[occ > occupied_thresh] = OCCUPIED
    grid[occ < free_thresh] = FREE
    if mode == "scale" and alpha is not None:
        grid[alpha < 1.0] = UNKNOWN
    return grid
