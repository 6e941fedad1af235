"""Issue 14: the inertia policy (robotkit.model.inertia_policy), one rule set for import, build
and check: known answers for each repair, and the recipe keys that choose it."""

from __future__ import annotations

import numpy as np
import pytest

from robotkit.errors import RobotkitError
from robotkit.model import inertia_policy as ip
from robotkit.tasks import load_robots
from tests.conftest import write_recipe


def test_a_physical_tensor_is_kept():
    I = np.diag([0.02, 0.03, 0.04])
    assert ip.defects(2.0, I) == []
    fixed = ip.repair(2.0, I, 2.0)
    assert fixed.changes == () and (fixed.inertia == I).all() and fixed.mass == 2.0


def test_the_triangle_inequality_is_met_with_the_least_change():
    # excess 0.05 - 0.02 = 0.03: a third of it off the largest moment, a third onto each other one
    fixed = ip.repair(1.0, np.diag([0.01, 0.01, 0.05]), 1.0)
    assert np.allclose(fixed.inertia, np.diag([0.02, 0.02, 0.04]), rtol=0, atol=1e-15)
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
                                  "violate the triangle inequality (no real body has them)"]
    for name, policy, link_policy in (("all.yaml", "inertia_policy: repair", ""),
                                      ("link.yaml", "", ", policy: repair")):
        recipe = write_recipe(tmp_path, RECIPE.format(policy=policy, link_policy=link_policy), name)
        (_, robot), = load_robots([recipe])
        arm = robot.link("arm").inertial
        assert np.allclose(arm.tensor(), np.diag([0.02, 0.02, 0.04]), rtol=0, atol=1e-15), name
    # a link may keep what the recipe would repair
    mixed = write_recipe(tmp_path, RECIPE.format(policy="inertia_policy: repair", link_policy=", policy: keep"),
                         "mixed.yaml")
    with pytest.raises(RobotkitError):
        load_robots([mixed])
