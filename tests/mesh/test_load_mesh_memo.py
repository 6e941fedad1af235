"""load_mesh keeps a parsed file for the process (robotkit.mesh.io._parsed): a second load, at
another scale, gives what a first load gives, a changed file is read again, and a loaded mesh
changed by its caller leaves the next load alone."""

from __future__ import annotations

import os

import numpy as np
import trimesh

from robotkit.mesh.export import stl_bytes
from robotkit.mesh.io import PARSED, load_mesh


def test_a_second_load_is_the_first_and_a_changed_file_is_read_again(tmp_path):
    path = tmp_path / "part.stl"
    path.write_bytes(stl_bytes(trimesh.creation.box(extents=(1, 2, 3))))
    PARSED.clear()
    first = load_mesh(str(path), (1, -1, 1))
    assert len(PARSED) == 1
    first.vertices[:] = 0.0  # the caller's copy
    again = load_mesh(str(path), (1, -1, 1))
    PARSED.clear()
    fresh = load_mesh(str(path), (1, -1, 1))
    assert np.array_equal(again.vertices, fresh.vertices) and np.array_equal(again.faces, fresh.faces)
    assert again.volume > 0 and np.allclose(again.extents, (1, 2, 3))

    tmp = tmp_path / "new.stl"
    tmp.write_bytes(stl_bytes(trimesh.creation.box(extents=(4, 2, 3))))
    os.replace(tmp, path)
    assert np.allclose(load_mesh(str(path)).extents, (4, 2, 3))
