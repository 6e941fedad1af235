"""Issue 14: the inertia policy (robotkit.model.inertia_policy), one rule set for import, build
and check: known answers for each repair, and the recipe keys that choose it."""

from __future__ import annotations

import numpy as np
import pytest

from robotkit.errors import RobotkitError
from robotkit.model import inertia_policy as ip
from robotkit.model.load import load_robots
from tests.conftest import write_recipe


def test_a_physical_tensor_is_kept():
    I = np.diag([0.02, 0.03, 0.04])
    assert ip.defects(2.0, I) == []
    fixed = ip.repair(2.0, I, 2.0)
    assert fixed.changes == () and (fixed.inertia == I).all() and fixed.mass == 2.0


REPAIRED_ARM = np.diag([0.02, 0.02, 0.04]) + np.diag([1, 1, -1]) * 0.05 * ip.TRIANGLE_TOL / 3
"""0.01, 0.01, 0.05 repaired: a + b ends TRIANGLE_TOL of c above c, not on it."""


def test_the_triangle_inequality_is_met_with_the_least_change():
    # excess 0.05 - 0.02 = 0.03: a third of it off the largest moment, a third onto each other one
    fixed = ip.repair(1.0, np.diag([0.01, 0.01, 0.05]), 1.0)
    assert np.allclose(fixed.inertia, REPAIRED_ARM, rtol=0, atol=1e-15)
    assert fixed.changes == ("principal moments 0.01, 0.01, 0.05 moved to 0.02, 0.02, 0.04 to meet the "
                             "triangle inequality",)
    assert ip.defects(1.0, fixed.inertia) == []


def test_a_negative_moment_is_raised_and_the_axes_kept():
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90 degrees about z
    I = R @ np.diag([-1e-3, 2e-3, 2e-3]) @ R.T
    assert ip.defects(1.0, I) == ["inertia is not positive definite (principal moments -0.001, 0.002, 0.002)"]
    fixed = ip.repair(1.0, I, 1.0)
    # floor: a 1 mm sphere at 1 kg is 4e-7, below a thousandth of 2e-3 (2e-6): 4e-7 wins; the
    # triangle inequality then holds (4e-7 + 2e-3 >= 2e-3)
    vals, vecs = np.linalg.eigh(fixed.inertia)
    assert np.allclose(vals, [4e-7, 2e-3, 2e-3], rtol=1e-12, atol=0)
    assert np.allclose(np.abs(vecs[:, 0]), [0.0, 1.0, 0.0])  # the smallest moment stays along y
    assert ip.defects(1.0, fixed.inertia) == []


def test_a_zero_mass_and_tensor_become_a_small_sphere():
    assert ip.defects(0.0, np.zeros((3, 3))) == ["mass is 0", "inertia is zero"]
    fixed = ip.repair(0.0, np.zeros((3, 3)), 1e-3)
    assert fixed.mass == 1e-3 and np.allclose(fixed.inertia, np.eye(3) * 4e-10, rtol=1e-12, atol=0)
    assert fixed.changes == ("mass 0 kg raised to 0.001 kg", "principal moments 0, 0, 0 raised to at least 4e-10 kg m^2")


RECIPE = """
robot: pol
{policy}
links:
  base:
    visual: {{box: {{size: [0.1, 0.1, 0.1]}}}}
  arm:
    visual: {{box: {{size: [0.1, 0.1, 0.4]}}}}
    inertial: {{mass: 1, inertia: {{ixx: 0.01, iyy: 0.01, izz: 0.05}}{link_policy}}}
joints:
  j1: {{type: continuous, parent: base, child: arm}}
"""


def test_the_recipe_chooses_the_policy(tmp_path):
    keep = write_recipe(tmp_path, RECIPE.format(policy="", link_policy=""), "keep.yaml")
    with pytest.raises(RobotkitError) as info:
        load_robots([keep])
    assert info.value.lines() == [f"{keep}:8: links.arm.inertial.inertia: principal moments 0.01, 0.01, 0.05 "
                                  "violate the triangle inequality (no real body has them; 'policy: repair', "
                                  "'recompute' or 'estimate' gives the link a physical one)"]
    for name, policy, link_policy in (("all.yaml", "inertia_policy: repair", ""),
                                      ("link.yaml", "", ", policy: repair")):
        recipe = write_recipe(tmp_path, RECIPE.format(policy=policy, link_policy=link_policy), name)
        (_, robot), = load_robots([recipe])
        arm = robot.link("arm").inertial
        assert np.allclose(arm.tensor(), REPAIRED_ARM, rtol=0, atol=1e-15), name
    # a link may keep what the recipe would repair
    mixed = write_recipe(tmp_path, RECIPE.format(policy="inertia_policy: repair", link_policy=", policy: keep"),
                         "mixed.yaml")
    with pytest.raises(RobotkitError):
        load_robots([mixed])


