"""The self-collision matrix on a robot whose answers are known by construction, its outputs
(SRDF, MJCF excludes, SDF bit masks), the interference check and bad input."""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from robotkit.model.selfcollision import Settings, solve_masks
from tests.conftest import run_cli, write_recipe

# base (20 cm cube) -> j1 (about z) -> post (40 cm bar) -> j2 (about y, at the post's top) -> boom:
# a 50 cm bar along x that swings down into the base.  Welded to the base: 'far', a ball 2 m away
# and 'far2', balls 2 m away that nothing reaches, and 'stop', a ball where the boom lies at the zero pose.
ARM = """
robot: arm
density: 1000
links:
  world: {}
  base: {collision: {box: {size: [0.2, 0.2, 0.2]}}, inertial: {mass: 1, inertia: {ixx: 0.01, iyy: 0.01, izz: 0.01}}}
  post: {collision: {box: {size: [0.05, 0.05, 0.4]}, origin: {xyz: [0, 0, 0.2]}},
         inertial: {mass: 1, inertia: {ixx: 0.01, iyy: 0.01, izz: 0.01}}}
  boom: {collision: {box: {size: [0.5, 0.04, 0.04]}, origin: {xyz: [0.3, 0, 0]}},
         inertial: {mass: 1, inertia: {ixx: 0.01, iyy: 0.01, izz: 0.01}}}
  far: {collision: {sphere: {radius: 0.05}}}
  stop: {collision: {sphere: {radius: 0.03}}}
  far2: {collision: {sphere: {radius: 0.05}}}
joints:
  weld: {type: fixed, parent: world, child: base}
  j1: {type: revolute, parent: base, child: post, origin: {xyz: [0, 0, 0.1]}, axis: [0, 0, 1],
       limit: {lower: -3, upper: 3, effort: 10, velocity: 1}}
  j2: {type: revolute, parent: post, child: boom, origin: {xyz: [0, 0, 0.4]}, axis: [0, 1, 0],
       limit: {lower: -2.9, upper: 2.9, effort: 10, velocity: 1}}
  to_far: {type: fixed, parent: base, child: far, origin: {xyz: [-2, 0, 0]}}
  to_stop: {type: fixed, parent: base, child: stop, origin: {xyz: [0.45, 0, 0.5]}}
  to_far2: {type: fixed, parent: base, child: far2, origin: {xyz: [0, 2, 0]}}
"""


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("arm")
    recipe = write_recipe(tmp, ARM + "self_collision: {allow: [[far, boom, a cable guard]]}\n", "arm.yaml")
    proc = run_cli("build", recipe, "--out", tmp / "out")
    assert proc.returncode == 0, proc.stderr
    return tmp / "out" / "arm"


def pairs(folder):
    report = json.loads((folder / "report.json").read_text())["self_collision"]
    return {(p["a"], p["b"]): p for p in report["pairs"]}, report


@pytest.mark.slow
def test_every_pair_is_classified_as_moveit_would(arm):
    found, report = pairs(arm)
    reasons = {k: v["reason"] for k, v in found.items()}
    assert reasons == {
        ("base", "post"): "Adjacent", ("boom", "post"): "Adjacent",  # joined by a joint
        ("far", "stop"): "Adjacent", ("base", "far"): "Adjacent", ("base", "stop"): "Adjacent",  # welded
        ("far", "post"): "Adjacent", ("post", "stop"): "Adjacent",  # one joint from the base's welded group
        ("base", "far2"): "Adjacent", ("far", "far2"): "Adjacent", ("far2", "stop"): "Adjacent",
        ("far2", "post"): "Adjacent",
        ("boom", "far"): "User",  # the recipe's, with its reason
        ("boom", "stop"): "Default",  # the boom lies on the ball at the zero pose
        ("boom", "far2"): "Never",  # 2 m away, out of the boom's reach
        ("base", "boom"): "",  # the boom swings down into the base: checked
    }
    assert found[("boom", "far")]["note"] == "a cable guard"
    assert found[("base", "boom")]["hits"] > 0 and found[("boom", "far2")]["hits"] == 0
    assert report["samples"] == 10000 and report["seed"] == 0 and "seconds" not in report


