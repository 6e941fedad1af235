"""The links of a body's joint chain carry 1e-05 kg taken from the body, where the joints after
them leave it fixed (robotkit.importer.mjcf.chainmass): the rebuild's dynamics are the
original's to rounding, and libsdformat (Gazebo) keeps every link."""

from __future__ import annotations

import numpy as np
import pytest

from robotkit.commands.import_ import build_mjcf
from robotkit.importer import import_mjcf
from robotkit.importer.mjcf import convert
from robotkit.importer.mjcf.chainmass import fixed_point, take_point_mass


def test_taking_a_point_mass_leaves_the_rest_of_the_body():
    # 1 kg, centre 0.1 m up z; 0.1 kg taken at the origin: 0.9 kg at 1/9 m, Ixx 0.01 - 1/900
    rest, c, I = take_point_mass(1.0, [0, 0, 0.1], np.diag([0.01, 0.01, 0.002]), 0.1, [0, 0, 0], 0.0)
    assert rest == pytest.approx(0.9, rel=1e-15)
    assert c == pytest.approx([0, 0, 1 / 9], rel=1e-15)
    assert I == pytest.approx(np.diag([0.01 - 1 / 900, 0.01 - 1 / 900, 0.002]), rel=1e-14, abs=1e-18)


def test_the_rest_and_the_point_are_the_body():
    """The rest and the point (with its tensor) together, about the body's centre: the body's own."""
    R, _ = np.linalg.qr(np.random.default_rng(3).normal(size=(3, 3)))
    inertia = R @ np.diag([0.01, 0.02, 0.025]) @ R.T
    com, p = np.array([0.1, -0.2, 0.05]), np.array([0.3, 0.1, -0.1])
    rest, c, I = take_point_mass(2.0, com, inertia, 1e-3, p, 1e-6)
    again = I + rest * _steiner(c - com) + 1e-6 * np.eye(3) + 1e-3 * _steiner(p - com)
    assert (rest * c + 1e-3 * p) / 2.0 == pytest.approx(com, abs=1e-15)
    assert np.abs(again - inertia).max() < 1e-14


def _steiner(d):
    return float(d @ d) * np.eye(3) - np.outer(d, d)


def test_a_point_the_rest_cannot_spare_is_not_taken():
    assert take_point_mass(1e-5, [0, 0, 0], np.eye(3) * 1e-9, 1e-5, [0, 0, 0], 1e-12) is None  # no mass left
    # half a light ball taken 1 m from its centre: the rest's moments would be negative
    assert take_point_mass(1.0, [0, 0, 0], np.eye(3) * 1e-3, 0.5, [1, 0, 0], 0.0) is None


def test_the_point_every_later_hinge_leaves_fixed():
    centre, x, y, z = np.array([0.1, 0.2, 0.3]), *np.eye(3)
    assert fixed_point([(centre, x), (centre, y), (centre, z)], [5, 5, 5]) == pytest.approx(centre, abs=1e-15)
    # one axis: the point on it nearest the body's centre of mass
    assert fixed_point([(centre, x)], [2, 0, 0]) == pytest.approx([2, 0.2, 0.3], abs=1e-15)
    assert fixed_point([(centre, x), (centre + [0, 0, 0.01], y)], [0, 0, 0]) is None  # skew axes
    assert fixed_point([(centre, z), (centre + [0.01, 0, 0], z)], [0, 0, 0]) is None  # parallel axes apart


