"""Hostile and broken input: nothing crashes, nothing escapes, nothing hangs.

A corpus of malformed recipes (numbers, names, YAML bombs, reads and writes outside the
allowed places), each answered word for word: one line per problem with file:line: key,
exit 2, no traceback, nothing written.  Then a bounded mutation fuzzer over the example
recipes (ROBOTKIT_FUZZ_SECONDS, 60 s under CI) with the same rules; a build that passes
must leave a complete output.  And the outputs of one recipe built from two places and two
working folders are byte-identical, report.json included.
"""

from __future__ import annotations

import os
import random
import re
import shutil
import textwrap
import time
from pathlib import Path

import pytest
import yaml

from conftest import RECIPES, tree_bytes

BOX = "{visual: {box: {size: [0.1, 0.1, 0.1]}}}"
REFUSED = ("is outside the project ./: robotkit reads only the project and declared package paths "
           "(widen on purpose with --root DIR or ROBOTKIT_ROOT)")
NAME_HINT = "a name starts with a letter or '_' and holds only letters, digits, '_', '-' and '.'"


def run(args: list[str], cwd: Path, capsys, monkeypatch) -> tuple[int, str, str]:
    """``robotkit ARGS`` in this process (an escaping exception fails the test: a traceback)."""
    from robotkit.cli import main

    monkeypatch.chdir(cwd)
    rc = main([str(a) for a in args])
    out = capsys.readouterr()
    return rc, out.out, out.err


def files_below(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file() or p.is_symlink()}


def written(out: Path) -> list[str]:
    """Files under the output folder outside its state folder."""
    return sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file() and ".robotkit" not in p.parts) \
        if out.exists() else []


# ---------------------------------------------------------------- the corpus

