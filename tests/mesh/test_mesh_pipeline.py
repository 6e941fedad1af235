"""The mesh-processing library against known answers: repair, transform, decimation, hulls,
CoACD decomposition, primitive fits, proxy fidelity, the result cache, reproducible export."""

from __future__ import annotations

import hashlib
import io
import json
import math
import multiprocessing
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh

from robotkit.mesh.cache import Cache, default_root, mesh_digest
from robotkit.mesh.decimate import closed_volume, decimate, point_surface_distance, surface_distance
from robotkit.mesh.decompose import decompose
from robotkit.mesh.export import obj_bytes, stl_bytes
from robotkit.mesh.fidelity import fidelity
from robotkit.mesh.hull import canonical, convex_hull, convex_hull_report, from_manifold, to_manifold
from robotkit.mesh.inertia import mesh_mass_properties
from robotkit.model.massprops import box_props
from robotkit.mesh.primitives import Primitive, fit_box, fit_capsule, fit_cylinder, fit_sphere
from robotkit.mesh.repair import repair
from robotkit.mesh.transform import transform
from robotkit.geometry import rpy_matrix

REPO = Path(__file__).resolve().parents[2]


def pose(rpy=(0.3, -0.7, 1.2), xyz=(0.1, -0.2, 0.3)) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = rpy_matrix(rpy)
    T[:3, 3] = xyz
    return T


def moved(mesh, T):
    m = mesh.copy()
    m.apply_transform(T)
    return m


def props(mesh):
    return mesh_mass_properties(mesh.vertices, mesh.faces)


def l_shape(subdivisions: int = 2) -> trimesh.Trimesh:
    """Two 0.2 x 0.05 x 0.05 m bars joined at one end (a closed L), subdivided."""
    import manifold3d as m3

    a = trimesh.creation.box([0.2, 0.05, 0.05])
    a.apply_translation([0.1, 0.025, 0.025])
    b = trimesh.creation.box([0.05, 0.2, 0.05])
    b.apply_translation([0.025, 0.1, 0.025])
    mesh = from_manifold(m3.Manifold.batch_boolean([to_manifold(a), to_manifold(b)], m3.OpType.Add))
    for _ in range(subdivisions):
        mesh = mesh.subdivide()
    return mesh


def shell(mesh) -> tuple[float, float]:
    """(rho, R) for a surface around the origin: every point of it has rho <= |p| <= R, and
    every ray from the origin meets it once (all face planes have the origin behind them)."""
    n = mesh.face_normals
    offsets = np.einsum("ij,ij->i", n, mesh.triangles[:, 0])
    assert (offsets > 0).all(), "not star-shaped about the origin"
    tri = np.asarray(mesh.triangles)
    nearest = trimesh.triangles.closest_point(tri, np.zeros((len(tri), 3)))
    return float(np.linalg.norm(nearest, axis=1).min()), float(np.linalg.norm(mesh.vertices, axis=1).max())


# --- repair ----------------------------------------------------------------------------------

def broken_box():
    """A unit box with faces 3 and 7 flipped, face 0 missing, faces 4 and 5 duplicated."""
    box = trimesh.creation.box([1.0, 1.0, 1.0])
    F = np.array(box.faces)
    F[[0, 3, 7]] = F[[0, 3, 7]][:, ::-1]
    F = np.vstack([F[1:], F[[4, 5]]])
    return trimesh.Trimesh(np.array(box.vertices), F, process=False)


def test_repair_reports_duplicates_flips_and_the_filled_hole():
    mesh = broken_box()
    V0, F0 = np.array(mesh.vertices), np.array(mesh.faces)
    fixed, report = repair(mesh)
    np.testing.assert_array_equal(mesh.vertices, V0)  # the input is untouched
    np.testing.assert_array_equal(mesh.faces, F0)
    assert report["faces_in"] == 13
    assert report["duplicate_faces_removed"] == 2
    assert report["faces_flipped"] == 2  # faces 3 and 7 (face 0 was the missing one)
    assert report["holes_found"] == report["holes_filled"] == 1
    assert report["faces_added"] == 1 and report["vertices_added"] == 0 and report["holes_left"] == 0
    assert report["degenerate_faces_removed"] == report["vertices_merged"] == 0
    assert report["is_volume"] and report["watertight"] and report["changed"]
    assert report["faces_out"] == 12 and report["open_edges"] == 0
    assert report["volume"] == pytest.approx(1.0, abs=1e-15)
    np.testing.assert_allclose(props(fixed).inertia, box_props([1, 1, 1]).inertia, atol=1e-15)


def test_repair_of_a_clean_mesh_changes_nothing():
    box = trimesh.creation.box([0.1, 0.2, 0.3])
    fixed, report = repair(box)
    assert not report["changed"] and report["is_volume"]
    np.testing.assert_array_equal(fixed.faces, box.faces)
    np.testing.assert_array_equal(fixed.vertices, box.vertices)


def test_repair_inverted_box_and_triangle_soup():
    box = trimesh.creation.box([1.0, 2.0, 3.0])
    inverted = trimesh.Trimesh(np.array(box.vertices), np.array(box.faces)[:, ::-1], process=False)
    fixed, report = repair(inverted)
    assert report["faces_flipped"] == 12 and report["bodies_inverted"] == 1
    assert fixed.volume == pytest.approx(6.0, rel=1e-14)
    soup = trimesh.Trimesh(box.triangles.reshape(-1, 3), np.arange(36).reshape(-1, 3), process=False)
    fixed, report = repair(soup)
    assert report["vertices_merged"] == 28 and report["is_volume"]
    assert fixed.volume == pytest.approx(6.0, rel=1e-14)


def test_repair_keeps_a_cavity_inward():
    """A hollow box: the inner shell is inward on purpose; trimesh's multibody fix would flip it."""
    outer, inner = trimesh.creation.box([1.0, 1.0, 1.0]), trimesh.creation.box([0.5, 0.5, 0.5])
    V = np.vstack([outer.vertices, inner.vertices])
    F = np.vstack([outer.faces, np.array(inner.faces)[:, ::-1] + 8])
    fixed, report = repair(trimesh.Trimesh(V, F, process=False))
    assert report["nested_bodies"] == 1 and report["faces_flipped"] == 0
    assert fixed.volume == pytest.approx(0.875, rel=1e-14)
    F2 = F.copy()
    F2[[13, 20]] = F2[[13, 20]][:, ::-1]  # two cavity faces wound the wrong way: the majority wins
    fixed, report = repair(trimesh.Trimesh(V, F2, process=False))
    assert report["faces_flipped"] == 2 and report["is_volume"]
    assert fixed.volume == pytest.approx(0.875, rel=1e-14)


def test_repair_turns_outward_a_body_in_the_hole_of_a_ring_not_inside_it():
    """A box in a torus's hole lies within the torus's bounds but outside it (the test stops at
    its first point): not nested, so turned outward; one in the torus's tube is nested."""
    ring = trimesh.creation.torus(major_radius=1.0, minor_radius=0.3, major_sections=48, minor_sections=24)
    for centre, nested in (((0.0, 0.0, 0.0), 0), ((1.0, 0.0, 0.0), 1)):
        box = trimesh.creation.box([0.1, 0.1, 0.1])
        V = np.vstack([ring.vertices, np.asarray(box.vertices) + centre])
        F = np.vstack([ring.faces, np.array(box.faces)[:, ::-1] + len(ring.vertices)])  # the box inward
        fixed, report = repair(trimesh.Trimesh(V, F, process=False))
        assert report["nested_bodies"] == nested and report["bodies_inverted"] == 1 - nested
        # outside the ring the box adds its volume; in the tube it stays a cavity
        assert fixed.volume == pytest.approx(ring.volume + (-0.001 if nested else 0.001), rel=1e-9)


