"""Issue 32: the implied-density rule judged on the rigid body a link belongs to.

A link welded by fixed joints is no body of its own where fixed joints are lumped (Gazebo, Drake):
ANYmal B's ``base`` carries its visual with 1e-6 kg while its 16.8 kg sit in the geometry-less
``base_inertia`` welded to it; TIAGo's, HyQ's and the racecar's sensors carry placeholder masses on
small boxes.  A link whose own density is out of range but whose rigid body's is in range is a
warning; the same link on a moving joint, or a body out of range too, is an error as before."""

from __future__ import annotations

import pytest

from robotkit.check.lints import lint, read_urdf_facts
from robotkit.model.rigidbody import WELDED_HINT, Part, rigid_bodies


def box_link(name, mass, size):
    x, y, z = size
    ixx, iyy, izz = (mass / 12 * (b * b + c * c) for b, c in ((y, z), (x, z), (x, y)))
    box = f'<box size="{x} {y} {z}"/>'
    return f"""
  <link name="{name}">
    <visual><geometry>{box}</geometry></visual>
    <collision><geometry>{box}</geometry></collision>
    <inertial><mass value="{mass!r}"/><inertia ixx="{ixx!r}" iyy="{iyy!r}" izz="{izz!r}" ixy="0" ixz="0" iyz="0"/>
    </inertial>
  </link>"""


def bare_link(name, mass, moment):
    """A link with an inertial and no geometry (ANYmal B's base_inertia)."""
    return f"""
  <link name="{name}">
    <inertial><mass value="{mass!r}"/><inertia ixx="{moment!r}" iyy="{moment!r}" izz="{moment!r}" ixy="0" ixz="0"
      iyz="0"/></inertial>
  </link>"""


def joint(name, kind, parent, child):
    limit = '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="10" velocity="2"/>' if kind == "revolute" else ""
    return f"""
  <joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>{limit}</joint>"""


def density_findings(tmp_path, body):
    path = tmp_path / "robot.urdf"
    path.write_text(f'<?xml version="1.0"?>\n<robot name="robot">{body}\n</robot>\n', encoding="utf-8")
    links, joints, _ = read_urdf_facts(path)
    return [(f.severity, f.subject, f.message, f.hint) for f in lint(links, joints) if f.check == "implied-density"]


def anymal(kind):
    """A dummy visual link of 1e-6 kg (a 20 cm box) on a geometry-less 16 kg link."""
    return (box_link("base", 1e-6, (0.2, 0.2, 0.2)) + bare_link("base_inertia", 16.0, 0.1)
            + joint("base_to_base_inertia", kind, "base", "base_inertia"))


def test_a_dummy_visual_link_welded_to_a_massive_geometryless_link_is_a_warning(tmp_path):
    assert density_findings(tmp_path, anymal("fixed")) == [
        ("warning", "link 'base'", "implied density 0.000125 kg/m^3 (mass 1e-06 kg, volume 0.008 m^3) is below 10; "
         "the rigid body it is welded to (base, base_inertia: 16 kg, 0.008 m^3) is 2000 kg/m^3: its mass is a share "
         "of that body's", WELDED_HINT)]
    assert WELDED_HINT == ("Gazebo and Drake lump links welded by fixed joints into one body, where only the body's "
                           "mass acts; give the link its own share of it for a simulator that keeps it a body of its "
                           "own")


def test_the_same_link_on_a_revolute_joint_is_an_error(tmp_path):
    assert density_findings(tmp_path, anymal("revolute")) == [
        ("error", "link 'base'", "implied density 0.000125 kg/m^3 (mass 1e-06 kg, volume 0.008 m^3) is below 10",
         "the density or mass is far too low")]


def test_a_too_heavy_sensor_welded_to_a_plausible_base_is_a_warning(tmp_path):
    """1 kg on a 1 cm box (PR2's sensor boxes, TIAGo's base_footprint), welded to a 10 kg base."""
    robot = (box_link("base_link", 10.0, (0.3, 0.3, 0.1)) + box_link("laser", 1.0, (0.01, 0.01, 0.01))
             + joint("laser_joint", "fixed", "base_link", "laser"))
    assert density_findings(tmp_path, robot) == [
        ("warning", "link 'laser'", "implied density 1e+06 kg/m^3 (mass 1 kg, volume 1e-06 m^3) is above 25000; "
         "the rigid body it is welded to (laser, base_link: 11 kg, 0.009001 m^3) is 1222 kg/m^3: its mass is a "
         "share of that body's", WELDED_HINT)]


def test_an_assembly_out_of_range_is_an_error(tmp_path):
    """The same sensor on a 10 g mount of 2 cm: the body is 1.01 kg in 9e-6 m^3, no solid part."""
    robot = (box_link("mount", 0.01, (0.02, 0.02, 0.02)) + box_link("laser", 1.0, (0.01, 0.01, 0.01))
             + joint("laser_joint", "fixed", "mount", "laser"))
    assert density_findings(tmp_path, robot) == [
        ("error", "link 'laser'", "implied density 1e+06 kg/m^3 (mass 1 kg, volume 1e-06 m^3) is above 25000",
         "the mass looks like grams written as kilograms")]


def test_the_body_spans_fixed_joints_both_ways_and_its_names_are_shortened():
    """The judged link first, the others heaviest first; past three names, how many more.  A link
    on an open mesh (no volume) does not count, nor one without mass, nor one across a moving joint."""
    parts = {"base": Part(1e-6, 0.04, True), "imu": Part(0.2, 1e-4, True), "inertia": Part(16.0, None, False),
             "shell": Part(5.0, None, True), "frame": Part(None, None, False), "cam": Part(0.5, 2e-4, True),
             "leg": Part(2.0, 1e-3, True)}
    fixed = [("inertia", "base"), ("base", "imu"), ("imu", "cam"), ("base", "shell"), ("frame", "base"),
             ("world", "frame")]
    bodies = rigid_bodies(parts, fixed)
    assert bodies["base"].links == ("base", "inertia", "cam", "imu")
    assert bodies["cam"].links == ("cam", "inertia", "imu", "base")
    assert bodies["base"].describe() == "base, inertia, cam and 1 more: 16.7 kg, 0.0403 m^3"
    assert bodies["shell"].links == ("inertia", "cam", "imu", "base")  # its own mass has no volume to go with
    assert bodies["leg"].links == ("leg",)
    assert bodies["leg"].mass == pytest.approx(2.0)