CASES = {
    "nan_inf_and_overflow": (
        """
        robot: arm
        density: 1e308
        links:
          base: {visual: {box: {size: [1, 1, 1]}, origin: {xyz: [.nan, 0, 0]}}}
          b2:
            visual: {sphere: {radius: .inf}}
            inertial: {mass: .inf}
          b3:
            visual: {box: {size: [1e-300, 1, 1]}}
            inertial: {mass: -.inf}
        joints:
          j: {type: fixed, parent: base, child: b2}
          k: {type: revolute, parent: base, child: b3, limit: {lower: -1, upper: 1e400, effort: 1, velocity: 1}}
        """,
        ["robot.yaml:2: density: must be <= 100000",
         "robot.yaml:4: links.base.visual.origin.xyz[0]: must be a finite number (got nan)",
         "robot.yaml:6: links.b2.visual.sphere.radius: must be a finite number (got inf)",
         "robot.yaml:7: links.b2.inertial.mass: must be a finite number (got inf)",
         "robot.yaml:9: links.b3.visual.box.size[0]: must be at least 1e-6 m (got 1e-300)",
         "robot.yaml:10: links.b3.inertial.mass: must be a finite number (got -inf)",
         "robot.yaml:13: joints.k.limit.upper: must be a finite number (got '1e400')"],
    ),
    "huge_integers_and_counts": (
        """
        robot: arm
        links:
          base:
            visual: {box: {size: [1, 1, 1]}}
            collision: {strategy: decompose, coacd: {resolution: 1000000000000000000000000000000}}
        sensors:
          lidar: {type: lidar, parent: base, lidar: {samples: 100000000000}, update_rate: 1e9}
        """,
        ["robot.yaml:5: links.base.collision.coacd.resolution: must be <= 100000000",
         "robot.yaml:7: sensors.lidar.update_rate: must be <= 1e6",
         "robot.yaml:7: sensors.lidar.lidar.samples: must be <= 1000000"],
    ),
    "names_that_become_file_names": (
        f"""
        robot: arm
        links:
          base: {BOX}
          {"l" * 300}: {BOX}
        sensors:
          cam: {{type: camera, parent: base, frame: ../../../../x}}
        worlds:
          {"w" * 101}: {{map: map.yaml}}
        """,
        ["robot.yaml:4: links." + "l" * 300 + ": name is 300 characters long; names that become file names "
         "are at most 100",
         "robot.yaml:6: sensors.cam.frame: invalid name '../../../../x': " + NAME_HINT,
         "robot.yaml:8: worlds." + "w" * 101 + ": name is 101 characters long; names that become file names "
         "are at most 100"],
    ),
    "urdf_extras_declaration_and_malformed": (
        """
        robot: arm
        links: {base: {}}
        urdf_extras:
          - '<?xml version="1.0"?><gazebo/>'
          - '<gazebo><plugin></gazebo>'
        """,
        ["robot.yaml:4: urdf_extras[0]: starts with an XML declaration or processing instruction: "
         "give the element alone",
         "robot.yaml:5: urdf_extras[1]: not well-formed XML: mismatched tag: line 1, column 18"],
    ),
    "recursive_alias": (
        """
        robot: arm
        links:
          base: &b {visual: [*b]}
        """,
        ["robot.yaml:3: alias '*b' refers to a node that contains it (recursive alias)"],
    ),
    "alias_bomb": (
        "robot: arm\nlinks: {base: {}}\nvalues:\n  a0: &a0 [x, x, x, x, x, x, x, x, x]\n"
        + "".join(f"  a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]\n" for i in range(1, 9)),
        ["robot.yaml:10: aliases expand to more than 1,000,000 values (an alias bomb?)"],
    ),
    "deep_nesting": (
        "robot: arm\nlinks: {base: {}}\nvalues: {x: " + "[" * 5000 + "]" * 5000 + "}\n",
        ["robot.yaml:3: nested deeper than 64 levels"],
    ),
    "nul_and_overlong_file_names": (
        'robot: arm\ninclude: ["a\\0b", "' + "x" * 300 + '.yaml"]\nlinks:\n  base: {visual: {mesh: "x\\0.stl"}}\n',
        ["robot.yaml:2: include[0]: included file 'a\\x00b' is not a valid file name (it holds a NUL character)",
         "robot.yaml:2: include[1]: included file '" + "x" * 300 + ".yaml' does not exist",
         "robot.yaml:4: links.base.visual.mesh: mesh file '{root}/x\\x00.stl' is not a valid file name "
         "(it holds a NUL character)"],
    ),
    "reads_outside_the_project": (
        """
        robot: arm
        include: [/etc/passwd]
        parts:
          p: ../outside.yaml
        instances:
          i: {part: p, parent: base}
        links:
          base: {visual: {mesh: ../secret.stl}}
          b: {visual: {mesh: /etc/hostname.stl}}
          c: {visual: {mesh: link.stl}}
        joints:
          j: {type: fixed, parent: base, child: b}
          k: {type: fixed, parent: base, child: c}
        worlds:
          w: {map: ../map.yaml}
        """,
        ["robot.yaml:2: include[0]: included file '/etc/passwd' " + REFUSED,
         "robot.yaml:4: parts.p: part file '../outside.yaml' " + REFUSED,
         "robot.yaml:8: links.base.visual.mesh: mesh file '{parent}/secret.stl' " + REFUSED,
         "robot.yaml:9: links.b.visual.mesh: mesh file '/etc/hostname.stl' " + REFUSED,
         "robot.yaml:10: links.c.visual.mesh: mesh file 'link.stl' " + REFUSED,
         "robot.yaml:15: worlds.w.map: map file '{parent}/map.yaml' " + REFUSED],
    ),
}


