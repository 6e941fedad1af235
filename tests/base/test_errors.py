"""Bad input: one line per problem naming file, line and key; all together; exit 2;
no traceback; nothing written under the output folder.  Messages checked word for word."""

from __future__ import annotations

import shutil
import textwrap

import pytest

from conftest import RECIPES, run_cli

BASE_STL = RECIPES / "meshes" / "turret_bot" / "base.stl"

CASES = {
    "invalid_yaml": (
        """
        robot: arm
        links:
          base: {visual: {box: {size: [1, 1, 1]}}
        """,
        ["robot.yaml:4: invalid YAML: the {...} mapping opened at line 3 is not closed: a '}' or ',' is missing"],
    ),
    "invalid_yaml_unclosed_list": (
        """
        robot: arm
        links:
          base: {visual: {box: {size: [1, 1, 1}}}
        """,
        ["robot.yaml:3: invalid YAML: the [...] list opened at line 3 is not closed: a ']' or ',' is missing"],
    ),
    "invalid_yaml_indentation": (
        """
        robot: arm
        links:
          base:
            visual: {box: {size: [1, 1, 1]}}
           inertial: {mass: 1}
        """,
        ["robot.yaml:5: invalid YAML: this line is indented differently from the keys of the mapping at line 3 "
         "(indent with spaces, aligned)"],
    ),
    "invalid_yaml_tab": (
        "robot: arm\nlinks:\n\tbase: {visual: {box: {size: [1, 1, 1]}}}\n",
        ["robot.yaml:3: invalid YAML: a tab character: YAML indents with spaces only"],
    ),
    "invalid_yaml_colon_in_value": (
        """
        robot: arm
        links:
          base: {visual: {box: {size: [1, 1, 1]}}}
        description: a robot: the arm
        """,
        ["robot.yaml:4: invalid YAML: a ': ' where no key may start: quote a value that contains ': ', "
         "or put the key on its own line"],
    ),
    "unknown_key": (
        """
        robot: arm
        links:
          base:
            visual: {box: {size: [1, 1, 1]}}
            inertial: {denisty: 3}
        """,
        ["robot.yaml:5: links.base.inertial.denisty: unknown key (did you mean 'density'?)"],
    ),
    "unknown_top_level_key": (
        """
        robot: arm
        linkz: {}
        links: {a: {}}
        """,
        ["robot.yaml:2: linkz: unknown key (did you mean 'links'?)"],
    ),
    "wrong_type": (
        """
        robot: arm
        links:
          base:
            visual: {box: {size: [1, one, 1]}}
        """,
        ["robot.yaml:4: links.base.visual.box.size[1]: must be a number (got 'one')"],
    ),
    "missing_mesh_file": (
        """
        robot: arm
        links:
          base:
            visual: {mesh: nothere.stl}
        """,
        ["robot.yaml:4: links.base.visual.mesh: mesh file 'nothere.stl' does not exist"],
    ),
    "missing_mesh_file_with_inertial": (  # one line: not also "the inertial needs geometry"
        """
        robot: arm
        links:
          base:
            visual: {mesh: nothere.stl, units: mm}
            inertial: {mass: 1}
        """,
        ["robot.yaml:4: links.base.visual.mesh: mesh file 'nothere.stl' does not exist"],
    ),
    "unreadable_mesh": (
        """
        robot: arm
        links:
          base:
            visual: {mesh: trunc.stl}
        """,
        ["robot.yaml:4: links.base.visual.mesh: mesh file 'trunc.stl' is truncated: "
         "its header announces 28 triangles (1484 bytes), the file has 300 bytes"],
    ),
    "not_a_mesh": (
        """
        robot: arm
        links:
          base:
            visual: {mesh: garbage.obj}
        """,
        ["robot.yaml:4: links.base.visual.mesh: mesh file 'garbage.obj' holds no triangles"],
    ),
    "zero_density_and_negative_mass": (
        """
        robot: arm
        density: 0
        links:
          base:
            visual: {box: {size: [1, 1, 1]}}
            inertial: {mass: -2}
        """,
        ["robot.yaml:2: density: must be > 0",
         "robot.yaml:6: links.base.inertial.mass: must be > 0"],
    ),
    "negative_link_density": (
        """
        robot: arm
        links:
          arm:
            visual: {box: {size: [1, 1, 1]}}
            inertial:
              density: -1250
        """,
        ["robot.yaml:6: links.arm.inertial.density: must be > 0"],
    ),
    "joint_names_missing_link": (
        """
        robot: arm
        links:
          base:
            visual: {box: {size: [1, 1, 1]}}
        joints:
          j1: {type: fixed, parent: base, child: arm}
        """,
        ["robot.yaml:6: joints.j1.child: no link named 'arm'"],
    ),
    "misspelt_link_gets_a_suggestion": (
        """
        robot: arm
        links:
          base: {}
          upper_arm: {}
        joints:
          j1: {type: fixed, parent: base, child: uper_arm}
        """,
        ["robot.yaml:6: joints.j1.child: no link named 'uper_arm' (did you mean 'upper_arm'?)"],
    ),
    "cycle": (
        """
        robot: arm
        links: {a: {}, b: {}, c: {}, d: {}}
        joints:
          j1: {type: fixed, parent: a, child: b}
          j2: {type: fixed, parent: c, child: d}
          j3: {type: fixed, parent: d, child: c}
        """,
        ["robot.yaml:5: joints.j2: joints 'j2', 'j3' form a cycle"],
    ),
    "no_link": (
        """
        robot: arm
        links: {}
        """,
        ["robot.yaml:2: links: no link: a robot needs at least one"],
    ),
    "two_roots": (
        """
        robot: arm
        links: {a: {}, b: {}, c: {}}
        joints:
          j1: {type: fixed, parent: a, child: b}
        """,
        ["robot.yaml:2: links: the links form 2 separate trees with roots 'a', 'c'; "
         "connect them with joints so one root remains"],
    ),
    "two_parents": (
        """
        robot: arm
        links: {a: {}, b: {}, c: {}}
        joints:
          j1: {type: fixed, parent: a, child: b}
          j2: {type: fixed, parent: c, child: b}
        """,
        ["robot.yaml:5: joints.j2.child: link 'b' already has a parent (joint 'j1'); a link has at most one",
         "robot.yaml:2: links: the links form 2 separate trees with roots 'a', 'c'; "
         "connect them with joints so one root remains"],
    ),
    "duplicate_name": (
        """
        robot: arm
        links:
          a: {}
          a: {}
        """,
        ["robot.yaml:4: links.a: duplicate key (first given on line 3)"],
    ),
    "bad_robot_name": (
        """
        robot: 'my arm'
        links: {a: {}}
        """,
        ["robot.yaml:1: robot: invalid name 'my arm': a name starts with a letter or '_' and holds only "
         "letters, digits, '_', '-' and '.'"],
    ),
    "two_shapes": (
        """
        robot: arm
        links:
          a: {visual: {box: {size: [1, 1, 1]}, sphere: {radius: 1}}}
        """,
        ["robot.yaml:3: links.a.visual: give exactly one of mesh, box, cylinder, sphere (found: box, sphere)"],
    ),
    "revolute_without_limits": (
        """
        robot: arm
        links: {a: {}, b: {}}
        joints:
          j: {type: revolute, parent: a, child: b}
        """,
        ["robot.yaml:4: joints.j: a revolute joint needs limit lower, upper, effort, velocity"],
    ),
    "unknown_joint_type": (
        """
        robot: arm
        links: {a: {}, b: {}}
        joints:
          j: {type: hinge, parent: a, child: b}
        """,
        ["robot.yaml:4: joints.j.type: must be one of 'fixed', 'revolute', 'continuous', 'prismatic', "
         "'floating' or 'planar' (got 'hinge')"],
    ),
    "open_mesh_is_an_error_by_default": (
        """
        robot: arm
        links:
          a: {visual: {mesh: open.stl}}
        """,
        ["robot.yaml:3: links.a.visual.mesh: mesh 'open.stl' is not a closed volume (32 open edges), so its "
         "mass properties would be wrong; repair the mesh, give an explicit inertial, or set 'open_mesh: hull'"],
    ),
    "every_problem_at_once": (
        """
        robot: arm
        density: -5
        materials:
          red: {rgba: [1, 0, 0, 1]}
        links:
          base:
            visual: {mesh: base.stl, material: rd}
          arm:
            visual: {box: {size: [1, 1, 0]}}
          hand:
            visual: {mesh: missing.stl}
        joints:
          j1: {type: revolute, parent: base, child: arm, limit: {lower: 0, upper: 1, effort: 1, velocity: 1}}
          j2: {type: hinge, parent: arm, child: hand}
          j3: {type: fixed, parent: base, child: nolink}
        """,
        ["robot.yaml:2: density: must be > 0",
         "robot.yaml:7: links.base.visual.material: no material named 'rd' (did you mean 'red'?)",
         "robot.yaml:9: links.arm.visual.box.size[2]: must be > 0",
         "robot.yaml:11: links.hand.visual.mesh: mesh file 'missing.stl' does not exist",
         "robot.yaml:14: joints.j2.type: must be one of 'fixed', 'revolute', 'continuous', 'prismatic', "
         "'floating' or 'planar' (got 'hinge')",
         "robot.yaml:15: joints.j3.child: no link named 'nolink'"],
    ),
}