def test_repair_leaves_large_holes_open():
    box = trimesh.creation.box([1.0, 1.0, 1.0])
    open_box = trimesh.Trimesh(np.array(box.vertices), np.array(box.faces)[2:], process=False)  # a square hole
    _, report = repair(open_box, max_hole_edges=3)
    assert report["holes_found"] == 1 and report["holes_left"] == 1 and not report["is_volume"]
    assert report["open_edges"] == 4 and report["volume"] is None
    _, report = repair(open_box, fill_holes=False)
    assert report["holes_filled"] == 0 and not report["watertight"]
    for k in range(10):  # one face wound against the rest: only it turns, wherever the winding fix starts
        F = np.array(open_box.faces)
        F[k] = F[k][::-1]
        fixed, report = repair(trimesh.Trimesh(open_box.vertices, F, process=False), fill_holes=False)
        assert report["faces_flipped"] == 1 and report["winding_consistent"]
        np.testing.assert_array_equal(fixed.faces, open_box.faces)
    fixed, report = repair(open_box)  # a whole side: 1 m^2 of a 5 m^2 surface is not a small hole
    assert report["holes_filled"] == 0 and report["holes_left"] == 1 and not report["is_volume"]


# --- transform -------------------------------------------------------------------------------

def test_transform_mm_to_m_is_exact():
    box_mm = trimesh.creation.box([100.0, 200.0, 300.0])
    box_mm.apply_translation([1000.0, -20.0, 5.0])
    out, M = transform(box_mm, scale=0.001)
    np.testing.assert_array_equal(out.vertices, np.asarray(box_mm.vertices) * 0.001)
    np.testing.assert_array_equal(M, np.diag([0.001, 0.001, 0.001, 1.0]))
    a, b = props(box_mm), props(out)
    assert b.volume == pytest.approx(a.volume * 1e-9, rel=1e-12)
    np.testing.assert_allclose(b.com, a.com * 0.001, rtol=1e-12)
    np.testing.assert_allclose(b.inertia, a.inertia * 1e-15, rtol=1e-12, atol=1e-20)
    np.testing.assert_allclose(b.inertia, box_props([0.1, 0.2, 0.3]).inertia, rtol=1e-10, atol=1e-18)


def test_transform_rotation_translation_carry_mass_properties():
    mesh = trimesh.creation.annulus(r_min=0.02, r_max=0.05, height=0.03, sections=48)
    mesh.apply_translation([0.01, 0.02, 0.03])
    before = props(mesh)
    out, M = transform(mesh, translate=(0.5, -0.25, 1.0), rpy=(0.3, -1.1, 2.5))
    R = rpy_matrix((0.3, -1.1, 2.5))
    np.testing.assert_allclose(M[:3, :3], R, atol=0)
    np.testing.assert_allclose(out.vertices, trimesh.transform_points(mesh.vertices, M), atol=1e-15)
    after = props(out)
    assert after.volume == pytest.approx(before.volume, rel=1e-12)
    np.testing.assert_allclose(after.com, R @ before.com + [0.5, -0.25, 1.0], atol=1e-15)
    np.testing.assert_allclose(after.inertia, R @ before.inertia @ R.T, atol=1e-17)


@pytest.mark.parametrize("recenter", ["bbox", "com"])
def test_transform_recenter(recenter):
    mesh = trimesh.creation.cone(radius=30.0, height=80.0, sections=64)  # mm, COM off the bbox centre
    mesh.apply_translation([5.0, 7.0, 11.0])
    out, M = transform(mesh, scale=0.001, translate=(0.1, 0.2, 0.3), rpy=(0.0, math.pi / 2, 0.0),
                       recenter=recenter)
    scaled = np.asarray(mesh.vertices) * 0.001
    c = (0.5 * (scaled.min(axis=0) + scaled.max(axis=0)) if recenter == "bbox"
         else mesh_mass_properties(scaled, mesh.faces).com)
    np.testing.assert_allclose(M[:3, :3] @ (c / 0.001) + M[:3, 3], [0.1, 0.2, 0.3], atol=1e-15)  # on translate
    if recenter == "com":
        np.testing.assert_allclose(props(out).com, [0.1, 0.2, 0.3], atol=1e-15)
        assert out.volume == pytest.approx(mesh.volume * 1e-9, rel=1e-12)


def test_transform_mirror_keeps_the_winding_outward():
    mesh = trimesh.creation.cone(radius=0.03, height=0.08, sections=32)
    mesh.apply_translation([0.01, 0.0, 0.0])
    out, M = transform(mesh, scale=(-1.0, 1.0, 1.0))
    assert np.linalg.det(M[:3, :3]) < 0
    assert out.is_volume and out.volume == pytest.approx(mesh.volume, rel=1e-12)
    np.testing.assert_allclose(props(out).com, props(mesh).com * [-1, 1, 1], atol=1e-15)
    assert mesh.is_volume  # input untouched


def test_transform_errors():
    box = trimesh.creation.box([1, 1, 1])
    with pytest.raises(ValueError, match="non-zero"):
        transform(box, scale=(1.0, 0.0, 1.0))
    with pytest.raises(ValueError, match="recenter"):
        transform(box, recenter="centre")
    open_box = trimesh.Trimesh(box.vertices, box.faces[1:], process=False)
    with pytest.raises(ValueError, match="closed"):
        transform(open_box, recenter="com")


# --- decimation and surface distance ---------------------------------------------------------

def test_surface_distance_is_exact():
    """Concentric spheres r=1 and 1.1: every distance lies in an interval set by the tessellations,
    and the k-d tree search equals brute force over every triangle."""
    a = trimesh.creation.icosphere(subdivisions=4, radius=1.0)
    b = trimesh.creation.icosphere(subdivisions=4, radius=1.1)
    (rho_a, big_a), (rho_b, big_b) = shell(a), shell(b)
    d = surface_distance(a, b, samples=2000)
    lo, hi = rho_b - big_a, big_b - rho_a
    for k in ("a_to_b_max", "a_to_b_mean", "b_to_a_max", "b_to_a_mean"):
        assert lo - 1e-12 <= d[k] <= hi + 1e-12, (k, d[k], lo, hi)
    pts = trimesh.sample.sample_surface(a, 300, seed=3)[0] * 1.03 + 0.01
    tri = np.asarray(b.triangles)
    brute = np.array([np.linalg.norm(trimesh.triangles.closest_point(tri, np.tile(p, (len(tri), 1))) - p,
                                     axis=1).min() for p in pts])
    np.testing.assert_allclose(point_surface_distance(pts, b), brute, rtol=0, atol=1e-15)


@pytest.mark.slow
def test_decimate_sphere_volume_and_distance_against_the_sphere():
    sphere = trimesh.creation.icosphere(subdivisions=6, radius=1.0)  # 81,920 faces
    out, report = decimate(sphere, target_faces=5000)
    assert 4900 <= report["faces_after"] <= 5000 and report["faces_before"] == 81920
    assert report["is_volume_after"] and abs(report["volume_change"]) < 0.01
    assert report["volume_change"] == pytest.approx(out.volume / sphere.volume - 1, rel=1e-12)
    # both surfaces lie between spheres: no sampled distance can exceed the shell bound
    (rho_s, big_s), (rho_d, big_d) = shell(sphere), shell(out)
    bound = max(big_d - rho_s, big_s - rho_d)
    dist = report["distance"]
    assert 0 < dist["mean"] < dist["max"] <= bound
    assert dist["max"] > 0.5 * bound  # and close to it: the bound is tight for a fine sphere