@pytest.fixture
def project(tmp_path, monkeypatch):
    """A recipe's folder (its project: no repository above it) with a real mesh, a symlink
    pointing out of it, and files outside it that a recipe must not read."""
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)
    folder = tmp_path / "project"
    folder.mkdir()
    shutil.copyfile(RECIPES / "meshes" / "turret_bot" / "base.stl", folder / "base.stl")
    shutil.copyfile(RECIPES / "meshes" / "turret_bot" / "base.stl", tmp_path / "secret.stl")
    (tmp_path / "outside.yaml").write_text("links: {x: {}}\n")
    (tmp_path / "map.yaml").write_text("image: map.pgm\n")
    os.symlink(tmp_path / "secret.stl", folder / "link.stl")
    return folder


@pytest.mark.parametrize("case", sorted(CASES))
def test_malformed_recipe(project, case, capsys, monkeypatch):
    text, expected = CASES[case]
    (project / "robot.yaml").write_text(textwrap.dedent(text).lstrip(), encoding="utf-8")
    before = files_below(project.parent)
    rc, out, err = run(["build", "robot.yaml", "--out", "out", "-j", "1", "--no-report"], project, capsys,
                       monkeypatch)
    expected = [line.format(root=project, parent=project.parent) for line in expected]
    assert (rc, out, err.splitlines()) == (2, "", expected)
    assert written(project / "out") == []
    assert files_below(project.parent) - before <= {f"project/out/{p}" for p in files_below(project / "out")}


def test_oversized_yaml_is_refused_before_it_is_read(project, capsys, monkeypatch):
    from robotkit.recipe.yamlsafe import MAX_YAML_BYTES

    with open(project / "robot.yaml", "w") as f:
        f.write("robot: arm\nlinks: {base: {}}\n")
        f.truncate(MAX_YAML_BYTES + 1)
    rc, _, err = run(["build", "robot.yaml", "--out", "out"], project, capsys, monkeypatch)
    assert (rc, err) == (2, f"robot.yaml: file is {MAX_YAML_BYTES + 1:,} bytes; robotkit reads YAML files of "
                            f"at most {MAX_YAML_BYTES:,} bytes\n")


def test_root_widens_the_reads_on_purpose(project, capsys, monkeypatch):
    (project / "robot.yaml").write_text("robot: arm\nlinks:\n  base: {visual: {mesh: ../secret.stl}}\n")
    rc, _, err = run(["expand", "robot.yaml"], project, capsys, monkeypatch)
    assert rc == 0  # expansion reads no mesh
    rc, _, err = run(["build", "robot.yaml", "--out", "out", "-j", "1", "--no-report"], project, capsys,
                     monkeypatch)
    assert rc == 2 and "is outside the project" in err
    rc, _, err = run(["build", "robot.yaml", "--out", "out", "-j", "1", "--no-report", "--root", ".."], project,
                     capsys, monkeypatch)
    assert rc == 0, err
    assert (project / "out" / "arm" / "meshes" / "visual" / "secret.stl").is_file()
    # the symlink still points out of every root given
    (project / "robot.yaml").write_text("robot: arm\nlinks:\n  base: {visual: {mesh: link.stl}}\n")
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)
    rc, _, err = run(["build", "robot.yaml", "--out", "out", "-j", "1", "--no-report"], project, capsys,
                     monkeypatch)
    assert rc == 2 and err.startswith("robot.yaml:3: links.base.visual.mesh: mesh file 'link.stl' is outside")


# ---------------------------------------------------------------- a failed build, stale outputs