# ---------------------------------------------------------------- recompute and estimate (build)


def _built_inertials(recipe, out):
    """{link: (mass, com, 3x3 tensor)} of the built URDF, after checking that the SDF and the MJCF
    carry the same masses and tensors (robotkit.check.equivalence, at 1e-9)."""
    import xml.etree.ElementTree as ET

    from robotkit.pipeline.runner import build
    from robotkit.check.equivalence import equivalence
    from tests.validators import mujoco, require

    result = build([recipe], out)
    assert not result.errors, result.errors
    robot_dir = next(p for p in out.iterdir() if p.is_dir() and not p.name.startswith("."))
    require("ign")
    mujoco()
    found = equivalence(robot_dir, tol=1e-9, configs=5)
    assert found == {k: [] for k in found}, found
    urdf = ET.parse(robot_dir / "urdf" / f"{robot_dir.name}.urdf").getroot()
    out_ = {}
    for link in urdf.iter("link"):
        el = link.find("inertial")
        if el is None:
            continue
        t = {k: float(v) for k, v in el.find("inertia").attrib.items()}
        I = np.array([[t["ixx"], t["ixy"], t["ixz"]], [t["ixy"], t["iyy"], t["iyz"]], [t["ixz"], t["iyz"], t["izz"]]])
        assert el.find("origin").get("rpy") == "0 0 0"
        com = np.array([float(v) for v in el.find("origin").get("xyz").split()])
        out_[link.get("name")] = (float(el.find("mass").get("value")), com, I)
    return out_


def box_inertia(mass, x, y, z):
    return mass / 12.0 * np.diag([y * y + z * z, x * x + z * z, x * x + y * y])


POLICIES = """
robot: pol
{policy}
links:
  base:
    visual: {{box: {{size: [0.1, 0.1, 0.1]}}}}
  arm:  # a vendor's tensor that breaks the triangle inequality, on a box 0.1 x 0.2 x 0.4 raised by 0.2
    visual: {{box: {{size: [0.1, 0.2, 0.4]}}, origin: {{xyz: [0, 0, 0.2]}}}}
    inertial: {{mass: 2, com: [0.5, 0, 0], inertia: {{ixx: 0.01, iyy: 0.01, izz: 0.05}}{arm}}}
  ball:  # a sphere mesh of radius 0.05, 0.3 off its link's origin
    visual: {{mesh: ball.stl, origin: {{xyz: [0.3, 0, 0]}}}}
    inertial: {{mass: 3, inertia: {{ixx: 0.01, iyy: 0.01, izz: 0.01}}{ball}}}
  rod:  # a cylinder mesh of radius 0.02 and length 0.3 along x
    visual: {{mesh: rod.stl, origin: {{rpy: [0, 1.5707963267948966, 0]}}}}
    inertial: {{mass: 0.5, inertia: {{ixx: 0.001, iyy: 0.001, izz: 0.001}}{rod}}}
  tip:  # no geometry
    inertial: {{mass: 0.1, inertia: {{ixx: 0, iyy: 0, izz: 0}}{tip}}}
joints:
  j1: {{type: continuous, parent: base, child: arm}}
  j2: {{type: continuous, parent: arm, child: ball, origin: {{xyz: [0, 0, 0.5]}}}}
  j3: {{type: continuous, parent: ball, child: rod, origin: {{xyz: [0, 0, 0.2]}}}}
  j4: {{type: continuous, parent: rod, child: tip, origin: {{xyz: [0, 0, 0.2]}}}}
"""


def _policies(tmp_path, policy="", **links):
    import trimesh

    text = POLICIES.format(policy=policy, **{k: links.get(k, "") for k in ("arm", "ball", "rod", "tip")})
    return write_recipe(tmp_path, text, meshes={
        "ball.stl": trimesh.creation.icosphere(subdivisions=3, radius=0.05),
        "rod.stl": trimesh.creation.cylinder(radius=0.02, height=0.3, sections=64)})