def test_decimate_torus_ratio_is_deterministic():
    torus = trimesh.creation.torus(major_radius=0.2, minor_radius=0.05, major_sections=128, minor_sections=64)
    a, ra = decimate(torus, ratio=0.1)
    b, rb = decimate(torus, ratio=0.1)
    assert ra["target_faces"] == round(0.1 * len(torus.faces))
    assert abs(ra["volume_change"]) < 0.01 and ra["is_volume_after"]
    np.testing.assert_array_equal(a.vertices, b.vertices)
    np.testing.assert_array_equal(a.faces, b.faces)
    assert ra == rb
    assert ra["distance"]["max"] < 0.01 * 0.5  # well under 1 % of the torus size


@pytest.mark.parametrize("shortcuts", [False, True])
def test_decimate_does_not_depend_on_units(shortcuts):
    """The shortcuts' thresholds are absolute (meshoptimizer's error, float32): that path
    normalises the size first, and gives the same bytes in mm and m.  MeshLib alone (the default)
    has no absolute threshold and is called on the coordinates as given, scaled by a power of two:
    the same surface up to float32 rounding (1000 is no power of two), not the same bytes: the
    torus's many ties go the other way, and the distances differ by 9 % (measured)."""
    torus_m = trimesh.creation.torus(major_radius=0.2, minor_radius=0.05, major_sections=96, minor_sections=48)
    torus_mm = trimesh.Trimesh(np.asarray(torus_m.vertices) * 1000.0, torus_m.faces, process=False)
    a, ra = decimate(torus_m, target_faces=900, samples=500, shortcuts=shortcuts)
    b, rb = decimate(torus_mm, target_faces=900, samples=500, shortcuts=shortcuts)
    if shortcuts:
        np.testing.assert_array_equal(a.faces, b.faces)
        np.testing.assert_allclose(np.asarray(b.vertices) / 1000.0, a.vertices, rtol=0, atol=1e-12)  # 5e-11 of the size
        assert ra["distance"]["max"] == pytest.approx(rb["distance"]["max"] / 1000.0, rel=1e-6)
    else:
        assert 882 <= ra["faces_after"] == rb["faces_after"] <= 900
        assert ra["distance"]["max"] == pytest.approx(rb["distance"]["max"] / 1000.0, rel=0.15)


REAL_VISUALS = sorted(str(p.relative_to(REPO)) for p in (REPO / "recipes" / "meshes").rglob("*")
                      if p.suffix.lower() in (".stl", ".dae") and "collision" not in p.parts)


@pytest.mark.slow
@pytest.mark.parametrize("keep", [0.1, 0.3])
def test_decimate_reaches_the_target_and_keeps_closed_meshes_closed_on_real_meshes(keep, monkeypatch):
    """Every visual mesh of the examples (CAD tessellations: long thin triangles, several bodies):
    the face count is within 2 % of the target, and a closed mesh stays closed.  The turret_bot's
    meshes (28-92 faces, targets under 30 faces where 2 % is less than one face) are left out.
    The shortcuts' results are kept (the quality check of issue 33 off), so the paths show."""
    import robotkit.mesh.decimate as decimate_module
    from robotkit.mesh.io import load_mesh

    monkeypatch.setattr(decimate_module, "GUARANTEE_FACTOR", float("inf"))

    meshes = [(rel, load_mesh(str(REPO / rel))) for rel in REAL_VISUALS]
    meshes = [(rel, m) for rel, m in meshes if len(m.faces) >= 1000]
    assert len(meshes) == 11
    misses, rounds = [], {}
    for rel, mesh in meshes:
        out, report = decimate(mesh, ratio=keep, samples=0, shortcuts=True)
        target = report["target_faces"]
        assert report["faces_after"] == len(out.faces) and report["library"] == "meshlib"
        assert report["prepass_library"] == "meshoptimizer"
        rounds[rel] = report["prepass_rounds"], report["prepass_locked"], report["prepass"], report["fast_stage"]
        if abs(len(out.faces) - target) > 0.02 * target or (report["is_volume_before"]
                                                            and not report["is_volume_after"]):
            misses.append((rel, target, len(out.faces), report["is_volume_before"], report["is_volume_after"]))
    assert misses == []
    if keep == 0.1:  # every way is taken: meshoptimizer's first pass at once (the UR5's parts), in
        # a second run after locking the vertices round the first one's defects (the tyres), and
        # MeshLib's fast stage where the first run left many defects (the lidar; the base, whose
        # own edges of three faces were locked from the start)
        assert rounds["recipes/meshes/ur5/visual/forearm.dae"] == (1, 0, 2.0, None)
        assert rounds["recipes/meshes/turtlebot3/left_tire.stl"][0::2] == (2, 4.0)
        assert rounds["recipes/meshes/turtlebot3/left_tire.stl"][1] > 0
        assert rounds["recipes/meshes/turtlebot3/lds.stl"] == (1, 0, None, 3.0)
        assert rounds["recipes/meshes/turtlebot3/burger_base.stl"][1:] == (648, None, 3.0)


def test_first_pass_locks_the_vertices_round_meshoptimizers_defects():
    """meshoptimizer alone leaves duplicate faces or edges of three faces on the TurtleBot3's
    tyre (closed); with the vertices round them locked its second run gives a closed surface,
    which MeshLib then takes to the target, closed."""
    from robotkit.mesh.decimate import CLOSED, _defective_faces, _edge_census, _prepass, _simplify
    from robotkit.mesh.io import load_mesh

    mesh = load_mesh(str(REPO / "recipes/meshes/turtlebot3/left_tire.stl"))
    V = np.asarray(mesh.vertices)
    centre = 0.5 * (V.min(axis=0) + V.max(axis=0))
    Vf = np.ascontiguousarray((V - centre) * (1000.0 / np.linalg.norm(np.ptp(V, axis=0))), dtype=np.float32)
    F = np.asarray(mesh.faces)
    assert _edge_census(F, len(V)) == CLOSED
    indices = np.ascontiguousarray(F, dtype=np.uint32).ravel()
    alone = _simplify(indices, Vf, 3 * 2 * 2167, np.zeros(len(V), np.uint8))
    assert _edge_census(alone, len(V))[0] and _defective_faces(alone, len(V), closed=True).sum() > 0
    faces, details = _prepass(Vf, F, 2167, closed=True, defective=False)
    assert details == {"prepass": 4.0, "prepass_rounds": 2, "prepass_locked": details["prepass_locked"]}
    assert details["prepass_locked"] > 0
    assert _edge_census(faces, len(V)) == CLOSED and len(faces) <= 4 * 2167
    out, report = decimate(mesh, target_faces=2167, samples=0, shortcuts=True)
    assert report["is_volume_after"] and 2124 <= report["faces_after"] <= 2167 and report["prepass"] == 4.0


def test_meshlib_runs_on_the_calling_thread_alone():
    """MeshLib's TBB pool is limited to one thread once robotkit has called it (a build already
    runs one process per core, and TBB's idle workers spin); trimesh's embreex brings a TBB of
    its own, so the one in MeshLib's folder is the one limited and checked."""
    import ctypes

    from robotkit.mesh.decimate import _meshlib_single_threaded

    decimate(trimesh.creation.icosphere(subdivisions=2), target_faces=100, samples=0)
    with open("/proc/self/maps") as maps:
        paths = sorted({ln.split()[-1] for ln in maps if "/libtbb" in ln and "malloc" not in ln})
    meshlib_tbb = [p for p in paths if "meshlib" in Path(p).parent.name]
    assert len(meshlib_tbb) == 1 and _meshlib_single_threaded() == 1
    active = ctypes.CDLL(meshlib_tbb[0])._ZN3tbb6detail2r127global_control_active_valueEi
    active.restype, active.argtypes = ctypes.c_size_t, [ctypes.c_int]
    assert active(0) == 1
    threads = len(os.listdir("/proc/self/task"))
    decimate(trimesh.creation.icosphere(subdivisions=4), target_faces=500, samples=0)
    assert len(os.listdir("/proc/self/task")) <= threads  # no TBB worker started