def test_a_failed_build_keeps_the_previous_complete_output(project, capsys, monkeypatch):
    shutil.copyfile(project / "base.stl", project / "tip.stl")
    good = "robot: arm\nlinks:\n  base: {visual: {mesh: base.stl}}\n  tip: {visual: {mesh: tip.stl}}\n" \
           "joints:\n  j: {type: fixed, parent: base, child: tip}\n"
    (project / "robot.yaml").write_text(good)
    args = ["build", "robot.yaml", "--out", "out", "-j", "1", "--no-report"]
    assert run(args, project, capsys, monkeypatch)[0] == 0
    complete = tree_bytes(project / "out")
    shutil.copyfile(project / "base.stl", project / "base.bak")
    (project / "base.stl").write_bytes((project / "base.bak").read_bytes()[:300])  # a task fails
    (project / "robot.yaml").write_text(good + "metadata: {description: changed}\n")  # other tasks run
    rc, _, err = run(args, project, capsys, monkeypatch)
    assert rc == 2 and "is truncated" in err
    assert tree_bytes(project / "out") == complete
    # the tip link goes: its files go with it (only what this build produces is published)
    shutil.copyfile(project / "base.bak", project / "base.stl")
    (project / "robot.yaml").write_text("robot: arm\nlinks:\n  base: {visual: {mesh: base.stl}}\n")
    assert run(args, project, capsys, monkeypatch)[0] == 0
    now = tree_bytes(project / "out")
    assert sorted(set(complete) - set(now)) == ["arm/meshes/collision/tip.obj", "arm/meshes/visual/tip.stl"]
    assert "tip" not in (project / "out" / "arm" / "urdf" / "arm.urdf").read_text()
    # a file dropped into the published folder by hand is not part of the output
    (project / "out" / "arm" / "stray.txt").write_text("x")
    (project / "robot.yaml").write_text("robot: arm\nmetadata: {description: again}\n"
                                        "links:\n  base: {visual: {mesh: base.stl}}\n")
    assert run(args, project, capsys, monkeypatch)[0] == 0
    assert not (project / "out" / "arm" / "stray.txt").exists()


# ---------------------------------------------------------------- independent of location


def test_outputs_do_not_depend_on_where_the_recipe_sits_or_robotkit_runs(tmp_path, capsys, monkeypatch):
    """The same recipe in two folders, built from different working folders: byte-identical
    outputs, report.json included."""
    outs = []
    for place, cwd_of in (("a/deep/er", lambda r: r), ("b", lambda r: r.parent.parent)):
        folder = tmp_path / place / "recipes"
        shutil.copytree(RECIPES, folder)
        out = tmp_path / place / "out"
        rc, _, err = run(["build", folder / "turret_bot.yaml", "--out", out, "-j", "1", "--no-report"],
                         cwd_of(folder), capsys, monkeypatch)
        assert rc == 0, err
        outs.append(tree_bytes(out))
    assert outs[0] == outs[1]
    assert str(tmp_path).encode() not in b"".join(outs[0].values())


# ---------------------------------------------------------------- the fuzzer

HOSTILE = [float("nan"), float("inf"), -float("inf"), 1e308, -1e308, 1e-308, 0, -1, 10 ** 30, -(10 ** 30), "",
           "../../../../x", "/etc/passwd", "x" * 300, "${9**9**9}", "${1e308*10}", "${1/0}", "5 parsec", None, [],
           {}, True, "<?xml version='1.0'?><a/>", "a b", ".hidden", 3.5, "90 deg", "-0"]
LINE = re.compile(r"^(?P<file>[^:\s][^:]*?)(:(?P<line>\d+))?: (?P<rest>.+)$")
CHEAP = ("turret_bot.yaml", "lidar_mast.yaml", "quadruped.yaml")  # full builds of these take seconds
USED_BY = {"parts/leg.yaml": "quadruped.yaml", "include/turtlebot3_burger.gazebo.yaml": "turtlebot3_burger.yaml"}


def _paths(node, prefix=()):
    yield prefix
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, prefix + (i,))


def _mutate(data, rng: random.Random) -> tuple[object, str]:
    """A copy of ``data`` with one value replaced, deleted or duplicated; and what was done."""
    import copy

    data = copy.deepcopy(data)
    paths = [p for p in _paths(data) if p]
    if not paths:
        return data, "nothing left to mutate"
    path = rng.choice(paths)
    parent = data
    for k in path[:-1]:
        parent = parent[k]
    how = rng.random()
    if how < 0.1 and isinstance(parent, dict):
        del parent[path[-1]]
        return data, f"delete {path}"
    if how < 0.15 and isinstance(parent, dict):
        parent[f"{path[-1]}_copy"] = parent[path[-1]]
        return data, f"duplicate {path}"
    value = rng.choice(HOSTILE)
    parent[path[-1]] = value
    return data, f"{path} = {value!r:.60}"