def test_recompute_and_estimate_known_answers_in_every_format(tmp_path):
    """Per link: recompute gives the box's exact tensor at the given mass; estimate gives the
    bounding sphere of a sphere mesh and the bounding cylinder of a cylinder mesh; a link without
    geometry under the recipe-wide policy gets the repair; the formats agree (1e-9)."""
    recipe = _policies(tmp_path, "inertia_policy: estimate", arm=", policy: recompute")
    got = _built_inertials(recipe, tmp_path / "out")
    mass, com, I = got["arm"]
    assert mass == 2.0 and np.allclose(com, [0, 0, 0.2], rtol=0, atol=1e-12)
    assert np.allclose(I, box_inertia(2.0, 0.1, 0.2, 0.4), rtol=1e-12, atol=0)
    mass, com, I = got["ball"]  # the icosphere's vertices lie on the sphere: its bounding sphere is r
    assert mass == 3.0 and np.allclose(com, [0.3, 0, 0], rtol=0, atol=1e-7)
    assert np.allclose(I, np.eye(3) * 0.4 * 3.0 * 0.05 ** 2, rtol=1e-6, atol=0)
    mass, com, I = got["rod"]  # a cylinder along x: I_xx = m r^2 / 2, the others m (3 r^2 + h^2) / 12
    r, h = 0.02, 0.3
    side = 0.5 * (3 * r * r + h * h) / 12
    assert mass == 0.5 and np.allclose(com, [0, 0, 0], rtol=0, atol=1e-7)
    assert np.allclose(I, np.diag([0.5 * r * r / 2, side, side]), rtol=1e-6, atol=1e-9 * side)
    mass, com, I = got["tip"]  # no geometry: the repair's floor (a 1 mm sphere at 0.1 kg)
    assert mass == 0.1 and np.allclose(I, np.eye(3) * 0.4 * 0.1 * 1e-6, rtol=1e-12, atol=0)


def test_a_link_policy_overrides_the_recipe_policy(tmp_path):
    """recipe-wide recompute; the arm asks to repair its tensor, the ball to keep its physical one."""
    recipe = _policies(tmp_path, "inertia_policy: recompute", arm=", policy: repair", ball=", policy: keep")
    got = _built_inertials(recipe, tmp_path / "out")
    assert np.allclose(got["arm"][2], REPAIRED_ARM, rtol=0, atol=1e-15)  # the repair
    assert np.allclose(got["arm"][1], [0.5, 0, 0], rtol=0, atol=0)  # the given centre of mass kept
    assert np.allclose(got["ball"][2], np.eye(3) * 0.01, rtol=0, atol=0)  # kept as given
    # the rod recomputed from its (64-section) cylinder mesh at 0.5 kg: trimesh's mass properties agree
    import trimesh

    rod = trimesh.load(recipe.parent / "rod.stl")
    rod.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
    rod.density = 0.5 / rod.volume
    assert np.allclose(got["rod"][2], rod.moment_inertia, rtol=1e-9, atol=1e-15)


def test_recompute_without_geometry_is_an_error(tmp_path):
    recipe = _policies(tmp_path, arm=", policy: repair", tip=", policy: recompute")
    with pytest.raises(RobotkitError) as info:
        load_robots([recipe])
    assert info.value.lines() == [
        f"{recipe}:16: links.tip.inertial.policy: 'recompute' needs the link's visual geometry, and the link "
        "has none (give the inertia with 'policy: repair')"]


def test_estimate_needs_a_mass(tmp_path):
    recipe = write_recipe(tmp_path, """
        robot: pol
        links:
          base:
            visual: {box: {size: [0.1, 0.1, 0.1]}}
            inertial: {density: 500, policy: estimate}
        """)
    with pytest.raises(RobotkitError) as info:
        load_robots([recipe])
    assert info.value.lines() == [f"{recipe}:5: links.base.inertial: policy 'estimate' needs the link's 'mass' "
                                  "(a bounding primitive has no density)"]