@pytest.mark.slow
def test_meshlib_fast_stage_where_the_first_pass_gives_up(monkeypatch):
    """Without the first pass, MeshLib goes to 3 times the target keeping vertices where they
    are, then to the target with its optimal positions: the target is reached, a closed mesh
    stays closed, and the distance stays near MeshLib's own (measured: 0.8-1.2 of it); here
    tested with the quality check (issue 33) off."""
    import robotkit.mesh.decimate as decimate_module
    from robotkit.mesh.io import load_mesh

    monkeypatch.setattr(decimate_module, "PREPASS_GIVE_UP", 0.0)  # give up after any defect
    monkeypatch.setattr(decimate_module, "FAST_STAGE", 3.0)
    monkeypatch.setattr(decimate_module, "GUARANTEE_FACTOR", float("inf"))
    tire = load_mesh(str(REPO / "recipes/meshes/turtlebot3/left_tire.stl"))
    out, report = decimate(tire, target_faces=2167, samples=2000, shortcuts=True)
    assert report["prepass"] is None and report["prepass_rounds"] == 1 and report["fast_stage"] == 3.0
    assert report["is_volume_after"] and 2124 <= report["faces_after"] <= 2167
    V = np.asarray(tire.vertices)
    centre = 0.5 * (V.min(axis=0) + V.max(axis=0))
    k = 1000.0 / np.linalg.norm(np.ptp(V, axis=0))
    v, f = decimate_module._meshlib_decimate((V - centre) * k, np.asarray(tire.faces), 2167)
    plain = trimesh.Trimesh(v / k + centre, f, process=False)
    assert report["distance"]["max"] <= 1.5 * surface_distance(tire, plain, 2000)["max"]


@pytest.mark.parametrize("first_pass", [False, True])
def test_decimate_fills_missing_triangles_that_stop_it_above_the_target(monkeypatch, first_pass):
    """A closed surface that lacks a few triangles (as the KUKA iiwa's link_7 lacks 37): edge
    collapses keep its holes, so MeshLib alone stops far above a low target; the missing
    triangles are filled and the target is reached, closed."""
    import robotkit.mesh.decimate as decimate_module

    if not first_pass:
        monkeypatch.setattr(decimate_module, "PREPASS_LIMIT", 0.0)
    sphere = trimesh.creation.icosphere(subdivisions=4)  # 5,120 faces
    # 40 faces no two of which share a vertex: 40 holes of three edges
    taken, used = [], set()
    for i in range(0, len(sphere.faces), 37):
        if not used & set(sphere.faces[i]) and len(taken) < 40:
            taken.append(i)
            used |= set(sphere.faces[i])
    assert len(taken) == 40
    holed = trimesh.Trimesh(sphere.vertices, np.delete(sphere.faces, taken, axis=0), process=False)
    out, report = decimate(holed, target_faces=100, samples=0, shortcuts=first_pass)
    assert 98 <= report["faces_after"] <= 100 and report["is_volume_after"]
    if not first_pass:
        assert report["holes_filled"] == 40
    # MeshLib alone (no first pass, no filling) stops above it: the holes are what held it
    from robotkit.mesh.decimate import _meshlib_decimate

    assert len(_meshlib_decimate(holed.vertices, holed.faces, 100)[1]) > 102


def test_edge_census_against_trimesh():
    """The checks the meshoptimizer first pass must pass: no degenerate face, no directed edge
    twice, no edge of three faces, its border count; no two faces with the same corners."""
    from robotkit.mesh.decimate import _edge_census

    box = trimesh.creation.box()
    F = np.asarray(box.faces)
    V = np.vstack([box.vertices, [[2.0, 0.0, 0.0]]])  # vertex 8: a fin on an edge of the box
    cases = {"closed": F, "one missing": F[1:], "two missing": F[2:], "a duplicate face": np.vstack([F, F[:1]]),
             "a flipped duplicate": np.vstack([F, F[:1, ::-1]]), "degenerate": np.vstack([F, [[0, 0, 1]]]),
             "an edge of three faces": np.vstack([F, [[F[0, 1], F[0, 0], 8]]]),
             "an open fin": np.vstack([F[1:], [[F[0, 1], F[0, 0], 8]]])}
    for name, faces in cases.items():
        defective, over_two, borders = _edge_census(faces, len(V))
        m = trimesh.Trimesh(V, faces, process=False)
        counts = np.unique(m.edges_sorted, axis=0, return_counts=True)[1]
        directed = np.unique(m.edges, axis=0, return_counts=True)[1]
        degenerate = bool((faces[:, 0] == faces[:, 1]).any())
        assert over_two == bool((counts > 2).any()), name
        assert defective == (over_two or degenerate or bool((directed > 1).any())), name
        assert borders == int((counts == 1).sum()), name
    assert _edge_census(F, 8) == (False, False, 0) and _edge_census(F[1:], 8)[2] == 3
    assert _edge_census(cases["an edge of three faces"], 9)[:2] == (True, True)
    # two faces back to back pass the edge test (each edge twice, in opposite directions),
    # and MeshLib would make a hole of them: the first pass's check flags repeated corners too
    from robotkit.mesh.decimate import _defective_faces

    pillow = np.vstack([F, [[8, 9, 10], [10, 9, 8]]])
    assert _edge_census(pillow, 11) == (False, False, 0)
    assert _defective_faces(pillow, 11, closed=True).nonzero()[0].tolist() == [12, 13]
    # per face, against trimesh's edge counts: the faces on an edge of three faces, on a directed
    # edge used twice, on a border (closed input), degenerate, or with another face's corners
    for name, faces in {**cases, "pillow": pillow}.items():
        m = trimesh.Trimesh(np.vstack([V, np.eye(3) + 5.0]), faces, process=False)
        und, inv, cnt = np.unique(m.edges_sorted, axis=0, return_inverse=True, return_counts=True)
        _, dinv, dcnt = np.unique(m.edges, axis=0, return_inverse=True, return_counts=True)
        slot = (cnt[inv.ravel()] != 2) | (dcnt[dinv.ravel()] > 1)
        expect = slot.reshape(-1, 3).any(axis=1) | (faces[:, 0] == faces[:, 1])
        _, rinv, rcnt = np.unique(np.sort(faces, axis=1), axis=0, return_inverse=True, return_counts=True)
        expect |= rcnt[rinv.ravel()] > 1
        got = _defective_faces(faces, 11, closed=True)
        assert got.tolist() == expect.tolist(), name
        # an edge defect between two allowed vertices is not counted
        allowed = np.zeros(11, bool)
        assert _defective_faces(faces, 11, closed=True, allowed=allowed).tolist() == expect.tolist(), name
    fin = cases["an edge of three faces"]
    allowed = np.zeros(11, bool)
    allowed[F[0, :2]] = True
    assert _defective_faces(fin, 11, closed=False).sum() == 3
    assert _defective_faces(fin, 11, closed=False, allowed=allowed).sum() == 0


