"""Mass properties against analytic answers and invariants."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from robotkit.mesh.inertia import mesh_mass_properties
from robotkit.model.massprops import box_props, combine, cylinder_props, sphere_props
from robotkit.geometry import matrix_rpy, rpy_matrix


def props(mesh):
    return mesh_mass_properties(mesh.vertices, mesh.faces)


def test_box_is_exact():
    p = props(trimesh.creation.box([1.0, 2.0, 3.0]))
    assert p.volume == pytest.approx(6.0, rel=1e-14)
    np.testing.assert_allclose(p.com, 0, atol=1e-15)
    expected = 6.0 / 12.0 * np.diag([4 + 9, 1 + 9, 1 + 4])
    np.testing.assert_allclose(p.inertia, expected, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(box_props([1, 2, 3]).inertia, expected, rtol=1e-15)


@pytest.mark.parametrize("sections", [32, 128, 512, 2048])
def test_cylinder_converges(sections):
    r, h = 0.5, 2.0
    p = props(trimesh.creation.cylinder(radius=r, height=h, sections=sections))
    exact = cylinder_props(r, h)
    # a regular polygon of n sides has area (n/2) r^2 sin(2 pi/n): the only error is this discretisation
    area_ratio = sections / (2 * math.pi) * math.sin(2 * math.pi / sections)
    assert p.volume == pytest.approx(exact.volume * area_ratio, rel=1e-12)
    err = np.abs(p.inertia - exact.inertia).max() / exact.inertia.max()
    assert err < 10.0 / sections ** 2  # second-order convergence (7.4e-3 at 32 sections)
    np.testing.assert_allclose(p.com, 0, atol=1e-12)


def test_sphere_converges():
    errors = []
    for sub in (2, 3, 4, 5):
        p = props(trimesh.creation.icosphere(subdivisions=sub, radius=0.3))
        exact = sphere_props(0.3)
        errors.append(abs(p.inertia[0, 0] - exact.inertia[0, 0]) / exact.inertia[0, 0])
        np.testing.assert_allclose(p.inertia, np.eye(3) * p.inertia[0, 0], atol=1e-3 * exact.inertia[0, 0])
    assert all(b < a / 3 for a, b in zip(errors, errors[1:]))  # each subdivision cuts the error ~4x
    assert errors[-1] < 1e-3


def test_units_cm_and_m_agree():
    m_mesh = trimesh.creation.box([0.1, 0.2, 0.3])
    cm_mesh = trimesh.creation.box([10.0, 20.0, 30.0])
    a = props(m_mesh)
    b = mesh_mass_properties(cm_mesh.vertices * 0.01, cm_mesh.faces)
    assert b.volume == pytest.approx(a.volume, rel=1e-12)
    np.testing.assert_allclose(b.inertia, a.inertia, rtol=1e-12, atol=1e-18)
    # the s^3 / s^5 rule people apply by hand
    raw = props(cm_mesh)
    assert raw.volume * 0.01 ** 3 == pytest.approx(a.volume, rel=1e-12)
    np.testing.assert_allclose(raw.inertia * 0.01 ** 5, a.inertia, rtol=1e-12, atol=1e-18)


def test_off_centre_mesh_gives_parallel_axis_result():
    mesh = trimesh.creation.box([1.0, 2.0, 3.0])
    mesh.apply_translation([5.0, -1.0, 2.0])
    p = props(mesh)
    np.testing.assert_allclose(p.com, [5.0, -1.0, 2.0], rtol=1e-14)
    # about the centre of mass: unchanged by the translation
    np.testing.assert_allclose(p.inertia, box_props([1, 2, 3]).inertia, rtol=1e-12, atol=1e-12)
    # about the origin: parallel-axis theorem (docs/libraries.md: diag 6.5, 5, 2.5 for the unit-density box at x=5 is
    # about the COM; here we add m (|r|^2 I - r r^T))
    r = np.array([5.0, -1.0, 2.0])
    about_origin = p.inertia + p.volume * (r @ r * np.eye(3) - np.outer(r, r))
    mass, com, I = combine([(p.volume, p.com, p.inertia)])
    np.testing.assert_allclose(I, p.inertia)
    assert about_origin[0, 1] == pytest.approx(6.0 * 5.0, rel=1e-12)  # -m x y with x=5, y=-1


def test_rotated_mesh_gives_rotated_tensor():
    mesh = trimesh.creation.box([0.1, 0.4, 0.9])
    mesh.apply_translation([0.3, 0.1, -0.2])
    base = props(mesh)
    R = rpy_matrix((0.3, -1.1, 2.5))
    T = np.eye(4)
    T[:3, :3] = R
    rotated = mesh.copy()
    rotated.apply_transform(T)
    p = props(rotated)
    np.testing.assert_allclose(p.com, R @ base.com, atol=1e-14)
    np.testing.assert_allclose(p.inertia, R @ base.inertia @ R.T, atol=1e-14)
    assert abs(p.inertia[0, 1]) > 1e-4  # products of inertia really appear


def test_agrees_with_trimesh_on_an_irregular_mesh():
    mesh = trimesh.creation.annulus(r_min=0.2, r_max=0.5, height=0.3, sections=40)
    T = np.eye(4)
    T[:3, :3] = rpy_matrix((0.7, -0.4, 1.9))
    mesh.apply_transform(T)
    mesh.apply_translation([1.0, 2.0, 3.0])
    p = props(mesh)
    assert p.volume == pytest.approx(mesh.volume, rel=1e-12)
    np.testing.assert_allclose(p.com, mesh.center_mass, rtol=1e-12)
    np.testing.assert_allclose(p.inertia, mesh.moment_inertia, rtol=1e-9, atol=1e-12)


def test_combine_two_boxes_equals_one():
    a, b = box_props([1, 1, 1]), box_props([1, 1, 1])
    mass, com, I = combine([(1.0, np.array([-0.5, 0, 0]), a.inertia), (1.0, np.array([0.5, 0, 0]), b.inertia)])
    whole = box_props([2, 1, 1])
    assert mass == 2.0
    np.testing.assert_allclose(com, 0, atol=1e-15)
    np.testing.assert_allclose(I, whole.inertia * 2 / whole.volume, rtol=1e-14)


@pytest.mark.parametrize("rpy", [(0.1, 0.2, 0.3), (-2.0, 1.2, 3.0), (0.0, math.pi / 2, 0.4)])
def test_rpy_round_trip(rpy):
    R = rpy_matrix(rpy)
    np.testing.assert_allclose(rpy_matrix(matrix_rpy(R)), R, atol=1e-12)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-15)
