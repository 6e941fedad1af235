"""Issue 32, go1 (example-robot-data): the import's test of whether a mesh is a closed volume
(``open_mesh: hull`` where an inertial is computed from it) ran robotkit's whole mesh repair on
every mesh, and its winding fix is a loop over faces: go1's 351k-face trunk.dae, which has edges
shared by four faces, kept the import busy past 900 s.  A mesh with an edge shared by more than two
faces after the repair's clean-up is not closed whatever the repair does; the import now says so
without running it, and its answer is the repair's on every shape."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from robotkit.errors import MeshError
from robotkit.importer.meshes import mesh_is_closed, never_volume
from robotkit.mesh.io import load_mesh, volume_mesh


def _box(offset=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    return trimesh.creation.box((0.1, 0.1, 0.1), trimesh.transformations.translation_matrix(offset))


def _shapes() -> dict[str, trimesh.Trimesh]:
    box = _box()
    holed = trimesh.Trimesh(box.vertices, box.faces[:-1], process=False)
    flipped = trimesh.Trimesh(box.vertices, np.vstack([box.faces[:6], box.faces[6:, ::-1]]), process=False)
    doubled = trimesh.Trimesh(box.vertices, np.vstack([box.faces, box.faces[:1]]), process=False)
    # two cubes touching along one edge (x = y = 0.05): that edge is shared by four faces
    touching = trimesh.util.concatenate([box, _box((0.1, 0.1, 0.0))])
    touching.merge_vertices()
    # a fin: one triangle on an edge of the cube, which three faces then share
    a, b = box.edges_unique[0]
    fin = trimesh.Trimesh(np.vstack([box.vertices, [[0.3, 0.3, 0.3]]]),
                          np.vstack([box.faces, [[a, b, len(box.vertices)]]]), process=False)
    return {"closed": box, "one face missing": holed, "half the faces flipped": flipped,
            "a face twice": doubled, "cubes touching on an edge": touching, "a fin": fin}


@pytest.mark.parametrize("shape", sorted(_shapes()))
def test_the_shortcut_agrees_with_the_repair(tmp_path, shape):
    path = tmp_path / "part.stl"
    _shapes()[shape].export(path)
    mesh = load_mesh(str(path))
    try:
        volume_mesh(mesh, "error", "part.stl")
        repaired_closed = True
    except MeshError:
        repaired_closed = False
    assert not (never_volume(mesh) and repaired_closed)
    assert mesh_is_closed(str(path), (1.0, 1.0, 1.0)) is repaired_closed


@pytest.mark.parametrize("shape, expected", [("closed", False), ("one face missing", False),
                                             ("half the faces flipped", False), ("a face twice", False),
                                             ("cubes touching on an edge", True), ("a fin", True)])
def test_an_edge_of_more_than_two_faces_is_never_a_volume(tmp_path, shape, expected):
    path = tmp_path / "part.stl"
    _shapes()[shape].export(path)
    assert never_volume(load_mesh(str(path))) is expected