def test_the_bounding_primitive_is_the_smallest_enclosure():
    import trimesh

    from robotkit.model.massprops import bounding_primitive

    # a box along the axes: the box itself (exact), centred on it
    box = trimesh.creation.box([0.1, 0.2, 0.4])
    box.apply_translation([1.0, 2.0, 3.0])
    b = bounding_primitive(box.vertices)
    assert b.kind == "box" and np.allclose(b.size, [0.1, 0.2, 0.4], rtol=1e-14, atol=0)
    assert (b.transform[:3, :3] == np.eye(3)).all() and np.allclose(b.transform[:3, 3], [1, 2, 3], rtol=1e-15)
    com, I = b.inertia(2.0)
    assert np.allclose(I, box_inertia(2.0, 0.1, 0.2, 0.4), rtol=1e-12, atol=0)
    # the same box turned 30 degrees about z: the oriented box, with the turned tensor
    R = trimesh.transformations.rotation_matrix(np.pi / 6, [0, 0, 1])
    b = bounding_primitive(trimesh.transform_points(box.vertices, R))
    assert b.kind == "box" and np.allclose(sorted(b.size), [0.1, 0.2, 0.4], rtol=1e-9)
    _, I2 = b.inertia(2.0)
    assert np.allclose(I2, R[:3, :3] @ I @ R[:3, :3].T, rtol=1e-9, atol=1e-12)
    # a long thin cylinder mesh, lying along x then tilted: the cylinder (smaller than its boxes
    # and its sphere), found along the points' principal axis where trimesh's search misses it
    rod = trimesh.creation.cylinder(radius=0.01, height=1.0, sections=64)
    for R in (trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]),
              trimesh.transformations.rotation_matrix(0.3, [1, 1, 0])):
        b = bounding_primitive(trimesh.transform_points(rod.vertices, R))
        assert b.kind == "cylinder" and np.allclose(b.size, [0.01, 1.0], rtol=1e-9)
        assert np.allclose(np.abs(b.transform[:3, 2]), np.abs(R[:3, 2]), atol=1e-9)
    # points in a plane: the flat box along the axes (a plate's tensor, which is physical)
    b = bounding_primitive([[0, 0, 0], [1, 0, 0], [0, 2, 0], [1, 2, 0]])
    assert (b.kind, b.size) == ("box", (1.0, 2.0, 0.0))
    assert ip.defects(1.0, b.inertia(1.0)[1]) == []


@pytest.mark.consumers
def test_check_names_the_defect_and_the_policies_on_the_original(tmp_path):
    from robotkit.check import check_urdf_file

    urdf = tmp_path / "vendor.urdf"
    urdf.write_text("""<robot name="vendor">
  <link name="base"><visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual></link>
  <link name="arm"><visual><geometry><box size="0.1 0.1 0.4"/></geometry></visual>
    <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.05"/></inertial></link>
  <joint name="j" type="continuous"><parent link="base"/><child link="arm"/></joint>
</robot>""", encoding="utf-8")
    found = [f for f in check_urdf_file(urdf, {}) if f.check == "triangle-inequality"]
    assert [(f.subject, f.message, f.hint) for f in found] == [(
        "link 'arm'", "principal moments 0.01, 0.01, 0.05 violate the triangle inequality (I1 + I2 >= I3): no real "
        "body has them", "inertia policy 'repair' (robotkit import's default) makes the smallest change: principal "
        "moments 0.01, 0.01, 0.05 moved to 0.02, 0.02, 0.04 to meet the triangle inequality; 'recompute' or "
        "'estimate' derive it from the link's geometry (robotkit import --inertia-policy, or inertial.policy in a "
        "recipe)")]


def test_estimate_encloses_all_of_a_links_shapes(tmp_path):
    """Two 0.1 m cubes at x = +-0.2: the bounding primitive is the 0.5 x 0.1 x 0.1 box along the
    link's axes (smaller than the cylinder around them), centred between them."""
    from robotkit.model.resolve import compute_inertial

    recipe = write_recipe(tmp_path, """
        robot: pair
        links:
          base:
            visual:
              - {box: {size: [0.1, 0.1, 0.1]}, origin: {xyz: [-0.2, 0, 0.3]}}
              - {box: {size: [0.1, 0.1, 0.1]}, origin: {xyz: [0.2, 0, 0.3]}}
            inertial: {mass: 4, policy: estimate}
        """)
    (_, robot), = load_robots([recipe])
    got = compute_inertial(robot.link("base"), {})
    assert got.mass == 4.0 and got.com == (0.0, 0.0, 0.3)
    assert np.allclose(got.tensor(), 4.0 / 12 * np.diag([0.02, 0.26, 0.26]), rtol=1e-12, atol=0)