def test_closed_volume_agrees_with_trimesh():
    box = trimesh.creation.box([1.0, 2.0, 3.0])
    F = np.asarray(box.faces)
    one_flipped = F.copy()
    one_flipped[3] = one_flipped[3][::-1]
    cases = [F, F[:, ::-1], F[1:], F[2:], one_flipped, np.vstack([F, F]), np.vstack([F, F[:, ::-1]])]
    for faces in cases:
        m = trimesh.Trimesh(box.vertices, faces, process=False)
        v = closed_volume(m)
        assert (v is not None) == m.is_volume
        if v is not None:
            assert v == pytest.approx(m.volume, rel=1e-14)
    torus = trimesh.creation.torus(0.2, 0.05, major_sections=64, minor_sections=32)
    assert closed_volume(torus) == pytest.approx(torus.volume, rel=1e-13)


def test_decimate_errors():
    box = trimesh.creation.box([1, 1, 1])
    with pytest.raises(ValueError, match="only 12 faces"):
        decimate(box, target_faces=100)
    with pytest.raises(ValueError, match="exactly one"):
        decimate(box, target_faces=10, ratio=0.5)
    with pytest.raises(ValueError, match="fraction of faces to keep"):
        decimate(box, ratio=1.5)
    same, report = decimate(box, target_faces=12)
    assert report["faces_after"] == 12 and report["distance"]["max"] < 1e-15


# --- convex hull -----------------------------------------------------------------------------

def test_exact_hull_of_a_box_and_determinism():
    box = trimesh.creation.box([1.0, 2.0, 3.0]).subdivide()
    hull, report = convex_hull_report(box)
    assert len(hull.vertices) == 8 and hull.is_volume and hull.is_convex
    assert hull.volume == pytest.approx(6.0, rel=1e-14) and report["method"] == "exact"
    again = convex_hull(box)
    np.testing.assert_array_equal(hull.vertices, again.vertices)
    np.testing.assert_array_equal(hull.faces, again.faces)


@pytest.mark.parametrize("budget", [16, 32, 64])
def test_hull_budget_and_error(budget):
    mesh = trimesh.creation.capsule(height=0.3, radius=0.1, count=[32, 32])
    hull, report = convex_hull_report(mesh, max_vertices=budget)
    assert len(hull.vertices) <= budget and report["vertices"] == len(hull.vertices)
    assert hull.is_volume and hull.is_convex
    # every hull vertex is a mesh vertex, so the hull is inside the exact hull
    assert set(map(tuple, np.asarray(hull.vertices))) <= set(map(tuple, np.asarray(mesh.vertices)))
    assert report["volume_ratio"] == pytest.approx(hull.volume / mesh.convex_hull.volume, rel=1e-12)
    assert report["volume_ratio"] > {16: 0.65, 32: 0.8, 64: 0.9}[budget]
    # the reported largest outside distance is the true one
    signed = np.asarray(mesh.vertices) @ hull.face_normals.T - np.einsum(
        "ij,ij->i", hull.face_normals, hull.triangles[:, 0])
    assert signed.max(axis=1).max() == pytest.approx(report["max_outside"], rel=1e-9)
    assert report["max_outside"] < {16: 0.07, 32: 0.035, 64: 0.02}[budget] * np.linalg.norm(mesh.extents)
    contained, rc = convex_hull_report(mesh, max_vertices=budget, contain=True)
    assert len(contained.vertices) <= budget and rc["scale"] > 1 and rc["volume_ratio"] > 1
    inside = np.asarray(mesh.vertices) @ contained.face_normals.T - np.einsum(
        "ij,ij->i", contained.face_normals, contained.triangles[:, 0])
    assert inside.max() <= 1e-12  # contains every vertex


def test_hull_errors():
    with pytest.raises(ValueError, match="at least 4"):
        convex_hull(trimesh.creation.box([1, 1, 1]), max_vertices=3)
    flat = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2]])
    with pytest.raises(ValueError, match="flat"):
        convex_hull(flat)


# --- CoACD -----------------------------------------------------------------------------------

@pytest.mark.slow
def test_decompose_l_shape(capfd):
    mesh = l_shape()
    t0 = time.perf_counter()
    pieces = decompose(mesh, max_hull_vertices=16)
    elapsed = time.perf_counter() - t0
    out, err = capfd.readouterr()
    assert out == "" and err == ""  # CoACD's console output is silenced at the file-descriptor level
    assert len(pieces) >= 2
    for p in pieces:
        assert p.is_volume and p.is_convex and len(p.vertices) <= 16
    report = fidelity(mesh, pieces)
    assert report["volume_ratio"] == pytest.approx(1.0, abs=0.02)
    assert report["largest_piece_vertices"] <= 16 and report["pieces"] == len(pieces)
    assert elapsed < 10
    again = decompose(mesh, max_hull_vertices=16)
    assert [p.vertices.tolist() for p in again] == [p.vertices.tolist() for p in pieces]
    tight = decompose(mesh, max_hull_vertices=8)
    assert max(len(p.vertices) for p in tight) <= 8


@pytest.mark.slow
def test_coacd_gets_the_union_of_overlapping_bodies():
    from robotkit.mesh.decompose import coacd_input

    a = trimesh.creation.box([2.0, 1.0, 1.0])
    b = trimesh.creation.box([1.0, 1.0, 2.0])
    b.apply_translation([0.5, 0.0, 0.5])
    both = trimesh.util.concatenate([a, b])  # closed, but its surfaces cross each other
    V, F, mode = coacd_input(np.asarray(both.vertices), np.asarray(both.faces), "auto")
    union = trimesh.Trimesh(V, F, process=False)
    assert mode == "off" and F.dtype == np.int32
    assert union.is_volume and len(union.split(only_watertight=False)) == 1
    assert union.volume == pytest.approx(2.0 + 2.0 - 1.0, rel=1e-12)  # the 1 x 1 x 1 overlap counted once
    for mode in ("on", "off"):  # the mesh as given
        V2, F2, got = coacd_input(np.asarray(both.vertices), np.asarray(both.faces), mode)
        assert got == mode and V2 is not None and np.array_equal(F2, both.faces)
    open_box = a.copy()
    open_box.update_faces(np.arange(len(a.faces)) > 0)
    V3, F3, got = coacd_input(np.asarray(open_box.vertices), np.asarray(open_box.faces), "auto")
    assert got == "auto" and np.array_equal(F3, open_box.faces)  # not a volume: CoACD's own remeshing
    pieces = decompose(both, max_hull_vertices=16)
    again = decompose(both, max_hull_vertices=16)
    assert [p.vertices.tobytes() for p in again] == [p.vertices.tobytes() for p in pieces]
    assert all(p.is_volume and p.is_convex and len(p.vertices) <= 16 for p in pieces)
    assert fidelity(both, pieces)["proxy_volume"] == pytest.approx(3.0, rel=0.02)  # the union, tightly


def test_coacd_input_above_the_face_limit_is_decimated_and_stays_closed():
    from robotkit.mesh.decompose import coacd_input

    torus = trimesh.creation.torus(major_radius=0.2, minor_radius=0.05, major_sections=80, minor_sections=40)
    V, F = np.asarray(torus.vertices), np.asarray(torus.faces)  # 6,400 faces
    V2, F2, mode = coacd_input(V, F, "auto", input_faces=1000)
    fewer = trimesh.Trimesh(V2, F2, process=False)
    assert mode == "off" and 980 <= len(F2) <= 1000 and fewer.is_volume
    assert fewer.volume == pytest.approx(torus.volume, rel=0.02)
    V3, F3, _ = coacd_input(V, F, "auto", input_faces=0)  # 0: never
    assert len(F3) == len(F)
    V4, F4, _ = coacd_input(V, F, "auto", input_faces=len(F))  # at the limit: as it is
    assert len(F4) == len(F)


