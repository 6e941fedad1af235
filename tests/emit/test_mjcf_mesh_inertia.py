"""MuJoCo computes an inertia for every mesh asset, even one whose geom carries no mass: a
visual mesh drawn open or misoriented (Alex's 'nub', example-robot-data) or tiny has no volume
MuJoCo accepts ("mesh volume is too small"), so the MJCF gives visual meshes the inertia of a
thin shell."""

from __future__ import annotations

import numpy as np
import trimesh

from conftest import write_recipe
from robotkit.pipeline.runner import build
from validators import mujoco


def test_a_tiny_visual_mesh_loads_in_mujoco(tmp_path):
    mj = mujoco()
    # a 4 um cube: 6.4e-17 m^3, under MuJoCo's least volume (1e-15) as a solid
    speck = trimesh.creation.box([4e-6, 4e-6, 4e-6])
    speck.apply_translation([2e-6, 2e-6, 2e-6])
    recipe = write_recipe(tmp_path, """
        robot: speckd
        links:
          base:
            visual: {mesh: speck.stl}
            collision: {box: {size: [0.1, 0.1, 0.01]}}
            inertial: {mass: 1, inertia: {ixx: 0.001, iyy: 0.001, izz: 0.001}}
        """, meshes={"speck.stl": speck})
    build([recipe], tmp_path / "out")
    mjcf = tmp_path / "out" / "speckd" / "mjcf" / "speckd.xml"
    assert '<mesh name="speck" file="visual/speck.stl" inertia="shell"/>' in mjcf.read_text()
    model = mj.MjModel.from_xml_path(str(mjcf))
    data = mj.MjData(model)
    mj.mj_forward(model, data)
    # the cube stays where the recipe puts it: its vertices' bounds in the world
    geom = next(i for i in range(model.ngeom) if model.geom_dataid[i] >= 0)
    mesh = model.geom_dataid[geom]
    start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
    world = data.geom_xpos[geom] + model.mesh_vert[start:start + count] @ data.geom_xmat[geom].reshape(3, 3).T
    lift = data.xpos[1][2]
    np.testing.assert_allclose(world.min(axis=0) - [0, 0, lift], [0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(world.max(axis=0) - [0, 0, lift], [4e-6, 4e-6, 4e-6], atol=1e-12)