def _check_answer(rc: int, out: str, err: str, what: str, folder: Path):
    lines = [line for line in err.splitlines() if not line.startswith("warning: ")
             and not line.endswith("(-v shows them; report.json lists what each format could not express)")]
    assert "Traceback" not in err, what
    assert rc in (0, 1, 2), (what, rc, err)
    if rc == 0:
        return
    assert lines, what
    for line in lines:
        m = LINE.match(line)
        assert m, (what, line)
        assert m["file"].endswith((".yaml", ".stl", ".obj", ".dae", ".pgm", ".png")) or m["file"].startswith(
            "--arg"), (what, line)


def load(recipe: Path, cwd: Path, monkeypatch) -> tuple[int, str, str]:
    """What ``robotkit build`` answers before it runs a task (load, expand, validate, resolve),
    as the CLI prints it."""
    from robotkit.errors import RobotkitError
    from robotkit.model.load import load_robots

    monkeypatch.chdir(cwd)
    try:
        load_robots([recipe])
    except RobotkitError as exc:
        return exc.exit_status, "", "".join(line + "\n" for line in exc.lines())
    return 0, "", ""


@pytest.mark.slow
def test_fuzz_example_recipes(tmp_path, capsys, monkeypatch):
    """Random single mutations of the example recipes, for a bounded time: every answer is a
    clean exit with one located line per problem, never a traceback; a failed build writes
    nothing; nothing is written outside the output folder."""
    seconds = float(os.environ.get("ROBOTKIT_FUZZ_SECONDS", 60 if os.environ.get("CI") else 10))
    seed = int(os.environ.get("ROBOTKIT_FUZZ_SEED", time.time()))
    rng = random.Random(seed)
    folder = tmp_path / "recipes"
    shutil.copytree(RECIPES, folder)
    sources = {str(p.relative_to(RECIPES)): yaml.safe_load(p.read_text()) for p in sorted(RECIPES.glob("*.yaml"))}
    sources.update({name: yaml.safe_load((RECIPES / name).read_text()) for name in USED_BY})  # part, included file
    before = files_below(tmp_path)
    end = time.monotonic() + seconds
    runs = builds = 0
    while time.monotonic() < end or runs < 5:
        name = rng.choice(sorted(sources))
        data, what = _mutate(sources[name], rng)
        for _ in range(rng.choice([0, 0, 0, 1, 2])):  # sometimes several at once
            data, more = _mutate(data, rng)
            what += f"; {more}"
        text = yaml.safe_dump(data, sort_keys=False)
        if rng.random() < 0.1:  # and sometimes the text itself: a line dropped, the file cut short
            lines = text.splitlines(keepends=True)
            cut = rng.randrange(len(lines))
            text = "".join(lines[:cut] + lines[cut + 1:]) if rng.random() < 0.5 else text[:rng.randrange(len(text))]
            what += f"; text edit at line {cut + 1}"
        what = f"seed {seed}, run {runs}: {name}: {what}"
        recipe = USED_BY.get(name, "fuzz.yaml")
        for other in USED_BY:  # the part and included files as they were, but the one mutated
            shutil.copyfile(RECIPES / other, folder / other)
        (folder / (name if name in USED_BY else "fuzz.yaml")).write_text(text, encoding="utf-8")
        shutil.rmtree(folder / "out", ignore_errors=True)
        try:
            rc, out, err = load(folder / recipe, folder, monkeypatch)
        except Exception as exc:  # a traceback: report the mutation that caused it
            raise AssertionError(f"{what}: {type(exc).__name__}: {exc}") from exc
        _check_answer(rc, out, err, what, folder)
        if rc == 0 and (name in CHEAP or USED_BY.get(name) in CHEAP):
            builds += 1
            try:
                rc, out, err = run(["build", recipe, "--out", "out", "-j", "1", "--no-report"], folder, capsys,
                                   monkeypatch)
            except Exception as exc:
                raise AssertionError(f"{what}: {type(exc).__name__}: {exc}") from exc
            _check_answer(rc, out, err, what, folder)
            if rc == 2:
                assert written(folder / "out") == [], what
        runs += 1
    assert files_below(tmp_path) - before <= {f"recipes/{p}" for p in files_below(folder)}
    print(f"fuzz: {runs} mutations, {builds} builds, seed {seed}")


