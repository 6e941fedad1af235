"""Decimation's quality guarantee (issue 33): on CAD meshes with open edges and many components,
the result is within 2 % of the target and its two-sided Hausdorff distance is at most MeshLib's
at the same face count (x1.05 for sampling noise), measured here against MeshLib (PyPI
``meshlib``) called plainly, as ``benchmarks/bench_decimate.py`` calls it, with the same sampled
distance for both."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from robotkit.mesh.decimate import decimate, point_surface_distance, surface_distance
from robotkit.mesh.io import load_mesh

REPO = Path(__file__).resolve().parents[2]
PANDA = REPO / "tests" / "data" / "meshes" / "panda"
ASSETS = REPO.parent / "shared" / "assets"
if not ASSETS.is_dir():
    ASSETS = Path("/work/shared/assets")


def meshlib_plain(mesh, target: int) -> trimesh.Trimesh:
    """MeshLib's quadric decimation with its defaults, to ``target`` faces, on a copy scaled to a
    1000-unit diagonal (MeshLib works in float32), mapped back."""
    import meshlib.mrmeshnumpy as mn
    import meshlib.mrmeshpy as mm

    V, F = np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces)
    c = 0.5 * (V.min(axis=0) + V.max(axis=0))
    k = 1000.0 / np.linalg.norm(np.ptp(V, axis=0))
    m = mn.meshFromFacesVerts(F.astype(np.int32), ((V - c) * k).astype(np.float32))
    s = mm.DecimateSettings()
    s.strategy = mm.DecimateStrategy.MinimizeError
    s.maxError = float("inf")
    s.maxDeletedFaces = max(m.topology.numValidFaces() - target, 0)
    s.packMesh = True
    mm.decimateMesh(m, s)
    v = np.asarray(mn.getNumpyVerts(m), np.float64) / k + c
    return trimesh.Trimesh(v, np.asarray(mn.getNumpyFaces(m.topology)), process=False)


def assert_guarantee(mesh, target: int, samples: int = 2000):
    out, report = decimate(mesh, target_faces=target, samples=samples)
    assert abs(report["faces_after"] - target) <= 0.02 * target, report["faces_after"]
    plain = meshlib_plain(mesh, target)
    ours, theirs = report["distance"]["max"], surface_distance(mesh, plain, samples)["max"]
    assert ours <= 1.05 * theirs, (ours, theirs, report["check"])
    return report


def test_panda_link4_to_3000_faces_is_on_target_and_no_further_than_meshlib():
    """The Panda's link4 (issue 33: 101 times MeshLib's distance, one vertex 47 mm off): 14,621
    faces, 4 components, 235 open edges, decimated to 3,000 faces as the issue did."""
    mesh = load_mesh(str(PANDA / "link4.dae"))
    assert len(trimesh.graph.connected_components(mesh.edges)) == 4
    assert len(trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1)) == 235
    assert_guarantee(mesh, 3000)


def test_the_check_is_the_exact_distance_of_the_probed_input_vertices(monkeypatch):
    """The check's distance (metres) is the largest exact distance from the vertices of every
    ``len(faces) / CHECK_POINTS``-th input face to the result, as robotkit's own exact
    point-to-triangle distance gives it (MeshLib measures in float32 on the normalised copy), and
    it is compared with 0.75 of the error MeshLib's last stage reports."""
    import robotkit.mesh.decimate as decimate_module

    monkeypatch.setattr(decimate_module, "GUARANTEE_FACTOR", float("inf"))  # keep the shortcut's result
    mesh = load_mesh(str(PANDA / "link4.dae"))
    out, report = decimate(mesh, target_faces=3000, samples=0)
    check = report["check"]
    assert check["kept"] == "shortcut" and report["prepass"] == 2.0 and check["error"] > 0
    F = np.asarray(mesh.faces)
    probed = np.unique(F[::len(F) // decimate_module.CHECK_POINTS])
    exact = point_surface_distance(np.asarray(mesh.vertices)[probed], out).max()
    diagonal = np.linalg.norm(np.ptp(mesh.vertices, axis=0))
    assert check["distance"] == pytest.approx(exact, abs=1e-6 * diagonal)


def test_a_failed_check_runs_meshlib_alone_and_keeps_its_result(monkeypatch):
    """With the bound at 0 every shortcut fails its check: MeshLib alone runs, its result is kept
    (the same faces as with no shortcut at all), and the report says so."""
    import robotkit.mesh.decimate as decimate_module

    mesh = load_mesh(str(PANDA / "link4.dae"))
    monkeypatch.setattr(decimate_module, "GUARANTEE_FACTOR", 0.0)
    out, report = decimate(mesh, target_faces=3000, samples=0)
    assert report["fallback"] is True and report["check"]["kept"] == "meshlib-alone"
    assert report["prepass"] is None and report["fast_stage"] is None
    monkeypatch.setattr(decimate_module, "PREPASS_LIMIT", 0.0)  # no first pass and no fast stage:
    monkeypatch.setattr(decimate_module, "FAST_STAGE", None)  # MeshLib alone at once
    alone, again = decimate(mesh, target_faces=3000, samples=0)
    assert again["check"] is None and again["fallback"] is False
    assert np.array_equal(alone.faces, out.faces) and np.array_equal(alone.vertices, out.vertices)
    monkeypatch.undo()
    monkeypatch.setattr(decimate_module, "GUARANTEE_FACTOR", float("inf"))
    fast, report = decimate(mesh, target_faces=3000, samples=0)
    assert report["fallback"] is False and report["check"]["kept"] == "shortcut" and report["prepass"] == 2.0


@pytest.mark.slow
def test_panda_link4_at_a_tenth_meets_the_guarantee():
    """link4 at a tenth of its faces (1,462).  (link0, 20,483 faces, the other Panda mesh kept
    here, does not meet it: 1.26 times MeshLib's distance at 3,000 faces with 4,000 samples, 1.07
    at 2,048 with 2,000; see docs/performance.md, *Issue 33*.)"""
    assert_guarantee(load_mesh(str(PANDA / "link4.dae")), 1462)


KINOVA = sorted((ASSETS / "menagerie" / "kinova_gen3" / "assets").glob("*.stl"))


@pytest.mark.slow
@pytest.mark.skipif(not KINOVA, reason="shared assets not present")
@pytest.mark.parametrize("path", KINOVA, ids=lambda p: p.name)
def test_kinova_meshes_at_a_tenth_meet_the_guarantee(path):
    mesh = load_mesh(str(path))
    if len(mesh.faces) < 1000:
        pytest.skip("under 1,000 faces (the benchmark's floor)")
    assert_guarantee(mesh, max(4, round(0.1 * len(mesh.faces))))