# on a floating base (its translations feel any mass added), a rod on a ball joint at its end
# (Menagerie Cassie's achilles rods) and a body on two hinges whose axes meet off its centre of mass
# (each with a ref: the recipe's joint zero is not the file's pose)
CHAINS = """<mujoco model="chains">
  <worldbody>
    <body name="base" pos="0 0 0.5">
      <freejoint name="float"/>
      <geom type="box" size="0.1 0.1 0.05" mass="3"/>
      <body name="rod" pos="0.1 0 0" euler="0 0 20">
        <joint name="rod_ball" type="ball" pos="0.01 0 0"/>
        <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.005" mass="0.15"/>
      </body>
      <body name="head" pos="-0.1 0 0">
        <joint name="yaw" axis="0 0 1" pos="0 0.02 0" range="-60 60" ref="20"/>
        <joint name="tilt" axis="1 0 0" pos="0 0.02 0" range="-60 60" ref="-30"/>
        <geom type="box" size="0.03 0.03 0.03" pos="0.05 0.07 0.01" mass="0.4"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.fixture(scope="module")
def chains(tmp_path_factory):
    folder = tmp_path_factory.mktemp("chains")
    (folder / "chains.xml").write_text(CHAINS)
    result = import_mjcf(folder / "chains.xml", folder / "chains.yaml", build=build_mjcf)
    return result, convert(folder / "chains.xml", folder / "chains.yaml")


def test_chain_links_carry_mass_taken_at_the_ball_centre_and_on_the_axis(chains):
    recipe, ledger, src, tree = chains[1]
    links = recipe["links"]
    for name in ("rod_rod_ball_x", "rod_rod_ball_y"):  # at the ball's centre, in the link's frame there
        assert links[name]["inertial"] == {"mass": 1e-5, "com": [0.0, 0.0, 0.0],
                                           "inertia": {"ixx": 1e-12, "iyy": 1e-12, "izz": 1e-12}}
    # on the tilt axis (x through 0 0.02 0 of the body), nearest the centre of mass (0.05 0.07 0.01), in the
    # frame of the chain link (on the yaw axis, z through 0 0.02 0)
    assert links["head_yaw"]["inertial"]["com"] == pytest.approx([0.05, 0, 0], abs=1e-15)
    assert links["head_yaw"]["inertial"]["mass"] == 1e-5
    assert links["rod"]["inertial"]["mass"] == pytest.approx(float(src.model.body("rod").mass[0]) - 2e-5, rel=1e-15)
    assert links["head"]["inertial"]["mass"] == pytest.approx(0.4 - 1e-5, rel=1e-15)
    assert not [line for line in ledger.lines() if "joint chain" in line]


def test_the_rebuild_has_the_original_dynamics_to_rounding(chains):
    """Once the chain links' millionth of the lightest body was added, the mass matrix was off by
    1.3e-7 here (4.5e-7 kg on 3.55 kg); taken from the body where the later joints leave it, the
    rebuild's is the original's but for the point's 1e-12 kg m^2 tensor, which turns with its link."""
    verdict = chains[0].verdict
    assert verdict.ok, verdict.lines()
    for kind in ("mass", "inertia"):
        assert verdict.worst[kind][0] < 1e-14, (kind, verdict.worst[kind])
    for kind in ("matrix", "bias", "pinocchio"):
        assert verdict.worst[kind][0] < 1e-9, (kind, verdict.worst[kind])


def test_a_link_whose_later_hinges_do_not_meet_keeps_an_added_mass(tmp_path):
    """Three hinges, the last two 2 cm apart: the first chain link has no point both leave fixed
    (on the ledger); the second takes its mass on the last hinge's axis."""
    (tmp_path / "skew.xml").write_text("""<mujoco model="skew">
  <worldbody>
    <body name="arm" pos="0 0 0.1">
      <joint name="a" axis="0 0 1"/>
      <joint name="b" axis="0 1 0"/>
      <joint name="c" axis="1 0 0" pos="0 0 0.02"/>
      <geom type="box" size="0.02 0.02 0.1" pos="0 0 0.1" mass="0.2"/>
    </body>
  </worldbody>
</mujoco>
""")
    recipe, ledger, _, tree = convert(tmp_path / "skew.xml", tmp_path / "skew.yaml")
    assert [line for line in ledger.lines() if "joint chain" in line] == [
        "skew.xml:3: body 'arm' (joint chain): all: approximated: chain link 'arm_a' carries an added point mass of "
        "2e-07 kg (a millionth of the lightest body), not taken from the body: the axes of the hinges after it do not "
        "meet, so no point of the link stays fixed in the body; Gazebo (libsdformat's URDF reader) drops a link of "
        "1e-06 kg or less with everything below it"]
    assert list(tree.moved) == ["arm_b"]
    assert recipe["links"]["arm_b"]["inertial"]["com"] == pytest.approx([0, 0, 0.02], abs=1e-15)  # on c's axis
    assert recipe["links"]["arm"]["inertial"]["mass"] == pytest.approx(0.2 - 1e-5, rel=1e-15)