@pytest.mark.slow
def test_srdf_mjcf_and_sdf_carry_the_same_disabled_set(arm):
    found, _ = pairs(arm)
    disabled = {frozenset(k) for k, v in found.items() if v["reason"]}
    srdf = ET.parse(arm / "srdf" / "arm.srdf").getroot()
    assert {frozenset((e.get("link1"), e.get("link2"))): e.get("reason") for e in srdf.iter("disable_collisions")} \
        == {frozenset(k): v["reason"] for k, v in found.items() if v["reason"]}
    assert srdf.find("group/chain").attrib == {"base_link": "world", "tip_link": "boom"}
    mjcf = ET.parse(arm / "mjcf" / "arm.xml").getroot()
    assert {frozenset((e.get("body1"), e.get("body2"))) for e in mjcf.iter("exclude")} == disabled
    sdf = ET.parse(arm / "model.sdf").getroot()
    assert sdf.find("model/self_collide").text == "true"
    masks = {link.get("name"): [int(c.find("surface/contact/collide_bitmask").text) for c in link.iter("collision")]
             for link in sdf.iter("link")}
    # the massless balls are frames of the base in SDF: their collisions are the base link's, each
    # with its own mask; of the base's four, only the box (checked against the boom) shares a bit
    [boom] = masks["boom"]
    assert len(masks["base"]) == 4 and [bool(m & boom) for m in masks["base"]] == [True, False, False, False]


@pytest.mark.slow
def test_the_matrix_is_the_same_for_a_seed_and_a_rebuild_reads_the_cache(arm, tmp_path):
    again = tmp_path / "again"
    recipe = write_recipe(tmp_path, ARM + "self_collision: {allow: [[far, boom, a cable guard]]}\n", "arm.yaml")
    assert run_cli("build", recipe, "--out", again).returncode == 0
    assert (again / "arm" / "srdf" / "arm.srdf").read_bytes() == (arm / "srdf" / "arm.srdf").read_bytes()
    assert pairs(again / "arm")[0] == pairs(arm)[0]


@pytest.mark.slow
def test_a_pose_that_folds_the_boom_into_the_base_is_an_error_and_the_sweep_names_the_angle(tmp_path):
    recipe = write_recipe(tmp_path, ARM + "poses:\n  folded: {j2: 90 deg}\n", "arm.yaml")
    proc = run_cli("check", recipe, "--format", "json")
    assert proc.returncode == 1, proc.stderr
    found = [f for f in json.loads(proc.stdout)["findings"] if f["check"] == "self-collision"]
    errors = [f for f in found if f["severity"] == "error"]
    assert [(f["subject"], f["message"].split(" by ")[0]) for f in errors] == [
        ("pose 'folded'", "links 'base' and 'boom' interpenetrate")]
    depth_mm = float(errors[0]["message"].split(" by ")[1].split(" mm")[0])
    # the boom's end reaches 5 cm below the base's top... and MuJoCo's depth is the shortest way out:
    # sideways, half the base (10 cm) plus half the bar (2 cm)
    assert depth_mm == pytest.approx(120, abs=1)
    # the sweeps start at 'folded', already in contact: they say nothing more about j2
    assert not [f for f in found if f["subject"] == "joint 'j2'"]