@pytest.fixture
def folder(tmp_path):
    import trimesh

    shutil.copyfile(BASE_STL, tmp_path / "base.stl")
    (tmp_path / "trunc.stl").write_bytes(BASE_STL.read_bytes()[:300])
    (tmp_path / "garbage.obj").write_text("this is not a mesh\n")
    tube = trimesh.creation.cylinder(radius=0.05, height=0.1, sections=32)
    up = tube.face_normals[:, 2] < 0.99  # no top cap: a 32-edge hole, too large to fill
    trimesh.Trimesh(tube.vertices, tube.faces[up]).export(tmp_path / "open.stl")
    return tmp_path


@pytest.mark.slow
@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_input(folder, case):
    text, expected = CASES[case]
    (folder / "robot.yaml").write_text(textwrap.dedent(text).lstrip(), encoding="utf-8")
    proc = run_cli("build", "robot.yaml", "--out", "out", cwd=folder)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.splitlines() == expected
    assert proc.stdout == ""
    written = [p for p in (folder / "out").rglob("*") if p.is_file() and ".robotkit" not in p.parts] \
        if (folder / "out").exists() else []
    assert written == []


def test_problems_in_an_included_file_name_that_file(folder):
    (folder / "parts").mkdir()
    (folder / "parts" / "arm.yaml").write_text("links:\n  arm:\n    inertial: {density: 0}\n")
    (folder / "robot.yaml").write_text("robot: arm\ninclude: [parts/arm.yaml]\nlinks:\n  base: {}\n"
                                       "joints:\n  j: {type: fixed, parent: base, child: arm}\n")
    proc = run_cli("build", "robot.yaml", "--out", "out", cwd=folder)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == ["parts/arm.yaml:3: links.arm.inertial.density: must be > 0"]


def test_missing_recipe_file(folder):
    proc = run_cli("build", "nofile.yaml", cwd=folder)
    assert (proc.returncode, proc.stderr) == (2, "nofile.yaml: file not found\n")


def test_usage_errors_exit_2(folder):
    proc = run_cli("build", cwd=folder)
    assert proc.returncode == 2
    assert proc.stderr.splitlines()[-1] == "robotkit: error: the following arguments are required: RECIPE"
    proc = run_cli("build", "x.yaml", "-j", "0", cwd=folder)
    assert (proc.returncode, proc.stderr) == (2, "robotkit: error: -j must be at least 1\n")