# ---------------------------------------------------------------- open meshes


def test_repair_fills_only_holes_small_against_the_mesh():
    """By area and perimeter, not edge count: a sphere missing half its faces stays open; a
    small cap of many edges is filled, with the volume a hair under the closed sphere's."""
    import numpy as np
    import trimesh

    from robotkit.mesh.repair import repair

    sphere = trimesh.creation.icosphere(subdivisions=4, radius=1.0)
    centres = sphere.triangles_center
    half = trimesh.Trimesh(sphere.vertices, sphere.faces[centres[:, 2] > 0], process=False)
    fixed, report = repair(half)
    assert (report["holes_found"], report["holes_filled"], report["is_volume"]) == (1, 0, False)
    cap = centres[:, 2] < 0.97  # a cap of 2.5 % of the surface, its rim has more than 16 edges
    capped = trimesh.Trimesh(sphere.vertices, sphere.faces[cap], process=False)
    fixed, report = repair(capped)
    assert report["holes_filled"] == 1 and report["is_volume"] and report["faces_added"] > 16
    assert sphere.volume * 0.995 < fixed.volume < sphere.volume
    assert report["hole_area"] == pytest.approx(np.pi * (1 - 0.97 ** 2), rel=0.1)  # the flat disc under the cap
    three = (np.abs(centres[:, 2]) < 0.97) & (centres[:, 0] < 0.97)  # three caps, each filled with its own fan
    fixed, report = repair(trimesh.Trimesh(sphere.vertices, sphere.faces[three], process=False))
    assert (report["holes_filled"], report["vertices_added"], report["is_volume"]) == (3, 3, True)
    assert sphere.volume * 0.99 < fixed.volume < sphere.volume
    slit = (np.abs(centres[:, 2]) < 0.03) & (centres[:, 0] > -0.7)  # along 3/4 of the equator: long, narrow
    _, report = repair(trimesh.Trimesh(sphere.vertices, sphere.faces[~slit], process=False))
    assert (report["holes_found"], report["holes_filled"]) == (1, 0)


def test_a_filled_hole_that_may_change_the_volume_is_warned_about(project, capsys, monkeypatch):
    import trimesh

    box = trimesh.creation.box([0.1, 0.1, 0.1])
    trimesh.Trimesh(box.vertices, box.faces[1:], process=False).export(project / "open.stl")  # half a side
    (project / "robot.yaml").write_text("robot: arm\nlinks:\n  base: {visual: {mesh: open.stl}}\n")
    rc, out, err = run(["build", "robot.yaml", "--out", "out", "-j", "1", "--no-report"], project, capsys,
                       monkeypatch)
    assert rc == 0, err
    assert "robot.yaml:3: links.base.visual.mesh: warning: mesh 'open.stl': filled 1 holes (0.005 m^2, 8.3% of " \
           "its surface) with flat patches; if the missing surface was not flat, the volume and the mass " \
           "properties may be off by up to 13%" in err.splitlines()


# ---------------------------------------------------------------- imported and checked files