def test_decompose_rejects_bad_parameters():
    box = trimesh.creation.box([1, 1, 1])
    with pytest.raises(ValueError, match="threshold"):
        decompose(box, threshold=0)
    with pytest.raises(ValueError, match="preprocess"):
        decompose(box, preprocess="maybe")
    with pytest.raises(ValueError, match="max_hull_vertices"):
        decompose(box, max_hull_vertices=3)


# --- primitives ------------------------------------------------------------------------------

def inside_primitive(p: Primitive, points: np.ndarray, tol: float) -> bool:
    T = np.linalg.inv(p.pose)
    q = points @ T[:3, :3].T + T[:3, 3]
    if p.kind == "box":
        return bool((np.abs(q) <= np.asarray(p.params["size"]) / 2 + tol).all())
    if p.kind == "sphere":
        return bool((np.linalg.norm(q, axis=1) <= p.params["radius"] + tol).all())
    rho = np.linalg.norm(q[:, :2], axis=1)
    half = p.params["length"] / 2
    if p.kind == "cylinder":
        return bool(((rho <= p.params["radius"] + tol) & (np.abs(q[:, 2]) <= half + tol)).all())
    dz = np.maximum(np.abs(q[:, 2]) - half, 0)
    return bool((np.hypot(rho, dz) <= p.params["radius"] + tol).all())


def test_fit_box_is_the_box():
    box = trimesh.creation.box([0.1, 0.2, 0.3])
    fit = fit_box(box)
    np.testing.assert_allclose(fit.params["size"], [0.1, 0.2, 0.3], rtol=1e-12)
    np.testing.assert_allclose(fit.pose, np.eye(4), atol=1e-12)
    assert fit.volume == pytest.approx(0.006, rel=1e-12)
    T = pose()
    fit = fit_box(moved(box, T))
    assert sorted(fit.params["size"]) == pytest.approx([0.1, 0.2, 0.3], rel=1e-9)
    np.testing.assert_allclose(fit.pose[:3, 3], T[:3, 3], atol=1e-12)
    json.dumps(fit.to_dict())


def test_fit_cylinder_sphere_capsule_give_the_analytic_parameters():
    T = pose()
    cyl = fit_cylinder(moved(trimesh.creation.cylinder(radius=0.05, height=0.4, sections=256), T))
    assert cyl.params["radius"] == pytest.approx(0.05, rel=1e-9)
    assert cyl.params["length"] == pytest.approx(0.4, rel=1e-9)
    assert abs(cyl.pose[:3, 2] @ T[:3, 2]) == pytest.approx(1.0, abs=1e-9)
    np.testing.assert_allclose(cyl.pose[:3, 3], T[:3, 3], atol=1e-9)
    assert cyl.volume == pytest.approx(math.pi * 0.05 ** 2 * 0.4, rel=1e-9)

    sph = fit_sphere(moved(trimesh.creation.icosphere(subdivisions=3, radius=0.2), T))
    assert sph.params["radius"] == pytest.approx(0.2, rel=1e-9)
    np.testing.assert_allclose(sph.pose[:3, 3], T[:3, 3], atol=1e-9)

    cap = fit_capsule(moved(trimesh.creation.capsule(height=0.4, radius=0.1, count=[32, 32]), T))
    assert cap.params["radius"] == pytest.approx(0.1, rel=1e-6)
    assert cap.params["length"] == pytest.approx(0.4, rel=1e-6)
    assert abs(cap.pose[:3, 2] @ T[:3, 2]) == pytest.approx(1.0, abs=1e-6)
    assert cap.volume == pytest.approx(math.pi * 0.01 * 0.4 + 4 / 3 * math.pi * 0.001, rel=1e-5)


def test_every_fit_contains_the_mesh():
    mesh = moved(l_shape(0), pose())
    V = np.asarray(mesh.vertices)
    for fit in (fit_box, fit_cylinder, fit_sphere, fit_capsule):
        p = fit(mesh)
        assert inside_primitive(p, V, 1e-9), p.kind
        assert p.volume >= mesh.volume
        assert p.to_mesh().is_volume


# --- fidelity --------------------------------------------------------------------------------

def test_fidelity_of_a_box_hull_is_perfect():
    box = trimesh.creation.box([0.1, 0.2, 0.3]).subdivide()
    f = fidelity(box, [convex_hull(box)])
    assert f["volume_ratio"] == pytest.approx(1.0, abs=1e-12)
    assert f["distance"]["max"] < 1e-15 and f["pieces"] == 1 and f["largest_piece_vertices"] == 8


def test_fidelity_of_a_sphere_proxied_by_its_bounding_box():
    r = 0.5
    sphere = trimesh.creation.icosphere(subdivisions=5, radius=r)
    rho, _ = shell(sphere)
    box = Primitive("box", {"size": (2 * r, 2 * r, 2 * r)}, np.eye(4), 8 * r ** 3)
    f = fidelity(sphere, [box])
    assert f["volume_method"] == "analytic" and f["largest_piece_vertices"] is None
    assert f["volume_ratio"] == pytest.approx(8 * r ** 3 / sphere.volume, rel=1e-12)
    assert f["volume_ratio"] == pytest.approx(6 / math.pi, rel=1e-3)
    d = f["distance"]
    # farthest box point from the sphere: a corner, sqrt(3) r - r; farthest sphere point: r (1 - 1/sqrt(3))
    assert 0.9 * (math.sqrt(3) - 1) * r <= d["a_to_b_max"] <= math.sqrt(3) * r - rho
    assert 0.9 * (1 - 1 / math.sqrt(3)) * r <= d["b_to_a_max"] <= (1 - 1 / math.sqrt(3)) * r + 1e-12


def test_point_triangle_distance_is_exact_on_millimetre_triangles():
    """1 mm triangles 3.7 m from the origin, points placed at known distances above the face interior
    and beside an edge: exact to 1e-9 of the triangle size (trimesh.triangles.closest_point is off by
    up to the triangle size here: its region tests have an absolute tolerance)."""
    from robotkit.mesh.decimate import point_triangle_distance

    rng = np.random.default_rng(7)
    n, size = 20000, 1e-3
    A = np.array([1.0, 2.0, 3.0]) + rng.normal(size=(n, 3)) * 0.01
    B, C = A + rng.normal(size=(n, 3)) * size, A + rng.normal(size=(n, 3)) * size
    normal = np.cross(B - A, C - A)
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    h = rng.uniform(-2, 2, n) * size
    # above the interior: a barycentric point inside plus h along the normal
    w = rng.dirichlet([1, 1, 1], n) * 0.98 + 0.02 / 3
    P = w[:, :1] * A + w[:, 1:2] * B + w[:, 2:] * C + h[:, None] * normal
    np.testing.assert_allclose(point_triangle_distance(P, A, B, C), np.abs(h), rtol=0, atol=1e-9 * size)
    # beside edge AB: a point of the edge, moved outwards in the plane by g and along the normal by h
    t = rng.uniform(0.05, 0.95, n)[:, None]
    out = np.cross(B - A, normal)
    out /= np.linalg.norm(out, axis=1)[:, None]
    out *= np.sign(np.einsum("ij,ij->i", out, A - C))[:, None]  # away from C
    g = rng.uniform(0, 2, n) * size
    P = A + t * (B - A) + g[:, None] * out + h[:, None] * normal
    np.testing.assert_allclose(point_triangle_distance(P, A, B, C), np.hypot(g, h), rtol=0, atol=1e-9 * size)
    # a degenerate triangle (all on one segment) is that segment
    d = point_triangle_distance([[0.0, 1.0, 0.0], [3.0, 0.0, 0.0]], [[0, 0, 0]] * 2, [[1, 0, 0]] * 2, [[2, 0, 0]] * 2)
    np.testing.assert_allclose(d, [1.0, 1.0], rtol=0, atol=1e-15)


