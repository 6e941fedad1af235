"""The lints read binary STL and plain OBJ with numpy (no trimesh on check's main path): the same
vertices, faces and closedness as trimesh's reading (``robotkit.mesh.io.load_mesh``), and
anything else falls back to trimesh with the same facts."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from robotkit.check.lints import mesh_facts, closed_and_wound, plain_mesh
from robotkit.mesh.export import obj_bytes, stl_bytes
from robotkit.mesh.io import load_mesh


def same_as_trimesh(path: Path) -> None:
    V, F = plain_mesh(path)
    mesh = load_mesh(str(path))
    assert np.array_equal(V, mesh.vertices) and np.array_equal(F, mesh.faces)
    assert closed_and_wound(F) == (mesh.is_watertight and mesh.is_winding_consistent)


@pytest.mark.parametrize("folder", ["ur_description/meshes/ur5/collision", "turret_bot/meshes"])
def test_asset_stl_read_as_trimesh_reads_it(assets, folder):
    files = sorted((assets / folder).rglob("*.stl"))
    assert files
    for path in files:
        same_as_trimesh(path)


def test_robotkit_obj_and_stl_read_as_trimesh_reads_them(tmp_path):
    box = trimesh.creation.box((0.1, 0.2, 0.3))
    for name, data in (("box.obj", obj_bytes(box)), ("box.stl", stl_bytes(box))):
        (tmp_path / name).write_bytes(data)
        same_as_trimesh(tmp_path / name)
        pts, props, faces = mesh_facts(tmp_path / name, np.ones(3))
        assert faces == 12 and props.volume == pytest.approx(0.006, rel=1e-6)
        assert np.ptp(pts, axis=0) == pytest.approx([0.1, 0.2, 0.3], rel=1e-6)


def test_closed_and_wound_as_trimesh_says():
    box = trimesh.creation.box((1, 1, 1))
    F = np.asarray(box.faces)
    assert closed_and_wound(F)
    assert not closed_and_wound(F[1:])  # open: a face missing
    flipped = F.copy()
    flipped[0] = flipped[0, ::-1]
    assert not closed_and_wound(flipped)  # one face wound the other way
    assert not closed_and_wound(np.vstack([F, F]))  # every edge in four faces
    for faces in (F[1:], flipped, np.vstack([F, F])):
        mesh = trimesh.Trimesh(box.vertices, faces, process=False)
        assert not (mesh.is_watertight and mesh.is_winding_consistent)


def test_other_files_go_through_trimesh_with_the_same_facts(tmp_path):
    box = trimesh.creation.box((0.1, 0.2, 0.3))
    (tmp_path / "ascii.stl").write_bytes(trimesh.exchange.stl.export_stl_ascii(box).encode())
    (tmp_path / "normals.obj").write_text(trimesh.exchange.obj.export_obj(box, include_normals=True))
    (tmp_path / "plain.stl").write_bytes(stl_bytes(box))
    _, plain, _ = mesh_facts(tmp_path / "plain.stl", np.ones(3))
    for name in ("ascii.stl", "normals.obj"):
        assert plain_mesh(tmp_path / name) is None
        pts, props, faces = mesh_facts(tmp_path / name, np.ones(3))
        assert faces == 12 and props.volume == pytest.approx(plain.volume, rel=1e-6)
        assert props.inertia == pytest.approx(plain.inertia, rel=1e-6, abs=1e-12)
    (tmp_path / "short.stl").write_bytes(stl_bytes(box)[:-10])  # truncated: trimesh's path says it cannot
    assert plain_mesh(tmp_path / "short.stl") is None
    assert mesh_facts(tmp_path / "short.stl", np.ones(3)) == (None, None, 0)


def test_reading_a_build_imports_no_trimesh(tmp_path):
    """trimesh costs 0.8 s of CPU to import: a URDF whose meshes are binary STL and plain OBJ is
    read without it."""
    import subprocess
    import sys

    box = trimesh.creation.box((0.1, 0.2, 0.3))
    (tmp_path / "a.stl").write_bytes(stl_bytes(box))
    (tmp_path / "b.obj").write_bytes(obj_bytes(box))
    (tmp_path / "r.urdf").write_text('<robot name="r"><link name="l">'
                                     '<visual><geometry><mesh filename="a.stl"/></geometry></visual>'
                                     '<collision><geometry><mesh filename="b.obj"/></geometry></collision>'
                                     '</link></robot>')
    code = ("import sys; from pathlib import Path; from robotkit.check.lints import read_urdf_facts; "
            f"links, _, notes = read_urdf_facts(Path({str(tmp_path / 'r.urdf')!r})); "
            "assert len(links[0].geoms) == 2 and not notes; print('trimesh' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
