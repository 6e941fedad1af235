"""The input's closedness read from MeshLib's own mesh (issue 33: the numpy edge census was 2-5 %
of a decimation's time): a hole in MeshLib's mesh of every face means an open input; no hole
means a closed input only where MeshLib's mesh is the input's own (no vertex split, no two edges
between the same two vertices); otherwise, or where MeshLib dropped a face, it does not answer
and ``decimate`` asks the census.  Where it answers, its answer is the census's, and
``is_volume_before`` is checked against trimesh's ``is_volume`` (an independent reference) in
every case."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from robotkit.mesh.decimate import CLOSED, _built_closed, _edge_census, decimate


def built(V, F):
    import meshlib.mrmeshnumpy as mn

    F = np.asarray(F, dtype=np.int64)
    m = mn.meshFromFacesVerts(np.ascontiguousarray(F, dtype=np.int32), np.ascontiguousarray(V, dtype=np.float32))
    return _built_closed(m.topology, F)


def sphere():
    s = trimesh.creation.icosphere(subdivisions=3)
    return np.asarray(s.vertices, np.float64), np.asarray(s.faces, np.int64)


def cases() -> dict:
    """name -> (V, F, what MeshLib's mesh says: True, False or None for 'ask the census')."""
    V, F = sphere()
    n = len(V)
    shifted = np.vstack([V, V + [2.0, 0.0, 0.0]])
    touching = np.vstack([F, F + n])
    a, b = np.argmax(V[:, 0]), np.argmin(V[:, 0])  # the first sphere's +x pole, the second's -x pole
    touching[touching == n + b] = a
    tri = F[0]
    return {
        "closed": (V, F, True),
        "unused vertices after the last": (np.vstack([V, V[:7] + 5.0]), F, True),
        "inside out": (V, F[:, ::-1], True),
        "one face removed": (V, F[1:], False),
        # vertices split by MeshLib, holes left: open
        "one face flipped": (V, np.vstack([F[:1, ::-1], F[1:]]), False),
        "a face twice": (V, np.vstack([F, F[:1]]), False),
        "two faces back to back": (V, np.vstack([F, F[:1, ::-1]]), False),
        "an edge of three faces": (np.vstack([V, [[3.0, 3.0, 3.0]]]), np.vstack([F, [[tri[0], tri[1], n]]]), False),
        # no answer: a face dropped; a vertex split and no hole (closed, by the census)
        "a degenerate face added": (V, np.vstack([F, [[tri[0], tri[0], tri[1]]]]), None),
        "two spheres touching at a vertex": (shifted, touching, None),
    }


@pytest.mark.parametrize("name", list(cases()))
def test_meshlib_answers_only_where_its_mesh_is_the_inputs_own_and_then_as_the_census(name):
    V, F, expected = cases()[name]
    got = built(V, F)
    assert got is expected
    if got is not None:
        assert got == (_edge_census(np.asarray(F), len(V)) == CLOSED)


@pytest.mark.parametrize("name", list(cases()))
def test_is_volume_before_is_trimeshs_is_volume_either_way(name):
    V, F, _ = cases()[name]
    mesh = trimesh.Trimesh(V, F, process=False)
    out, report = decimate(mesh, target_faces=len(F) // 4, samples=0)
    assert report["is_volume_before"] is bool(mesh.is_volume)
    if mesh.is_volume:
        assert report["volume_before"] == pytest.approx(mesh.volume, rel=1e-12)
    assert report["is_volume_after"] is bool(out.is_volume)


def test_a_fin_of_two_faces_back_to_back_is_not_taken_for_closed():
    """A fin on an edge (two faces back to back, as on the TIAGo's ``arm_1.stl``: the edge then
    has four faces, two each way): MeshLib adds every face with no vertex split, as two edges
    between the same two vertices, and calls the mesh closed; the census does not, nor does
    trimesh, and :func:`_built_closed` leaves it to the census (``hasMultipleEdges``)."""
    import meshlib.mrmeshnumpy as mn
    import meshlib.mrmeshpy as mm

    V, F = sphere()
    a, b, _ = F[0]
    V = np.vstack([V, 0.65 * (V[a] + V[b])])
    fin = [[b, a, len(V) - 1], [a, b, len(V) - 1]]
    F = np.vstack([F[:1], fin, F[1:]])  # in this order MeshLib keeps the fin as a second edge a-b
    m = mn.meshFromFacesVerts(np.ascontiguousarray(F, dtype=np.int32), np.ascontiguousarray(V, dtype=np.float32))
    top = m.topology
    assert top.numValidFaces() == len(F) and top.vertSize() == len(V)
    assert top.isClosed() and mm.hasMultipleEdges(top)
    assert built(V, F) is None and _edge_census(F, len(V)) != CLOSED
    mesh = trimesh.Trimesh(V, F, process=False)
    assert not mesh.is_volume
    assert decimate(mesh, target_faces=300, samples=0)[1]["is_volume_before"] is False