def _cube(side: float, centre, subdivisions: int = 3):
    m = trimesh.creation.box([side] * 3)
    for _ in range(subdivisions):
        m = m.subdivide()
    return trimesh.Trimesh(np.asarray(m.vertices) + centre, m.faces, process=False)


def test_fidelity_exact_on_a_fine_box_and_its_hull():
    """A 5 mm box of 0.6 mm triangles, 3.7 m from the origin, against its hull: zero distance."""
    box = _cube(0.005, [1.0, 2.0, 3.0])
    f = fidelity(box, [convex_hull(box)])
    assert f["volume_ratio"] == pytest.approx(1.0, abs=1e-12)
    assert f["distance"]["max"] <= 1e-9 * 0.005 * math.sqrt(3)


def test_fidelity_exact_for_a_cube_inside_a_scaled_cube():
    """A 4 mm cube against the same cube scaled by 1.01: every point of the small cube is exactly
    0.5 % of the side from the large one; points of the large one are 0.5 % (faces) to
    0.5 % sqrt(3) (corners) from the small one.  Same as a mesh piece and as a box primitive."""
    s, c = 0.004, np.array([1.0, 2.0, 3.0])
    small = _cube(s, c)
    big = trimesh.Trimesh((np.asarray(small.vertices) - c) * 1.01 + c, small.faces, process=False)
    T = np.eye(4)
    T[:3, 3] = c
    box = Primitive("box", {"size": (1.01 * s,) * 3}, T, (1.01 * s) ** 3)
    gap, tol = 0.005 * s, 1e-9 * s
    for proxy in (big, box):
        f = fidelity(small, [proxy])
        d = f["distance"]
        assert f["volume_ratio"] == pytest.approx(1.01 ** 3, rel=1e-12)
        assert d["b_to_a_max"] == pytest.approx(gap, abs=tol) and d["b_to_a_mean"] == pytest.approx(gap, abs=tol)
        assert gap - tol <= d["a_to_b_mean"] < d["a_to_b_max"] <= gap * math.sqrt(3) + tol
        assert d["a_to_b_max"] > 1.2 * gap  # samples in the strips along the edges


def test_fidelity_of_a_sphere_against_an_icosphere_of_known_deviation():
    """An exact sphere of radius r (primitive) against an icosphere on it (vertices at r): the
    icosphere's points are r - |p - c| inside it; the sphere's farthest points are over the face
    centres, r - (smallest face-plane distance) away."""
    r, c = 0.01, np.array([1.0, 2.0, 3.0])
    ico = trimesh.creation.icosphere(subdivisions=4, radius=r)
    ico = trimesh.Trimesh(np.asarray(ico.vertices) + c, ico.faces, process=False)
    T = np.eye(4)
    T[:3, 3] = c
    sphere = Primitive("sphere", {"radius": r}, T, 4 / 3 * math.pi * r ** 3)
    f = fidelity(ico, [sphere], samples=4000)
    d, tol = f["distance"], 1e-9 * r
    pts = trimesh.sample.sample_surface(ico, 4000, seed=1)[0]  # the visual samples fidelity draws
    inside = r - np.linalg.norm(pts - c, axis=1)
    assert d["b_to_a_max"] == pytest.approx(inside.max(), abs=tol)
    assert d["b_to_a_mean"] == pytest.approx(inside.mean(), abs=tol)
    tri = np.asarray(ico.triangles) - c
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    plane = np.abs(np.einsum("ij,ij->i", tri[:, 0], normals / np.linalg.norm(normals, axis=1)[:, None]))
    deviation = r - plane.min()
    assert 0.95 * deviation <= d["a_to_b_max"] <= deviation + tol
    assert f["volume_ratio"] == pytest.approx(sphere.volume / ico.volume, rel=1e-12)


@pytest.mark.parametrize("kind,params", [("box", {"size": (0.1, 0.2, 0.3)}), ("sphere", {"radius": 0.1}),
                                         ("cylinder", {"radius": 0.1, "length": 0.3}),
                                         ("capsule", {"radius": 0.1, "length": 0.3})])
def test_primitive_samples_lie_on_the_surface_and_distances_are_analytic(kind, params):
    T = pose()
    p = Primitive(kind, params, T, 1.0)
    pts = p.sample(3000, seed=2)
    assert np.abs(p.distance(pts)).max() < 1e-15
    local = (pts - T[:3, 3]) @ T[:3, :3]
    # area-uniform: the share of points on the flat caps (cylinder) / a face pair (box)
    if kind == "cylinder":
        caps = np.isclose(np.abs(local[:, 2]), 0.15, rtol=0, atol=1e-12).mean()
        assert caps == pytest.approx(2 * 0.01 / (2 * 0.01 + 2 * 0.1 * 0.3), abs=0.03)
    if kind == "box":
        xy = np.isclose(np.abs(local[:, 2]), 0.15, rtol=0, atol=1e-12).mean()
        assert xy == pytest.approx(0.02 / (0.02 + 0.03 + 0.06), abs=0.03)
    # 1 m out along the local x axis from the centre: 1 - half-width
    far = (T[:3, :3] @ np.array([1.0, 0.0, 0.0])) + T[:3, 3]
    half = params["size"][0] / 2 if kind == "box" else params["radius"]
    assert p.distance([far])[0] == pytest.approx(1.0 - half, abs=1e-15)
    assert p.distance([T[:3, 3]])[0] == pytest.approx(min(params.get("size", [2 * half])) / 2, abs=1e-15)


def test_fidelity_unions_overlapping_pieces():
    a = trimesh.creation.box([1.0, 1.0, 1.0])
    b = moved(a, pose((0, 0, 0), (0.5, 0, 0)))
    whole = moved(trimesh.creation.box([1.5, 1.0, 1.0]), pose((0, 0, 0), (0.25, 0, 0)))
    f = fidelity(whole, [a, b])
    assert f["volume_method"] == "union"
    assert f["proxy_volume"] == pytest.approx(1.5, rel=1e-12) and f["overlap_volume"] == pytest.approx(0.5)
    assert f["volume_ratio"] == pytest.approx(1.0, rel=1e-12) and f["distance"]["max"] < 1e-12
    with pytest.raises(ValueError):
        fidelity(whole, [])
    open_box = trimesh.Trimesh(whole.vertices, whole.faces[2:], process=False)
    f = fidelity(whole, [open_box])  # an open piece has no volume: none is made up
    assert f["volume_method"] == "unavailable" and f["proxy_volume"] is None and f["volume_ratio"] is None
    assert f["distance"]["a_to_b_max"] < 1e-12  # every proxy point lies on the visual surface


# --- cache -----------------------------------------------------------------------------------

class Counter:
    def __init__(self, value):
        self.calls, self.value = 0, value

    def __call__(self):
        self.calls += 1
        return self.value


def test_cache_hit_and_misses(tmp_path):
    torus = trimesh.creation.torus(0.2, 0.05, major_sections=32, minor_sections=16)
    cache = Cache(tmp_path)
    compute = Counter(([torus, convex_hull(torus)], {"note": "two meshes", "n": 2}))
    first = cache.get_or_compute("hull", {"max_vertices": 32}, torus, compute)
    second = cache.get_or_compute("hull", {"max_vertices": 32}, torus, compute)
    assert compute.calls == 1 and cache.stats["hits"] == 1 and cache.stats["misses"] == 1
    (m1, info1), (m2, info2) = first, second
    assert info1 == info2 == {"note": "two meshes", "n": 2}
    for x, y in zip(m1, m2):
        np.testing.assert_array_equal(x.vertices, y.vertices)
        np.testing.assert_array_equal(x.faces, y.faces)
    np.testing.assert_array_equal(m1[0].vertices, torus.vertices)  # exact float64
    cache.get_or_compute("hull", {"max_vertices": 16}, torus, compute)  # other parameters
    assert compute.calls == 2
    cache.get_or_compute("hull", {"max_vertices": 32}, torus.copy().apply_scale(2.0), compute)  # other input
    assert compute.calls == 3
    other_versions = dict(cache.versions, coacd="0.0.1")
    Cache(tmp_path, versions=other_versions).get_or_compute("hull", {"max_vertices": 32}, torus, compute)
    assert compute.calls == 4
    assert cache.get_or_compute("hull", {"max_vertices": 32}, torus, compute)[1]["n"] == 2
    assert compute.calls == 4