CYCLIC_URDF = """<?xml version="1.0"?>
<robot name="cyc">
  <link name="a"/>
  <link name="b"/>
  <link name="c"/>
  <joint name="j1" type="fixed"><parent link="a"/><child link="b"/></joint>
  <joint name="j2" type="fixed"><parent link="c"/><child link="b"/></joint>
  <joint name="j3" type="fixed"><parent link="b"/><child link="c"/></joint>
  <joint name="j4" type="fixed"><parent link="b"/><child link="nowhere"/></joint>
</robot>
"""


def test_import_errors_name_the_imported_file_and_line(tmp_path, capsys, monkeypatch):
    (tmp_path / "cyc.urdf").write_text(CYCLIC_URDF.replace(
        '  <joint name="j4" type="fixed"><parent link="b"/><child link="nowhere"/></joint>\n', ""))
    rc, out, err = run(["import", "cyc.urdf", "-o", "recipe/cyc.yaml"], tmp_path, capsys, monkeypatch)
    assert (rc, out) == (2, "")
    assert err.splitlines() == [
        "cyc.urdf:7: joints.j2.child: link 'b' already has a parent (joint 'j1'); a link has at most one",
        "cyc.urdf:7: joints.j2: joints 'j2', 'j3' form a cycle"]
    assert not (tmp_path / "recipe").exists() or files_below(tmp_path / "recipe") == set()


def test_check_of_a_broken_urdf_tree_is_located_and_ends(tmp_path, capsys, monkeypatch):
    """check_urdf prints a cyclic tree forever and simulators crash on it: the tree is checked
    first, each finding with its file and line (JSON too)."""
    import json

    (tmp_path / "cyc.urdf").write_text(CYCLIC_URDF.replace('<parent link="c"/><child link="b"/>',
                                                           '<parent link="c"/><child link="a"/>'))
    rc, out, err = run(["check", "cyc.urdf", "--format", "json"], tmp_path, capsys, monkeypatch)
    assert (rc, err) == (1, "")
    found = [(f["subject"], f["message"], f["file"], f["line"]) for f in json.loads(out)["findings"]]
    assert found == [("joint 'j4'", "its child link 'nowhere' is not a link of the robot", "cyc.urdf", 9),
                     ("link 'a'", "its joints form a cycle: a <- c <- b <- a", "cyc.urdf", 3)]


def test_meshes_are_bounded_before_and_after_they_are_decoded(project, capsys, monkeypatch):
    import numpy as np
    import trimesh

    from robotkit.mesh import io

    (project / "far.obj").write_text("v 0 0 0\nv 1e30 0 0\nv 0 1e30 0\nv 0 0 1e30\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n")
    (project / "robot.yaml").write_text("robot: arm\nlinks:\n  base: {visual: {mesh: far.obj}}\n"
                                        "  b: {visual: {mesh: base.stl, scale: 1000000}}\n"
                                        "joints:\n  j: {type: fixed, parent: base, child: b}\n")
    rc, _, err = run(["build", "robot.yaml", "--out", "out", "-j", "1", "--no-report"], project, capsys,
                     monkeypatch)
    reach = float(np.abs(trimesh.load(project / "base.stl").vertices).max()) * 1e6
    assert (rc, written(project / "out")) == (2, [])
    assert sorted(err.splitlines()) == [  # in the order the mesh tasks ran
        "robot.yaml:3: links.base.visual.mesh: mesh file 'far.obj' reaches 1e+30 m from its origin once scaled; "
        "robotkit takes meshes within 10000 m (check its units or scale)",
        f"robot.yaml:4: links.b.visual.mesh: mesh file 'base.stl' reaches {reach:.3g} m from its origin once "
        "scaled; robotkit takes meshes within 10000 m (check its units or scale)"]
    monkeypatch.setattr(io, "MAX_MESH_BYTES", 100)
    with pytest.raises(io.MeshError) as exc:
        io.load_mesh(str(project / "base.stl"))
    size = (project / "base.stl").stat().st_size
    assert str(exc.value.problems[0]) == f"mesh file 'base.stl' is {size:,} bytes; robotkit reads meshes of at " \
                                         "most 100 bytes"
