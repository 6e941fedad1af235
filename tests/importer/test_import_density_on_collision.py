"""Issue 32, ANYmal B (example-robot-data): check judges a link's implied density on its visual
geometry when closed, else on its collision geometry; the import judged it on the visual only, so
the base's placeholder mass (1e-6 kg on an open mesh and closed boxes: 2.5e-5 kg/m^3) was an error
check named and the import never mentioned.  It is now reported, on the volume check uses, whether
the link's tensor is kept or repaired."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from robotkit.importer import import_file

TENSORS = {"kept": 'ixx="1e-9" ixy="0" ixz="0" iyy="1e-9" iyz="0" izz="1e-9"',
           "repaired": 'ixx="1e-6" ixy="1e-6" ixz="1e-6" iyy="1e-6" iyz="1e-6" izz="1e-6"'}


def _open_shell(path):
    """A cube with a fin: an edge shared by three faces, so no repair closes it."""
    box = trimesh.creation.box((0.2, 0.2, 0.2))
    a, b = box.edges_unique[0]
    trimesh.Trimesh(np.vstack([box.vertices, [[0.3, 0.3, 0.3]]]),
                    np.vstack([box.faces, [[a, b, len(box.vertices)]]]), process=False).export(path)


@pytest.mark.parametrize("tensor", sorted(TENSORS))
def test_a_placeholder_mass_is_reported_on_the_collision_volume(tmp_path, tensor):
    _open_shell(tmp_path / "shell.stl")
    urdf = tmp_path / "body.urdf"
    urdf.write_text(f"""<?xml version="1.0"?>
<robot name="body">
  <link name="base">
    <visual><geometry><mesh filename="shell.stl"/></geometry></visual>
    <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
    <inertial><mass value="1e-6"/><inertia {TENSORS[tensor]}/></inertial>
  </link>
</robot>
""", encoding="utf-8")
    result = import_file(urdf, tmp_path / "recipe" / "robot.yaml")
    assert [w.split("body.urdf:3: ", 1)[-1] for w in result.warnings if "implies" in w] == [
        "link 'base': the original's mass 1e-06 kg over its geometry's 0.008 m^3 implies 0.000125 kg/m^3, "
        "below 10 (the density or mass is far too low): kept (check reports it)"]
