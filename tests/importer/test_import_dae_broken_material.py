"""Issue 32, ANYmal B and ANYmal with Kinova (example-robot-data): anymal_foot.dae, a Blender
export whose textured material's effect is missing, was refused as holding no triangles.
pycollada drops a whole node whose ``<bind_material>`` names a material the file lacks; Assimp
(RViz, Gazebo) draws the node's geometry with a default material, and so does robotkit now,
with the node's transform (here a millimetre-to-metre scale) applied."""

from __future__ import annotations

import yaml

from robotkit.importer import import_file
from robotkit.mesh.io import load_mesh

# a tetrahedron in millimetres, scaled to metres by its node, bound to a material whose effect
# the file does not define (as anymal_foot.dae's carbon_fibre_001-material)
DAE = """<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_materials>
    <material id="carbon-material" name="carbon"><instance_effect url="#carbon-effect"/></material>
  </library_materials>
  <library_geometries>
    <geometry id="tetra-mesh" name="tetra">
      <mesh>
        <source id="tetra-positions">
          <float_array id="tetra-positions-array" count="12">0 0 0 100 0 0 0 100 0 0 0 100</float_array>
          <technique_common><accessor source="#tetra-positions-array" count="4" stride="3">
            <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
          </accessor></technique_common>
        </source>
        <vertices id="tetra-vertices"><input semantic="POSITION" source="#tetra-positions"/></vertices>
        <triangles material="carbon-material" count="4">
          <input semantic="VERTEX" source="#tetra-vertices" offset="0"/>
          <p>0 2 1 0 1 3 0 3 2 1 2 3</p>
        </triangles>
      </mesh>
    </geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="Scene" name="Scene">
      <node id="foot" name="foot" type="NODE">
        <matrix sid="transform">0.001 0 0 0 0 0.001 0 0 0 0 0.001 0 0 0 0 1</matrix>
        <instance_geometry url="#tetra-mesh" name="foot">
          <bind_material><technique_common>
            <instance_material symbol="carbon-material" target="#carbon-material"/>
          </technique_common></bind_material>
        </instance_geometry>
      </node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#Scene"/></scene>
</COLLADA>
"""


def test_a_node_bound_to_a_missing_material_keeps_its_triangles(tmp_path):
    path = tmp_path / "foot.dae"
    path.write_text(DAE, encoding="utf-8")
    mesh = load_mesh(str(path))
    assert len(mesh.faces) == 4
    assert mesh.is_volume
    assert mesh.bounds.round(6).tolist() == [[0.0, 0.0, 0.0], [0.1, 0.1, 0.1]]
    assert abs(mesh.volume - 0.1 ** 3 / 6) < 1e-9


def test_a_robot_with_that_mesh_imports(tmp_path):
    (tmp_path / "foot.dae").write_text(DAE, encoding="utf-8")
    urdf = tmp_path / "leg.urdf"
    urdf.write_text('<?xml version="1.0"?>\n<robot name="leg">\n  <link name="foot">\n    <visual><geometry>'
                    '<mesh filename="foot.dae"/></geometry></visual>\n  </link>\n</robot>\n', encoding="utf-8")
    out = tmp_path / "recipe" / "robot.yaml"
    import_file(urdf, out)
    recipe = yaml.safe_load(out.read_text(encoding="utf-8"))
    assert recipe["links"]["foot"]["visual"]["mesh"].endswith("foot.dae")
