"""Worlds from occupancy maps: map_server semantics, an exact closed wall mesh, the five
output files (validated by `ign sdf -k` and MuJoCo), and bad input word for word."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
import trimesh
from PIL import Image

from conftest import ASSETS, REPO, run_cli
from robotkit.errors import MapError
from robotkit.world import build_world, load_map, wall_mesh
from robotkit.world.walls import extrude, rectangles, wall_cells
from validators import ign_sdf_check, mujoco

MAPS = ASSETS / "maps"
KEYS = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")


# ---------------------------------------------------------------- helpers


def write_map(folder, pixels, name="map", image=None, mode=None, **keys):
    """Write ``name``.yaml and its image (``pixels``: an array or a PIL image) into ``folder``.

    The YAML keys come one per line in the order of KEYS (then ``mode``), so line numbers
    are known: image 1, resolution 2, origin 3, negate 4, occupied_thresh 5, free_thresh 6.
    """
    folder.mkdir(parents=True, exist_ok=True)
    image = image or f"{name}.pgm"
    if pixels is not None:
        im = pixels if isinstance(pixels, Image.Image) else Image.fromarray(np.asarray(pixels, dtype=np.uint8))
        im.save(folder / image)
    values = {"image": image, "resolution": 0.05, "origin": "[0.0, 0.0, 0.0]", "negate": 0,
              "occupied_thresh": 0.65, "free_thresh": 0.196}
    values.update(keys)
    lines = [f"{k}: {values[k]}" for k in KEYS if values.get(k) is not None]
    if mode is not None:
        lines.append(f"mode: {mode}")
    path = folder / f"{name}.yaml"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def asset_yaml(tmp_path, which: str):
    """The YAML of an assets map (nav2_empty_room's names a missing image: use its real files)."""
    if which.startswith("empty_room."):
        return write_map(tmp_path, None, name=which.replace(".", "_"), image=str(MAPS / "nav2_empty_room" / which),
                         resolution=0.1, origin="[-10.0, -10.0, 0.0]")
    return MAPS / which


def rooms_map(rows=120, cols=160, seed=7):
    """A map that is not in the assets: rooms with doors, a diagonal wall, pinches, unknown patches."""
    rng = np.random.default_rng(seed)
    img = np.full((rows, cols), 254, dtype=np.uint8)
    img[:3, :] = img[-3:, :] = img[:, :3] = img[:, -3:] = 0
    img[:, cols // 2:cols // 2 + 2] = 0
    img[rows // 2, :] = 0
    img[rows // 2, cols // 8:cols // 5] = 254  # a door
    img[rows // 12:rows // 3, cols // 2:cols // 2 + 2] = 254  # another
    steps = max(0, min(rows // 2 - 8, cols - 10))
    for k in range(steps):  # a staircase wall: every step touches the next at a corner
        img[rows // 2 + 4 + k, 5 + k] = 0
    img[rows * 2 // 3:rows * 4 // 5, cols * 5 // 8:cols * 4 // 5] = 205  # unknown
    img[rng.random((rows, cols)) < 0.01] = 0
    return img


def box_faces(n_cells: int) -> int:
    return 12 * n_cells


def centres_by_formula(om, rows, cols):
    """origin + R(yaw) . ((c + 0.5) res, (rows - 1 - r + 0.5) res), written out independently."""
    x0, y0, yaw = om.origin
    res = om.resolution
    u = (np.asarray(cols) + 0.5) * res
    v = (om.rows - 1 - np.asarray(rows) + 0.5) * res
    return np.stack([x0 + math.cos(yaw) * u - math.sin(yaw) * v, y0 + math.sin(yaw) * u + math.cos(yaw) * v], axis=-1)


def footprint(mesh, om):
    """Winding number of the mesh's outline around every cell centre (image order), exactly.

    The outline is read off the mesh itself: the bottom edges of its side faces, mapped back
    to grid coordinates.  Every face must be a side face or a cap at z = 0 or z = height.
    """
    v = mesh.vertices
    n = mesh.face_normals
    z = v[:, 2]
    side = np.abs(n[:, 2]) < 1e-9
    caps = ~side
    cap_z = z[mesh.faces[caps]]
    assert ((np.abs(n[caps, 2]) > 1 - 1e-9)).all()
    assert ((cap_z == 0).all(axis=1) | (cap_z == cap_z.max()).all(axis=1)).all()
    inv = np.linalg.inv(om.grid_to_map())
    g = v[:, :2] @ inv[:2, :2].T + inv[:2, 2]
    edges = mesh.faces[side][:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    edges = edges[(z[edges[:, 0]] == 0) & (z[edges[:, 1]] == 0)]
    a, b = g[edges[:, 0]], g[edges[:, 1]]
    ai, bi = np.rint(a).astype(np.int64), np.rint(b).astype(np.int64)
    assert np.abs(a - ai).max() < 1e-6 and np.abs(b - bi).max() < 1e-6
    assert ((ai[:, 0] == bi[:, 0]) | (ai[:, 1] == bi[:, 1])).all(), "outline edges run along the grid"
    vert = ai[:, 0] == bi[:, 0]
    x, ya, yb = ai[vert, 0], ai[vert, 1], bi[vert, 1]
    north = np.sign(yb - ya)
    d = np.zeros((om.rows + 1, om.cols + 2), dtype=np.int64)
    np.add.at(d, (np.minimum(ya, yb), x), -north)
    np.add.at(d, (np.maximum(ya, yb), x), north)
    winding = d.cumsum(axis=0).cumsum(axis=1)[:om.rows, :om.cols]
    return winding[::-1]


def assert_closed_mesh(mesh):
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.is_volume
    assert len(np.unique(np.sort(mesh.faces, axis=1), axis=0)) == len(mesh.faces), "duplicate faces"
    assert (mesh.area_faces > 0).all(), "degenerate faces"
    merged = trimesh.Trimesh(mesh.vertices, mesh.faces)  # as reloaded from STL: vertices merged
    assert merged.is_watertight and merged.is_winding_consistent and merged.is_volume


def sample_cells(mask, n, seed=0):
    """Every kind of cell: wall cells, non-wall cells next to a wall, others; up to n of each."""
    rng = np.random.default_rng(seed)
    pad = np.pad(mask, 1)
    near = (pad[:-2, 1:-1] | pad[2:, 1:-1] | pad[1:-1, :-2] | pad[1:-1, 2:]) & ~mask
    picks = []
    for kind in (mask, near, ~mask & ~near):
        r, c = np.nonzero(kind)
        sel = rng.choice(len(r), min(n, len(r)), replace=False)
        picks.append((r[sel], c[sel]))
    return np.concatenate([p[0] for p in picks]), np.concatenate([p[1] for p in picks])


# ---------------------------------------------------------------- the assets maps

ASSET_MAPS = ["turtlebot3_world/map.yaml", "nav2_warehouse/warehouse.yaml", "empty_room.pgm", "empty_room.png"]


@pytest.fixture(scope="module")
def asset_meshes(tmp_path_factory):
    if not MAPS.is_dir():
        pytest.fail(f"test assets not found at {MAPS} (CI clones the repository next to shared/)")
    folder = tmp_path_factory.mktemp("maps")
    out = {}
    for which in ASSET_MAPS:
        om = load_map(asset_yaml(folder, which))
        out[which] = (om, wall_mesh(om, 2.0))
    return out


def test_assets_maps_read_as_map_server_reads_them(asset_meshes):
    for which, (om, _) in asset_meshes.items():
        pixels = np.asarray(Image.open(om.image_path), dtype=np.float64)
        p = (255 - pixels) / 255
        np.testing.assert_array_equal(om.occupied, p > 0.65, err_msg=which)
        np.testing.assert_array_equal(om.free, p < om.free_thresh, err_msg=which)
    counts = {w: (om.cols, om.rows, int(om.occupied.sum())) for w, (om, _) in asset_meshes.items()}
    assert counts == {"turtlebot3_world/map.yaml": (384, 384, 795),
                      "nav2_warehouse/warehouse.yaml": (1006, 1674, 30951),
                      "empty_room.pgm": (200, 200, 396), "empty_room.png": (200, 200, 396)}


@pytest.mark.parametrize("which", ASSET_MAPS)
def test_assets_mesh_is_closed_with_exact_volume(asset_meshes, which):
    om, mesh = asset_meshes[which]
    assert_closed_mesh(mesh)
    expected = om.occupied.sum() * om.resolution ** 2 * 2.0
    assert mesh.volume == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("which", ASSET_MAPS)
def test_assets_mesh_outline_is_the_occupied_cells_exactly(asset_meshes, which):
    om, mesh = asset_meshes[which]
    np.testing.assert_array_equal(footprint(mesh, om), om.occupied.astype(np.int64))


@pytest.mark.parametrize("which", ASSET_MAPS)
def test_assets_cell_centres_inside_iff_occupied(asset_meshes, which):
    """3D point containment at the cell centres given by the ROS formula (sampled)."""
    om, mesh = asset_meshes[which]
    r, c = sample_cells(om.occupied, 1500)
    xy = centres_by_formula(om, r, c)
    inside = mesh.contains(np.column_stack([xy, np.full(len(xy), 0.7)]))
    np.testing.assert_array_equal(inside, om.occupied[r, c])


@pytest.mark.parametrize("which", ASSET_MAPS)
def test_assets_rectangles_cover_the_occupied_cells_once(asset_meshes, which):
    """The MuJoCo collision boxes: every occupied cell in exactly one rectangle, nothing else."""
    om, _ = asset_meshes[which]
    rects = rectangles(wall_cells(om))
    cover = np.zeros((om.rows + 1, om.cols + 1), dtype=np.int64)
    x0, y0, x1, y1 = rects.T
    for ys, xs, s in ((y0, x0, 1), (y0, x1, -1), (y1, x0, -1), (y1, x1, 1)):
        np.add.at(cover, (ys, xs), s)
    cover = cover.cumsum(0).cumsum(1)[:om.rows, :om.cols][::-1]
    np.testing.assert_array_equal(cover, om.occupied.astype(np.int64))


def test_warehouse_has_at_most_a_tenth_of_the_faces_of_one_box_per_cell(asset_meshes):
    om, mesh = asset_meshes["nav2_warehouse/warehouse.yaml"]
    assert len(mesh.faces) <= box_faces(int(om.occupied.sum())) / 10
    _, rect_faces = extrude(wall_cells(om), 2.0, method="rectangles")
    assert len(mesh.faces) <= len(rect_faces)


# ---------------------------------------------------------------- the mesher on many masks


def random_masks():
    rng = np.random.default_rng(2024)
    for _ in range(150):
        rows, cols = rng.integers(1, 16, 2)
        mask = rng.random((rows, cols)) < rng.random()
        if mask.any():
            yield mask
    yield np.add.outer(np.arange(9), np.arange(7)) % 2 == 0  # a checkerboard: every inner corner a pinch
    ring = np.ones((9, 9), dtype=bool)
    ring[1:-1, 1:-1] = False
    ring[3, 3] = ring[4, 4] = ring[5, 3] = True  # islands inside a hole, touching by corners
    yield ring


@pytest.mark.slow
@pytest.mark.parametrize("method", ["outline", "rectangles"])
def test_mesher_is_exact_on_random_masks(method):
    for mask in random_masks():
        v, f = extrude(mask, 1.5, method=method)
        mesh = trimesh.Trimesh(v, f, process=False)
        assert_closed_mesh(mesh)
        assert mesh.volume == pytest.approx(mask.sum() * 1.5, rel=1e-12)
        rows, cols = np.nonzero(np.ones_like(mask))
        inside = mesh.contains(np.column_stack([cols + 0.5, rows + 0.5, np.full(len(rows), 0.4)]))
        np.testing.assert_array_equal(inside, mask[rows, cols])


def test_cells_touching_by_a_corner_survive_an_stl_round_trip(tmp_path):
    img = np.full((4, 4), 254, dtype=np.uint8)
    img[1, 1] = img[2, 2] = 0
    om = load_map(write_map(tmp_path, img))
    mesh = wall_mesh(om, 1.0)
    path = tmp_path / "pinch.stl"
    mesh.export(path)
    back = trimesh.load(path)
    assert back.is_watertight and back.is_winding_consistent and back.is_volume
    assert back.volume == pytest.approx(2 * 0.05 ** 2, rel=1e-6)


# ---------------------------------------------------------------- map frame, yaw


def test_yawed_origin_places_every_cell_by_the_ros_formula(tmp_path):
    img = rooms_map(40, 30)
    om = load_map(write_map(tmp_path, img, resolution=0.1, origin="[1.5, -2.25, 0.3]"))
    mesh = wall_mesh(om, 2.0)
    assert_closed_mesh(mesh)
    assert mesh.volume == pytest.approx(om.occupied.sum() * 0.01 * 2.0, rel=1e-9)
    rows, cols = np.nonzero(np.ones(img.shape, dtype=bool))
    xy = centres_by_formula(om, rows, cols)
    np.testing.assert_allclose(om.cell_centres(rows, cols), xy, rtol=0, atol=1e-12)
    inside = mesh.contains(np.column_stack([xy, np.full(len(xy), 1.0)]))
    np.testing.assert_array_equal(inside, om.occupied[rows, cols])
    np.testing.assert_array_equal(footprint(mesh, om), om.occupied.astype(np.int64))
    # the lower-left corner of the lower-left pixel is the origin
    grid_origin = om.grid_to_map() @ [0, 0, 1]
    np.testing.assert_allclose(grid_origin[:2], [1.5, -2.25], atol=1e-15)


def test_zero_yaw_keeps_vertices_on_the_exact_grid(tmp_path):
    img = np.full((5, 6), 254, dtype=np.uint8)
    img[1:3, 2:5] = 0
    om = load_map(write_map(tmp_path, img, resolution=0.25, origin="[-1.0, 2.0, 0.0]"))
    mesh = wall_mesh(om, 2.0)
    # image rows 1..2 are grid rows 2..3 (5 rows): walls span x in [-1 + 2*0.25, -1 + 5*0.25], y in [2 + 0.5, 2 + 1.0]
    np.testing.assert_array_equal(mesh.bounds, [[-0.5, 2.5, 0.0], [0.25, 3.0, 2.0]])


# ---------------------------------------------------------------- map_server semantics

GREYS = [0, 50, 100, 150, 200, 205, 230, 254, 255]


def one_row(values):
    return np.array([values], dtype=np.uint8)


def test_trinary_thresholds(tmp_path):
    om = load_map(write_map(tmp_path, one_row(GREYS)))
    assert om.mode == "trinary"
    assert om.grid.tolist() == [[100, 100, -1, -1, -1, -1, 0, 0, 0]]  # 205 -> p = 0.19608 > 0.196: unknown


def test_negate_swaps_black_and_white(tmp_path):
    om = load_map(write_map(tmp_path, one_row(GREYS), negate=1))
    assert om.grid.tolist() == [[0, -1, -1, -1, 100, 100, 100, 100, 100]]


def test_scale_mode_keeps_in_between_values_and_they_are_not_walls(tmp_path):
    om = load_map(write_map(tmp_path, one_row(GREYS), mode="scale"))
    between = [round((p - 0.196) / (0.65 - 0.196) * 100) for p in ((255 - v) / 255 for v in (100, 150, 200, 205))]
    assert om.grid.tolist() == [[100, 100, *between, 0, 0, 0]]
    assert om.occupied.tolist() == [[True, True] + [False] * 7]
    # 205: p = 0.19608, just above free_thresh, scales to rint(0.02) = 0, which is FREE in the grid
    assert between[-1] == 0
    assert om.unknown.tolist() == [[False, False] + [True] * 3 + [False] * 4]


def test_scale_mode_treats_transparent_pixels_as_unknown(tmp_path):
    rgba = np.array([[[0, 0, 0, 255], [0, 0, 0, 128], [255, 255, 255, 0], [255, 255, 255, 255]]], dtype=np.uint8)
    om = load_map(write_map(tmp_path, Image.fromarray(rgba, "RGBA"), image="map.png", mode="scale"))
    assert om.grid.tolist() == [[100, -1, -1, 0]]


def test_trinary_mode_averages_alpha_in_like_nav2(tmp_path):
    # (R + G + B + A) / 4: white but transparent -> shade 0.75, p = 0.25: unknown
    rgba = np.array([[[0, 0, 0, 255], [255, 255, 255, 0], [255, 255, 255, 255], [0, 0, 0, 0]]], dtype=np.uint8)
    om = load_map(write_map(tmp_path, Image.fromarray(rgba, "RGBA"), image="map.png"))
    assert om.grid.tolist() == [[100, -1, 0, 100]]


def test_colour_pixels_are_averaged(tmp_path):
    rgb = np.array([[[255, 0, 0], [255, 255, 0], [255, 255, 255], [0, 0, 0]]], dtype=np.uint8)
    om = load_map(write_map(tmp_path, Image.fromarray(rgb, "RGB"), image="map.png"))
    assert om.grid.tolist() == [[100, -1, 0, 100]]  # p = 2/3 > 0.65; p = 1/3 unknown


def test_raw_mode_uses_pixel_values_as_occupancy(tmp_path):
    om = load_map(write_map(tmp_path, one_row([0, 50, 65, 66, 100, 101, 255]), mode="raw"))
    assert om.grid.tolist() == [[0, 50, 65, 66, 100, -1, -1]]
    assert om.occupied.tolist() == [[False, False, False, True, True, False, False]]  # value / 100 > 0.65
    assert om.free.tolist() == [[True, False, False, False, False, False, False]]  # value / 100 < 0.196


def test_png_and_pgm_of_the_same_map_give_the_same_grid(tmp_path):
    a = load_map(asset_yaml(tmp_path, "empty_room.pgm"))
    b = load_map(asset_yaml(tmp_path, "empty_room.png"))
    np.testing.assert_array_equal(a.grid, b.grid)


def test_unknown_cells_are_free_unless_asked(tmp_path):
    img = np.full((6, 8), 254, dtype=np.uint8)
    img[0, :] = 0
    img[2:4, 2:5] = 205
    om = load_map(write_map(tmp_path, img))
    assert wall_mesh(om, 1.0).volume == pytest.approx(8 * 0.05 ** 2, rel=1e-12)
    assert wall_mesh(om, 1.0, unknown_as_wall=True).volume == pytest.approx(14 * 0.05 ** 2, rel=1e-12)


# ---------------------------------------------------------------- outputs

FILES = ["model.config", "model.sdf", "meshes/rooms.stl", "rooms.world", "scene.xml"]


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    folder = tmp_path_factory.mktemp("world")
    yaml_path = write_map(folder / "maps", rooms_map(), name="rooms", resolution=0.05, origin="[-2.0, -3.0, 0.3]")
    paths = build_world(yaml_path, folder / "out", height=1.0)
    return yaml_path, folder / "out" / "rooms", paths


def test_writes_the_five_files(built):
    _, out, paths = built
    assert paths == [out / f for f in FILES]
    assert all(p.is_file() for p in paths)


def test_world_and_model_pass_ign_sdf(built):
    _, out, _ = built
    ign_sdf_check(out / "rooms.world")
    ign_sdf_check(out / "model.sdf")


def test_model_folder_references(built):
    _, out, _ = built
    sdf = (out / "model.sdf").read_text()
    assert "<static>true</static>" in sdf and sdf.count("<uri>model://rooms/meshes/rooms.stl</uri>") == 2
    assert '<sdf version="1.9">model.sdf</sdf>' in (out / "model.config").read_text()
    world = (out / "rooms.world").read_text()
    assert "<uri>meshes/rooms.stl</uri>" in world and "model://" not in world  # loads without a model path


def test_stl_is_binary_closed_and_in_the_map_frame(built):
    yaml_path, out, _ = built
    data = (out / "meshes" / "rooms.stl").read_bytes()
    assert not data.startswith(b"solid") and len(data) == 84 + 50 * int.from_bytes(data[80:84], "little")
    back = trimesh.load(out / "meshes" / "rooms.stl")
    assert back.is_watertight and back.is_winding_consistent and back.is_volume
    om = load_map(yaml_path)
    assert back.volume == pytest.approx(om.occupied.sum() * 0.05 ** 2 * 1.0, rel=1e-5)  # float32 STL
    np.testing.assert_allclose(back.bounds, wall_mesh(om, 1.0).bounds, atol=1e-5)


def test_scene_loads_in_mujoco_and_walls_collide(built):
    mj = mujoco()
    yaml_path, out, _ = built
    model = mj.MjModel.from_xml_path(str(out / "scene.xml"))
    data = mj.MjData(model)
    for _ in range(10):
        mj.mj_step(model, data)
    # drop balls on a wall cell and on a free cell (centres by the ROS formula, yaw 0.3)
    om = load_map(yaml_path)
    wall, free = (1, 60), (30, 40)  # image (row, column): the top wall, a free cell in a room
    assert om.occupied[wall] and om.free[free]
    spec = mj.MjSpec.from_file(str(out / "scene.xml"))
    for i, cell in enumerate((wall, free)):
        x, y = centres_by_formula(om, *cell)
        body = spec.worldbody.add_body(name=f"ball{i}", pos=[x, y, 1.5])
        body.add_freejoint()
        body.add_geom(type=mj.mjtGeom.mjGEOM_SPHERE, size=[0.02, 0, 0])
    model = spec.compile()
    data = mj.MjData(model)
    for _ in range(1500):
        mj.mj_step(model, data)
    z_wall, z_free = data.body("ball0").xpos[2], data.body("ball1").xpos[2]
    assert z_wall == pytest.approx(1.0 + 0.02, abs=2e-3)
    assert z_free == pytest.approx(0.02, abs=2e-3)


def test_rebuild_rewrites_nothing_and_is_byte_identical(built, tmp_path):
    yaml_path, out, paths = built
    before = {p: (p.stat().st_mtime_ns, p.read_bytes()) for p in paths}
    build_world(yaml_path, out.parent, height=1.0)
    assert {p: (p.stat().st_mtime_ns, p.read_bytes()) for p in paths} == before
    other = build_world(yaml_path, tmp_path / "elsewhere", height=1.0)
    assert [p.read_bytes() for p in other] == [before[p][1] for p in paths]


def test_name_and_height(tmp_path):
    yaml_path = write_map(tmp_path, rooms_map(20, 20), name="small")
    paths = build_world(yaml_path, tmp_path / "out", name="lab_2", height=3.0)
    assert [p.relative_to(tmp_path / "out").as_posix() for p in paths] == [
        "lab_2/model.config", "lab_2/model.sdf", "lab_2/meshes/lab_2.stl", "lab_2/lab_2.world", "lab_2/scene.xml"]
    assert trimesh.load(paths[2]).bounds[1, 2] == pytest.approx(3.0)


# ---------------------------------------------------------------- bad input, word for word


def errors(yaml_path, **kwargs):
    with pytest.raises(MapError) as info:
        build_world(yaml_path, yaml_path.parent / "out", **kwargs)
    assert not (yaml_path.parent / "out").exists(), "nothing may be written on error"
    return info.value.lines()


def test_nav2_empty_room_names_a_missing_image(monkeypatch):
    monkeypatch.chdir(MAPS)
    with pytest.raises(MapError) as info:
        load_map("nav2_empty_room/empty_room.yaml")
    assert info.value.lines() == ["nav2_empty_room/empty_room.yaml:1: image: file 'empty.pgm' does not exist "
                                  "(looked in nav2_empty_room/; did you mean 'empty_room.pgm'?)"]


def test_missing_image(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = write_map(tmp_path / "maps", None, name="x", image="nothere.pgm")
    assert errors(path) == ["maps/x.yaml:1: image: file 'nothere.pgm' does not exist (looked in maps/)"]


@pytest.mark.parametrize("content, message", [
    (b"garbage\n", "cannot read 'bad.pgm': not an image (map_server reads PGM or PNG)"),
    (b"", "cannot read 'bad.pgm': the file is empty"),
    (b"P5\n10 8\n255\n" + bytes(30), "cannot read 'bad.pgm': the pixel data is truncated "
                                     "(its header announces 10 x 8 pixels)"),
    # a header announcing 400 million pixels: refused before decoding (not Pillow's DecompressionBombError)
    (b"P5\n20000 20000\n255\n" + bytes(64), "'bad.pgm' is 20000 x 20000 pixels, more than robotkit reads "
                                            "(100,000,000 pixels; crop or downsample the map)"),
    (b"P5\n10001 10000\n255\n" + bytes(64), "'bad.pgm' is 10001 x 10000 pixels, more than robotkit reads "
                                            "(100,000,000 pixels; crop or downsample the map)"),
])
def test_unreadable_image(tmp_path, monkeypatch, content, message):
    monkeypatch.chdir(tmp_path)
    path = write_map(tmp_path / "maps", None, name="x", image="bad.pgm")
    (tmp_path / "maps" / "bad.pgm").write_bytes(content)
    assert errors(path) == [f"maps/x.yaml:1: image: {message}"]


def test_every_problem_in_the_yaml_at_once(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = write_map(tmp_path / "maps", None, name="x", image="gone.pgm", resolution=-0.05, origin="[1, 2]",
                     negate=2, occupied_thresh=1.5, free_thresh=-0.1, mode="trinry")
    assert errors(path) == [
        "maps/x.yaml:2: resolution: must be > 0",
        "maps/x.yaml:3: origin: must be [x, y, yaw]: three numbers, not [1, 2]",
        "maps/x.yaml:4: negate: must be 0 or 1, not 2",
        "maps/x.yaml:5: occupied_thresh: must be between 0 and 1",
        "maps/x.yaml:6: free_thresh: must be between 0 and 1",
        "maps/x.yaml:7: mode: must be trinary, scale or raw, not 'trinry'",
        "maps/x.yaml:1: image: file 'gone.pgm' does not exist (looked in maps/)",
    ]


def test_free_above_occupied(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = write_map(tmp_path / "maps", rooms_map(10, 10), name="x", free_thresh=0.7)
    assert errors(path) == ["maps/x.yaml:6: free_thresh: must be below occupied_thresh (0.65)"]


def test_wrong_types(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = write_map(tmp_path / "maps", rooms_map(10, 10), name="x", resolution="fine", origin="[0, zero, 0]",
                     occupied_thresh="high")
    assert errors(path) == [
        "maps/x.yaml:2: resolution: must be a number (metres per cell), not 'fine'",
        "maps/x.yaml:3: origin: must be [x, y, yaw]: three numbers, not [0, 'zero', 0]",
        "maps/x.yaml:5: occupied_thresh: must be a number between 0 and 1, not 'high'",
    ]


def test_missing_keys_and_missing_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "m.yaml").write_text("image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    assert errors(tmp_path / "m.yaml") == [
        "m.yaml: negate: missing (map_server requires this key)",
        "m.yaml: occupied_thresh: missing (map_server requires this key)",
        "m.yaml: free_thresh: missing (map_server requires this key)",
        "m.yaml:1: image: file 'm.pgm' does not exist (looked in ./)",
    ]
    assert errors(tmp_path / "nothere.yaml") == ["nothere.yaml: file does not exist"]


def test_invalid_yaml_and_not_a_mapping(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a.yaml").write_text("image: m.pgm\nresolution: [0.05\n")
    assert errors(tmp_path / "a.yaml") == [
        "a.yaml:3: invalid YAML: the [...] list opened at line 2 is not closed: a ']' or ',' is missing"]
    (tmp_path / "b.yaml").write_text("- image\n- m.pgm\n")
    assert errors(tmp_path / "b.yaml") == [
        "b.yaml:1: a map YAML file must be a mapping of map_server keys "
        "(image, resolution, origin, negate, occupied_thresh, free_thresh, mode)"]



def test_deep_nesting_and_alias_bombs_are_refused_before_composing(tmp_path, monkeypatch):
    """PyYAML's composer recurses once per level (5,000 brackets: RecursionError) and expands
    aliases in full: the map YAML gets the recipe's limits first."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "deep.yaml").write_text("image: m.pgm\nresolution: " + "[" * 5000 + "]" * 5000 + "\n")
    assert errors(tmp_path / "deep.yaml") == ["deep.yaml:2: nested deeper than 64 levels"]
    lines = ["image: m.pgm", "a: &a [" + ", ".join(["1"] * 10) + "]"]
    for prev, name in zip("abcde", "bcdef"):
        lines.append(f"{name}: &{name} [" + ", ".join([f"*{prev}"] * 10) + "]")
    lines.append("g: [" + ", ".join(["*f"] * 10) + "]")
    (tmp_path / "bomb.yaml").write_text("\n".join(lines) + "\n")
    assert errors(tmp_path / "bomb.yaml") == ["bomb.yaml:7: aliases expand to more than 1,000,000 values (an alias bomb?)"]

def test_empty_map(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    img = np.full((10, 12), 254, dtype=np.uint8)
    img[0, :5] = 205
    path = write_map(tmp_path / "maps", img, name="x")
    assert errors(path) == ["maps/x.yaml:1: image: no occupied cell in 'x.pgm' (12 x 10 px: 115 free, 5 unknown), "
                            "so there is no wall to build"]
    img[0, :5] = 254
    path = write_map(tmp_path / "maps", img, name="x")
    assert errors(path, unknown_as_wall=True) == [
        "maps/x.yaml:1: image: no occupied or unknown cell in 'x.pgm' (12 x 10 px, all free), "
        "so there is no wall to build"]


def test_bad_name_and_height_with_the_map_problems(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = write_map(tmp_path / "maps", rooms_map(10, 10), name="x", resolution=0)
    assert errors(path, name="my world", height=-1.0) == [
        "name: 'my world' cannot name a Gazebo model and its files (use letters, digits, '_', '-' and '.')",
        "height: must be > 0 (metres), not -1.0",
        "maps/x.yaml:2: resolution: must be > 0",
    ]


# ---------------------------------------------------------------- the command, as a new user runs it


@pytest.mark.slow
def test_cli_writes_the_five_files(tmp_path):
    yaml_path = write_map(tmp_path / "maps", rooms_map(), name="office", resolution=0.05, origin="[-4.0, -3.0, 0.1]")
    proc = run_cli("world", yaml_path, "--out", "OUT", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    out = tmp_path / "OUT" / "office"
    assert proc.stdout.split() == [f"OUT/office/{f}" for f in
                                   ("model.config", "model.sdf", "meshes/office.stl", "office.world", "scene.xml")]
    mesh = trimesh.load(out / "meshes" / "office.stl")
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.is_volume
    ign_sdf_check(out / "office.world")
    mj = mujoco()
    mj.MjModel.from_xml_path(str(out / "scene.xml"))


def test_cli_bad_map_exits_2_with_one_line(tmp_path):
    proc = run_cli("world", MAPS / "nav2_empty_room" / "empty_room.yaml", "--out", tmp_path / "OUT", cwd=MAPS)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == ["nav2_empty_room/empty_room.yaml:1: image: file 'empty.pgm' does not exist "
                                        "(looked in nav2_empty_room/; did you mean 'empty_room.pgm'?)"]
    assert not (tmp_path / "OUT").exists()


def test_cli_too_large_map_exits_2_with_one_line(tmp_path):
    path = write_map(tmp_path / "maps", None, name="x", image="huge.pgm")
    (tmp_path / "maps" / "huge.pgm").write_bytes(b"P5\n20000 20000\n255\n" + bytes(64))
    proc = run_cli("world", path, "--out", tmp_path / "OUT", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == ["maps/x.yaml:1: image: 'huge.pgm' is 20000 x 20000 pixels, more than "
                                        "robotkit reads (100,000,000 pixels; crop or downsample the map)"]
    assert not (tmp_path / "OUT").exists()


def test_importing_the_package_stays_light():
    code = "import sys, robotkit.world; print(sorted(m for m in ('numpy', 'PIL', 'trimesh') if m in sys.modules))"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO)
    assert proc.stdout.strip() == "[]", proc.stderr


def test_building_a_world_does_not_import_trimesh(tmp_path):
    """The STL is written by robotkit.mesh.export from the arrays: trimesh (0.8 s to import) stays out."""
    code = ("import sys; from robotkit.world import build_world; "
            f"build_world({str(MAPS / 'nav2_warehouse' / 'warehouse.yaml')!r}, {str(tmp_path)!r}); "
            "print(sorted(m for m in ('trimesh', 'scipy') if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO)
    assert proc.stdout.strip() == "[]", proc.stderr


def test_cycles_of_a_permutation_in_walking_order():
    from robotkit.world.walls import _cycles

    rng = np.random.default_rng(3)
    succ = rng.permutation(2000)
    seen, walk, sizes = set(), [], []
    for s in range(len(succ)):  # the plain walk: from each unvisited index, follow succ
        size = 0
        while s not in seen:
            seen.add(s)
            walk.append(s)
            s = int(succ[s])
            size += 1
        if size:
            sizes.append(size)
    order, got = _cycles(succ)
    assert order.tolist() == walk and got.tolist() == sizes


def test_closed_check_of_the_wall_mesh():
    from robotkit.world.walls import _closed

    box = trimesh.creation.box([1, 1, 1])
    faces = np.asarray(box.faces)
    assert _closed(faces, len(box.vertices))
    assert not _closed(faces[1:], len(box.vertices))  # a hole
    assert not _closed(np.concatenate([faces, faces[:1]]), len(box.vertices))  # a face twice
    flipped = faces.copy()
    flipped[0] = flipped[0, ::-1]
    assert not _closed(flipped, len(box.vertices))  # one face the wrong way round


def turns_by_the_grid(mask):
    """The outline's turns from the four cells around every grid point: one or three walls, or
    two walls touching at a corner (a pinch); with, for a pinch, whether the south-west cell is a wall."""
    g = np.pad(mask, 1).astype(np.int64)
    sw, se, nw, ne = g[:-1, :-1], g[:-1, 1:], g[1:, :-1], g[1:, 1:]
    count = sw + se + nw + ne
    pinch = (count == 2) & (sw == ne)
    ty, tx = np.nonzero((count % 2 == 1) | pinch)
    py, px = np.nonzero(pinch)
    return ty, tx, py, px, sw[py, px] > 0


def nested_mask():
    """Walls in walls: a ring, an island ring in its hole, a block in the island's hole, two holes
    in one piece, holes touching their wall at a corner, and pieces side by side."""
    m = np.zeros((40, 60), dtype=bool)
    m[2:38, 2:40] = True
    m[5:35, 5:37] = False  # the big hole
    m[8:30, 8:30] = True
    m[11:27, 11:27] = False  # the island's hole
    m[15:20, 15:20] = True  # a block in it
    m[12, 12] = True  # touching the hole's wall at a corner
    m[31:34, 31:34] = True  # in the big hole, beside the island
    m[2:20, 44:58] = True
    m[5:8, 47:50] = m[11:16, 47:55] = False  # one piece, two holes
    m[8, 50] = True
    m[24:38, 44:58] = True
    m[27:29, 47:49] = False
    m[29, 49] = False  # a hole cell touching the other by a corner: one hole or two
    return m


def masks_with_holes():
    yield nested_mask()
    yield rooms_map(60, 80)[::-1] == 0
    rng = np.random.default_rng(11)
    for _ in range(40):
        rows, cols = rng.integers(3, 30, 2)
        yield rng.random((rows, cols)) < rng.uniform(0.3, 0.8)


def test_turns_come_from_the_row_changes_as_from_the_whole_grid():
    from robotkit.world.walls import _Grid

    for mask in [*random_masks(), *masks_with_holes()]:
        grid = _Grid(mask)
        ty, tx, py, px, ne_sw = turns_by_the_grid(mask)
        np.testing.assert_array_equal(grid.turn_y, ty)
        np.testing.assert_array_equal(grid.turn_x, tx)
        np.testing.assert_array_equal(grid.pinch_y, py)
        np.testing.assert_array_equal(grid.pinch_x, px)
        np.testing.assert_array_equal(grid._pinch_ne_sw, ne_sw)


def test_rectangles_from_the_row_and_column_changes_cover_the_mask_once():
    for mask in [*random_masks(), *masks_with_holes()]:
        rects = rectangles(mask)
        cover = np.zeros(mask.shape, dtype=np.int64)
        for x0, y0, x1, y1 in rects:
            cover[y0:y1, x0:x1] += 1
        np.testing.assert_array_equal(cover, mask.astype(np.int64))


def test_each_hole_is_triangulated_with_the_outer_loop_of_its_piece_of_wall(monkeypatch):
    """Every loop's outer loop bounds the same 4-connected piece of wall (scipy's labels), and
    the triangles are those of one call on all the loops, only in another order."""
    import manifold3d
    from scipy import ndimage

    from robotkit.world import walls

    def canonical(tris):
        return sorted(tuple(np.roll(t, -int(np.argmin(t)))) for t in tris.tolist())

    calls = []
    triangulate = walls._triangulate

    def spy(*args):
        calls.append(args[1:])
        return triangulate(*args)

    monkeypatch.setattr(walls, "_triangulate", spy)
    n_holes = 0
    for mask in masks_with_holes():
        calls.clear()
        grid = walls._Grid(mask)
        assert walls._outline_caps(grid, grid.outline(grid.turn_y, grid.turn_x)) is not None, \
            "the outline path was taken, not the rectangles fallback"
        (polygons, starts, sizes, outer), = calls
        assert outer is not None
        # each loop's first edge a -> b has the wall on its left: that cell's piece of wall
        a = np.array([p[0] for p in polygons], dtype=np.int64)
        b = np.array([p[1] for p in polygons], dtype=np.int64)
        d = np.sign(b - a)
        cx = np.where((d[:, 0] > 0) | (d[:, 1] < 0), a[:, 0], a[:, 0] - 1)
        cy = np.where((d[:, 0] > 0) | (d[:, 1] > 0), a[:, 1], a[:, 1] - 1)
        assert mask[cy, cx].all()
        labels, n_pieces = ndimage.label(mask)
        piece = labels[cy, cx]
        np.testing.assert_array_equal(piece[outer], piece)
        area = np.array([np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]) for p in polygons])
        assert (area[outer] > 0).all()
        assert len(np.unique(outer)) == (area > 0).sum() == n_pieces
        n_holes += int((area < 0).sum())
        whole = triangulate(manifold3d, polygons, starts, sizes, None)
        assert canonical(triangulate(manifold3d, polygons, starts, sizes, outer)) == canonical(whole)
    assert n_holes > 50


def test_each_filter_writes_what_a_jinja_loop_writes_and_escapes_values():
    """The scene's boxes go through the ``each`` filter; its text is the Jinja loop's, escapes included."""
    from robotkit.emit.env import environment
    from robotkit.world.emit import Box

    env = environment()
    loop = env.from_string('{% for b in boxes %}  <geom pos="{{ b.pos }}" size="{{ b.size }}"/>\n{% endfor %}')
    fast = env.from_string('{% set line %}  <geom pos="{it.pos}" size="{it.size}"/>\n{% endset %}'
                           '{{ boxes | each(line) }}')
    plain = [Box(f"{i} {i / 7} 1", f"0.5 {i} 1") for i in range(500)]
    hostile = plain + [Box('1 "2" 3', "<a> & 'b'")]
    for boxes in (plain, hostile, []):
        assert fast.render(boxes=boxes) == loop.render(boxes=boxes)
    assert "&lt;a&gt; &amp; &#39;b&#39;" in fast.render(boxes=hostile)
    plain_fields = env.from_string('{% set line %}{it}:{it!r};{% endset %}{{ xs | each(line) }}')
    assert plain_fields.render(xs=[1, "<"]) == "1:1;&lt;:&#39;&lt;&#39;;"


def test_grey_images_read_from_the_file_as_pillow_decodes_them(tmp_path):
    """Binary PGMs are read straight from the file at the header's offset; every other layout
    (bottom-up BMP, TIFF, ASCII PGM, maxval other than 255) is left to Pillow: same grid each way."""
    rng = np.random.default_rng(5)
    pixels = rng.choice(np.array([0, 100, 205, 254, 255], dtype=np.uint8), size=(23, 37))
    reference = load_map(write_map(tmp_path, pixels, name="ref", image="ref.png")).grid
    header = b"P5\n# a comment, as map_saver writes\n37 23\n255\n"
    handmade = {"comment.pgm": header + pixels.tobytes(), "trailing.pgm": header + pixels.tobytes() + b"\n\0\0",
                "ascii.pgm": b"P2\n37 23\n255\n" + " ".join(map(str, pixels.ravel())).encode() + b"\n"}
    for image, data in handmade.items():
        (tmp_path / image).write_bytes(data)
    for image in ("pillow.pgm", "grey.bmp", "grey.tif"):
        Image.fromarray(pixels).save(tmp_path / image)
    for image in [*handmade, "pillow.pgm", "grey.bmp", "grey.tif"]:
        om = load_map(write_map(tmp_path, None, name=image.replace(".", "_"), image=image))
        np.testing.assert_array_equal(om.grid, reference, err_msg=image)
    # maxval 100: Pillow scales the values to 0..255, so it is not read as raw bytes
    (tmp_path / "max100.pgm").write_bytes(b"P5\n37 23\n100\n" + (pixels // 3).tobytes())
    scaled = load_map(write_map(tmp_path, None, name="max100", image="max100.pgm")).grid
    expected = load_map(write_map(tmp_path, np.asarray(Image.open(tmp_path / "max100.pgm")), name="m100",
                                  image="m100.png")).grid
    np.testing.assert_array_equal(scaled, expected)


def test_the_padded_wall_cells_give_the_same_mesh_and_rectangles(tmp_path):
    from robotkit.world.walls import padded_wall_cells

    om = load_map(write_map(tmp_path, rooms_map(50, 70), origin="[1.0, 2.0, 0.4]"))
    for unknown in (False, True):
        mask = wall_cells(om, unknown)
        padded = padded_wall_cells(om, unknown)
        assert padded.shape == (om.rows + 2, om.cols + 2) and not padded[[0, -1]].any() and not padded[:, [0, -1]].any()
        np.testing.assert_array_equal(padded[1:-1, 1:-1], mask)
        np.testing.assert_array_equal(rectangles(padded[1:-1, 1:-1], padded=padded), rectangles(mask))
        for got, want in zip(extrude(padded[1:-1, 1:-1], 2.0, padded=padded), extrude(mask, 2.0)):
            np.testing.assert_array_equal(got, want)


def test_a_piece_of_wall_with_too_many_holes_gets_rectangle_caps(monkeypatch):
    """manifold3d's time grows with holes x points in one piece: past MAX_HOLE_WORK the caps come
    from rectangles (exact too, linear); below it, from the outline (fewer faces)."""
    from robotkit.world import walls

    mask = nested_mask()
    outline = extrude(mask, 1.0)
    by_rectangles = extrude(mask, 1.0, method="rectangles")
    assert len(outline[1]) < len(by_rectangles[1])
    monkeypatch.setattr(walls, "MAX_HOLE_WORK", 0)  # any hole is too many
    for got, want in zip(extrude(mask, 1.0), by_rectangles):
        np.testing.assert_array_equal(got, want)
