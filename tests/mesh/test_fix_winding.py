"""robotkit.mesh.repair.fix_winding flips the same faces as trimesh.repair.fix_winding, face for
face, on meshes whose walk order matters (several bodies, holes, a one-sided Moebius band, a
non-manifold edge), and a real Menagerie mesh."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from robotkit.mesh.io import load_mesh
from robotkit.mesh.repair import fix_winding, repair

MENAGERIE = Path(__file__).resolve().parents[3] / "shared" / "assets" / "menagerie"


def _flipped(mesh: trimesh.Trimesh, fraction: float, seed: int) -> trimesh.Trimesh:
    F = np.array(mesh.faces)
    pick = np.random.default_rng(seed).random(len(F)) < fraction
    pick[seed % len(F)] = True  # one face at least
    F[pick] = F[pick][:, ::-1]
    return trimesh.Trimesh(np.array(mesh.vertices), F, process=False)


def _moebius(n: int = 24) -> trimesh.Trimesh:
    """A triangulated Moebius band: no consistent winding exists, so the walk decides the result."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    V = np.concatenate([np.stack([(1 + s * np.cos(t / 2)) * np.cos(t), (1 + s * np.cos(t / 2)) * np.sin(t),
                                  s * np.sin(t / 2)], axis=1) for s in (-0.3, 0.3)])
    F = []
    for i in range(n):
        j = (i + 1) % n
        a, b, c, d = (i, j, n + i, n + j) if j else (i, n + j, n + i, j)  # the half twist at the seam
        F += [[a, b, d], [a, d, c]]
    return trimesh.Trimesh(V, np.array(F), process=False)


def _cases():
    sphere = trimesh.creation.icosphere(3)
    two = trimesh.util.concatenate([sphere, trimesh.creation.box(extents=(1, 2, 3)).apply_translation((4, 0, 0))])
    open_box = trimesh.creation.box()
    open_box = trimesh.Trimesh(open_box.vertices, open_box.faces[2:], process=False)
    fin = trimesh.Trimesh(np.vstack([sphere.vertices, [[0, 0, 2.0]]]),  # a third face on a sphere's edge
                          np.vstack([sphere.faces, [[*sphere.faces[0][:2], len(sphere.vertices)]]]), process=False)
    boxes = trimesh.util.concatenate([trimesh.creation.box().apply_translation((3 * i, 0, 0)) for i in range(40)])
    shuffled = trimesh.Trimesh(boxes.vertices, boxes.faces[np.random.default_rng(5).permutation(len(boxes.faces))],
                               process=False)  # parts whose walk starts where networkx's set of their faces does
    for name, mesh in (("sphere", sphere), ("two bodies", two), ("open box", open_box), ("fin", fin),
                       ("moebius", _moebius()), ("forty boxes", shuffled)):
        for fraction, seed in ((0.01, 0), (0.5, 1), (0.5, 2)):
            yield pytest.param(_flipped(mesh, fraction, seed), id=f"{name}-{fraction}-{seed}")
    yield pytest.param(_moebius(), id="moebius-as-built")


@pytest.mark.parametrize("mesh", list(_cases()))
def test_fix_winding_flips_the_faces_trimesh_flips(mesh):
    ours, theirs = mesh.copy(), mesh.copy()
    assert not mesh.is_winding_consistent
    fix_winding(ours)
    trimesh.repair.fix_winding(theirs)
    assert np.array_equal(np.asarray(ours.faces), np.asarray(theirs.faces))
    assert not np.array_equal(np.asarray(ours.faces), np.asarray(mesh.faces))  # it did flip some


def test_fix_winding_of_a_consistent_mesh_changes_nothing():
    box = trimesh.creation.box()
    faces = np.array(box.faces)
    fix_winding(box)
    assert np.array_equal(box.faces, faces)


@pytest.mark.skipif(not (MENAGERIE / "agility_cassie").is_dir(), reason="the shared Menagerie set is absent")
def test_repair_of_cassies_tarsus_flips_the_faces_trimesh_flips():
    """The mesh whose winding repair cost Cassie's import 1.5 s: the same 4 faces flipped."""
    mesh = load_mesh(str(MENAGERIE / "agility_cassie" / "assets" / "tarsus.obj"))
    fixed, report = repair(mesh)
    assert report["faces_flipped"] == 4 and report["winding_consistent"]
    reference = _flipped(mesh, 0.5, 3)
    ours, theirs = reference.copy(), reference.copy()
    fix_winding(ours)
    trimesh.repair.fix_winding(theirs)
    assert np.array_equal(np.asarray(ours.faces), np.asarray(theirs.faces))
