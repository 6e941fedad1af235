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


MENAGERIE = os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "assets", "menagerie")


def test_an_obj_robotkit_writes_is_kept_as_trimesh_reads_it_back(tmp_path):
    """convert_mesh keeps the OBJ it writes as parsed (robotkit.mesh.io.remember_written_obj), so
    that the MJCF's task does not parse it again: what it keeps is what trimesh reads from the
    file, bit for bit (-0.0 written and kept as 0.0), for a mesh with a -0.0 coordinate and
    unreferenced vertices, a mirroring scale, and shared Menagerie meshes (OBJ with texture
    coordinates, STL) when the assets are there."""
    from robotkit.pipeline.actions import convert_mesh

    own = tmp_path / "own.obj"
    own.write_text("v -0.0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 5 5 5\nvt 0 0\nf 1/1 2/1 3/1\nf 1/1 3/1 4/1\n"
                   "f 1/1 4/1 2/1\nf 2/1 4/1 3/1\n")
    cases = [(str(own), (1, 1, 1)), (str(own), (0.001, -0.001, 0.001))]
    for name in ("agility_cassie/assets/foot.obj", "wonik_allegro/assets/base_link.stl",
                 "robotiq_2f85/assets/base_mount.stl"):
        path = os.path.join(MENAGERIE, name)
        if os.path.isfile(path):
            cases.append((path, (1, 1, 1)))
            cases.append((path, (-1, 1, 1)))
    for i, (source, scale) in enumerate(cases):
        target = str(tmp_path / f"out{i}.obj")
        PARSED.clear()
        convert_mesh(source, target, list(scale))
        kept = [entry for key, entry in PARSED.items() if key[0] == os.path.realpath(target)]
        assert len(kept) == 1
        PARSED.clear()
        load_mesh(target)
        (read,) = PARSED.values()
        for a, b in zip(kept[0], read):
            assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes(), (source, scale)
    PARSED.clear()