def test_cache_keys_are_canonical(tmp_path):
    cache = Cache(tmp_path, versions={"x": "1"})
    box = trimesh.creation.box([1, 1, 1])
    assert cache.key("op", {"a": 1, "b": (1.0, 2.0)}, box) == cache.key("op", {"b": [1.0, 2.0], "a": 1}, box)
    assert cache.key("op", {"a": 1}, box) != cache.key("op2", {"a": 1}, box)
    assert cache.key("op", {"a": 1}, b"abc") != cache.key("op", {"a": 1}, b"abd")
    assert mesh_digest(box) == mesh_digest(box.copy())


@pytest.mark.parametrize("damage", ["flip_byte", "truncate", "drop_payload", "garble_manifest",
                                    "manifest_of_other_key"])
def test_cache_corrupt_entry_is_recomputed(tmp_path, damage):
    box = trimesh.creation.box([1, 2, 3])
    cache = Cache(tmp_path)
    compute = Counter(box)
    cache.get_or_compute("op", {}, b"input", compute)
    key = cache.key("op", {}, b"input")
    manifest = cache.manifest_path(key)
    payload = manifest.parent / json.loads(manifest.read_text())["payload"]["file"]
    if damage == "flip_byte":
        data = bytearray(payload.read_bytes())
        data[30] ^= 0xFF
        payload.write_bytes(bytes(data))
    elif damage == "truncate":
        payload.write_bytes(payload.read_bytes()[:-7])
    elif damage == "drop_payload":
        payload.unlink()
    elif damage == "garble_manifest":
        manifest.write_text(manifest.read_text()[:40])
    else:
        doc = json.loads(manifest.read_text())
        doc["key"] = "0" * 64
        manifest.write_text(json.dumps(doc))
    again = cache.get_or_compute("op", {}, b"input", compute)
    assert compute.calls == 2 and cache.stats["corrupt"] == 1
    np.testing.assert_array_equal(again.vertices, box.vertices)
    assert cache.get(key) is not None  # the recomputed entry is whole again
    assert len(list(manifest.parent.glob("*.bin"))) == 1


def test_cache_location(monkeypatch, tmp_path):
    monkeypatch.setenv("ROBOTKIT_CACHE", str(tmp_path / "mine"))
    assert default_root() == tmp_path / "mine"
    cache = Cache()
    cache.get_or_compute("op", {}, b"x", Counter(trimesh.creation.box([1, 1, 1])))
    assert list((tmp_path / "mine").rglob("*.json"))
    monkeypatch.delenv("ROBOTKIT_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert default_root() == tmp_path / "xdg" / "robotkit"
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert default_root() == Path.home() / ".cache" / "robotkit"


def _slow_compute_in_process(root: str, log: str, out: str):
    def compute():
        with open(log, "a") as f:
            f.write(f"{os.getpid()}\n")
        time.sleep(0.3)
        return trimesh.creation.icosphere(2)

    mesh = Cache(root, versions={"v": "1"}).get_or_compute("slow", {}, b"same", compute)
    Path(out).write_text(hashlib.sha256(stl_bytes(mesh)).hexdigest())


def test_cache_two_processes_compute_the_same_key_once(tmp_path):
    ctx = multiprocessing.get_context("fork")
    log = tmp_path / "calls.log"
    procs = [ctx.Process(target=_slow_compute_in_process, args=(str(tmp_path / "c"), str(log), str(tmp_path / f"o{i}")))
             for i in range(2)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(30)
        assert p.exitcode == 0
    assert len(log.read_text().split()) == 1
    assert (tmp_path / "o0").read_text() == (tmp_path / "o1").read_text()


# --- export ----------------------------------------------------------------------------------

@pytest.mark.slow
def test_stl_bytes_are_reproducible_across_processes():
    mesh = moved(trimesh.creation.icosphere(subdivisions=3, radius=0.1), pose())
    data = stl_bytes(mesh)
    assert data == stl_bytes(mesh.copy())
    assert len(data) == 84 + 50 * len(mesh.faces)
    code = ("import hashlib, numpy as np, trimesh, sys; sys.path.insert(0, %r);"
            "from robotkit.mesh.export import stl_bytes; from robotkit.geometry import rpy_matrix;"
            "m = trimesh.creation.icosphere(subdivisions=3, radius=0.1); T = np.eye(4);"
            "T[:3, :3] = rpy_matrix((0.3, -0.7, 1.2)); T[:3, 3] = (0.1, -0.2, 0.3); m.apply_transform(T);"
            "print(hashlib.sha256(stl_bytes(m)).hexdigest())") % str(REPO)
    other = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert other.stdout.strip() == hashlib.sha256(data).hexdigest()
    back = trimesh.load(io.BytesIO(data), file_type="stl")
    assert back.is_volume and back.volume == pytest.approx(mesh.volume, rel=1e-6)


def test_obj_bytes_are_exact_and_reproducible():
    mesh = moved(trimesh.creation.icosphere(subdivisions=2, radius=0.1), pose())
    data = obj_bytes(mesh)
    assert data == obj_bytes(mesh.copy())
    back = trimesh.load(io.BytesIO(data), file_type="obj", process=False)
    np.testing.assert_array_equal(back.vertices, mesh.vertices)
    np.testing.assert_array_equal(back.faces, mesh.faces)


def test_obj_text_is_one_line_per_vertex_and_face_in_repr():
    """obj_bytes formats every number at once; the text is the line-by-line one: ``v`` with each
    coordinate's repr (-0.0 written 0.0), ``f`` with 1-based indices, a name line when named."""
    V = np.array([[-0.0, 1e-05, 123456789.125], [0.1, -2.5e-300, 3.0], [1 / 3, 0.0, -7.0]])
    mesh = trimesh.Trimesh(V, [[0, 1, 2], [2, 1, 0]], process=False)
    lines = ["# robotkit OBJ", "o part"] + [f"v {x!r} {y!r} {z!r}" for x, y, z in (V + 0.0).tolist()]
    assert obj_bytes(mesh, "part") == ("\n".join(lines + ["f 1 2 3", "f 3 2 1"]) + "\n").encode()
    assert obj_bytes(mesh).startswith(b"# robotkit OBJ\nv 0.0 1e-05 123456789.125\n")
    assert obj_bytes(trimesh.Trimesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=int), process=False)) == b"# robotkit OBJ\n"


def test_canonical_order_ignores_the_input_order():
    box = trimesh.creation.box([1, 2, 3])
    rng = np.random.default_rng(0)
    perm = rng.permutation(len(box.vertices))
    inv = np.argsort(perm)
    shuffled = trimesh.Trimesh(np.asarray(box.vertices)[perm], np.roll(inv[box.faces][rng.permutation(12)], 1, axis=1),
                               process=False)
    a, b = canonical(box.vertices, box.faces), canonical(shuffled.vertices, shuffled.faces)
    assert stl_bytes(a) == stl_bytes(b)