@pytest.mark.slow
def test_a_limit_that_reaches_into_the_base_is_a_warning_naming_the_angle(tmp_path):
    recipe = write_recipe(tmp_path, ARM + "poses:\n  home: {j2: -30 deg}\n", "arm.yaml")
    proc = run_cli("check", recipe, "--format", "json")
    found = [f for f in json.loads(proc.stdout)["findings"] if f["check"] == "self-collision"]
    [down] = [f for f in found if f["subject"] == "joint 'j2'" and "166.2 deg" in f["message"]]
    assert down["severity"] == "warning" and "links 'base' and 'boom' collide at" in down["message"]
    angle = float(down["message"].split("collide at ")[1].split(" deg")[0])
    # an oracle: the bar's points (s along it from 5 to 55 cm, t across its 4 cm) as it turns by
    # theta about y from the pivot at z 0.5; the first theta that puts one in the base's top face
    s_, t_ = np.meshgrid(np.linspace(0.05, 0.55, 501), np.linspace(-0.02, 0.02, 41))
    for theta in np.arange(0, 166.2, 0.01):
        c, n = math.cos(math.radians(theta)), math.sin(math.radians(theta))
        x, z = s_ * c + t_ * n, 0.5 - s_ * n + t_ * c
        if ((np.abs(x) <= 0.1) & (z <= 0.1)).any():
            break
    assert angle == pytest.approx(theta, abs=0.2)


def test_bad_self_collision_input_is_named_together(tmp_path):
    recipe = write_recipe(tmp_path, ARM + """self_collision:
  samples: 0
  allow: [[boom, nope], [post, post]]
  check: [[far, boom, extra], [far, post]]
""".replace("samples: 0\n", "samples: 0\n") + "\n", "arm.yaml")
    proc = run_cli("build", recipe, "--out", tmp_path / "out")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    rows = proc.stderr.splitlines()
    n = {k: next(i for i, r in enumerate(recipe.read_text().splitlines(), 1) if r.startswith(k))
         for k in ("  samples", "  allow", "  check")}
    assert rows == [
        f"{recipe}:{n['  samples']}: self_collision.samples: must be > 0",
        f"{recipe}:{n['  check']}: self_collision.check[0]: must have 2 values (got 3)",
    ], rows
    assert not (tmp_path / "out" / "arm").exists()


def test_names_and_contradictions_are_named_together(tmp_path):
    recipe = write_recipe(tmp_path, ARM + """self_collision:
  allow: [[boom, nope], [post, post], [far, post, guard]]
  check: [[post, far]]
""", "arm.yaml")
    proc = run_cli("build", recipe, "--out", tmp_path / "out")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    allow = next(i for i, r in enumerate(recipe.read_text().splitlines(), 1) if r.startswith("  allow"))
    check = allow + 1
    assert proc.stderr.splitlines() == [
        f"{recipe}:{allow}: self_collision.allow[0]: no link named 'nope'",
        f"{recipe}:{allow}: self_collision.allow[1]: a pair names two links; 'post' is named twice",
        f"{recipe}:{check}: self_collision.check[0]: pair 'far', 'post' is also in self_collision.allow",
    ]
    assert not (tmp_path / "out" / "arm").exists()


def test_masks_make_exactly_the_enabled_pairs_share_a_bit():
    nodes = ["a", "b", "c", "d"]
    enabled = {frozenset("ac"), frozenset("bd"), frozenset("ad")}
    free = {frozenset("ab")}
    masks = solve_masks(nodes, enabled, free)
    for i, u in enumerate(nodes):
        assert masks[u]
        for v in nodes[i + 1:]:
            pair = frozenset((u, v))
            if pair in enabled:
                assert masks[u] & masks[v]
            elif pair not in free:
                assert not masks[u] & masks[v]
    # a complete graph of 17 isolated links needs 17 bits: more than Gazebo's 16
    many = [f"l{i}" for i in range(17)]
    assert solve_masks(many, set(), set()) is None
    assert Settings().samples == 10000


def chain_robot(tmp_path, n: int, extra: str = ""):
    from robotkit.model.load import load_robots

    links = "\n".join(f"  l{i}: {{collision: {{box: {{size: [0.1, 0.1, 0.1]}}}}, "
                      f"inertial: {{mass: 1, inertia: {{ixx: 0.01, iyy: 0.01, izz: 0.01}}}}}}" for i in range(n))
    joints = "\n".join(f"  j{i}: {{type: revolute, parent: l{i}, child: l{i + 1}, origin: {{xyz: [0, 0, 0.2]}}, "
                       "axis: [0, 1, 0], limit: {lower: -1, upper: 1, effort: 1, velocity: 1}}" for i in range(n - 1))
    recipe = write_recipe(tmp_path, f"robot: chain\n{extra}links:\n{links}\njoints:\n{joints}\n", "chain.yaml")
    [(_, robot)] = load_robots([recipe])
    return robot


def with_matrix(robot, enabled: set):
    from dataclasses import replace

    from robotkit.model.selfcollision import Matrix, Pair

    names = [link.name for link in robot.links]
    adjacent = {frozenset((j.parent, j.child)) for j in robot.joints}
    pairs = tuple(Pair(a, b, "" if frozenset((a, b)) in enabled else
                       "Adjacent" if frozenset((a, b)) in adjacent else "Never")
                  for i, a in enumerate(names) for b in names[i + 1:])
    return replace(robot, collision_matrix=Matrix(10000, 0, pairs))


def test_a_matrix_that_16_masks_cannot_express_leaves_the_sdf_without_self_collision(tmp_path):
    from robotkit.emit.sdf import losses, render_sdf

    # 34 links, 17 checked pairs that share no link: each needs a bit of its own
    robot = chain_robot(tmp_path, 34)
    matrix = with_matrix(robot, {frozenset((f"l{i}", f"l{i + 17}")) for i in range(17)})
    assert "<self_collide>" not in render_sdf(matrix) and "collide_bitmask" not in render_sdf(matrix)
    [loss] = [x for x in losses(matrix) if "self-collision" in x]
    assert loss == "self-collision is off in model.sdf: 16 collide bit masks cannot express the self-collision matrix"
    # 16 such pairs fit, the two links left over each sharing a bit with a pair it never comes near
    fits = with_matrix(robot, {frozenset((f"l{i}", f"l{i + 17}")) for i in range(16)})
    assert "<self_collide>true</self_collide>" in render_sdf(fits)
    assert [x.split(":")[0] for x in losses(fits) if "bit masks" in x] == [
        "model.sdf's collide bit masks also check 4 pairs the matrix calls Never (16 masks cannot separate them; "
        "they never come within 1 cm)"]
    asked = with_matrix(chain_robot(tmp_path / "on", 34, "self_collide: true\n"),
                        {frozenset((f"l{i}", f"l{i + 17}")) for i in range(17)})
    assert "<self_collide>true</self_collide>" in render_sdf(asked) and "collide_bitmask" not in render_sdf(asked)
    assert [x for x in losses(asked) if "self_collide" in x] == [
        "self_collide: 16 collide bit masks cannot express the self-collision matrix; on with Gazebo's own filter"]


def test_self_collide_false_turns_it_off_in_the_mjcf_and_the_sdf(tmp_path):
    from robotkit.emit.mjcf import self_contacts
    from robotkit.emit.sdf import render_sdf
    from robotkit.emit.srdf import render_srdf

    robot = with_matrix(chain_robot(tmp_path, 4, "self_collide: false\n"), {frozenset(("l0", "l2"))})
    assert self_contacts(robot) == (False, [])
    assert "<self_collide>" not in render_sdf(robot)
    assert render_srdf(robot).count("<disable_collisions") == 5  # the SRDF still carries the matrix
    on = with_matrix(chain_robot(tmp_path / "on", 4), {frozenset(("l0", "l2"))})
    assert self_contacts(on) == (True, [("l0", "l1"), ("l0", "l3"), ("l1", "l2"), ("l1", "l3"), ("l2", "l3")])


def test_a_long_list_of_pairs_is_cut_to_five_in_the_loss(tmp_path):
    from robotkit.emit.sdf import losses

    robot = with_matrix(chain_robot(tmp_path, 40), {frozenset((f"l{i}", f"l{i + 20}")) for i in range(16)})
    [loss] = [x for x in losses(robot) if "bit masks" in x]
    head, names = loss.split(": ", 1)
    assert head.startswith("model.sdf's collide bit masks also check 37 pairs the matrix calls Never")
    assert names.count("-") == 5 and names.endswith(" and 32 more (report.json: self_collision)")
