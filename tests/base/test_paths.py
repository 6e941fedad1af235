"""The one place that decides where robotkit reads and writes (robotkit/paths.py)."""

import os

import pytest

from robotkit.errors import RobotkitError
from robotkit.paths import MAX_NAME, ReadPolicy, file_stem, inside, name_problem, out_join, project_root


def test_project_root_is_the_repository_holding_the_file(tmp_path):
    (tmp_path / "repo" / ".git").mkdir(parents=True)
    (tmp_path / "repo" / "recipes").mkdir()
    recipe = tmp_path / "repo" / "recipes" / "arm.yaml"
    recipe.write_text("name: arm\n")
    assert project_root(recipe) == (tmp_path / "repo").resolve()
    loose = tmp_path / "loose.yaml"
    loose.write_text("")
    assert project_root(loose) == tmp_path.resolve()


def test_reads_outside_the_project_are_refused_with_key(tmp_path, monkeypatch):
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)
    (tmp_path / "repo" / ".git").mkdir(parents=True)
    recipe = tmp_path / "repo" / "arm.yaml"
    recipe.write_text("")
    (tmp_path / "repo" / "m.stl").write_text("")
    (tmp_path / "secret").write_text("")
    os.symlink(tmp_path / "secret", tmp_path / "repo" / "link.stl")
    policy = ReadPolicy.for_file(recipe)
    assert policy.allows(tmp_path / "repo" / "m.stl")
    assert not policy.allows(tmp_path / "repo" / ".." / "secret")
    assert not policy.allows(tmp_path / "repo" / "link.stl")  # symlink out of the project
    assert not policy.allows("/etc/passwd")
    p = policy.problem("/etc/passwd", file=str(recipe), line=3, key="links.a.visual.mesh")
    assert str(p).endswith("links.a.visual.mesh: /etc/passwd is outside the project "
                           f"{tmp_path / 'repo'}/: robotkit reads only the project and declared package "
                           "paths (widen on purpose with --root DIR or ROBOTKIT_ROOT)")
    assert ReadPolicy.for_file(recipe, extra_roots=[tmp_path]).allows(tmp_path / "secret")
    monkeypatch.setenv("ROBOTKIT_ROOT", str(tmp_path))
    assert ReadPolicy.for_file(recipe).allows(tmp_path / "secret")
    assert ReadPolicy.for_file(recipe, packages={"pkg": "/etc"}).allows("/etc/passwd")


def test_writes_stay_in_the_output_folder(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    assert out_join(out, "urdf", "arm.urdf") == out / "urdf" / "arm.urdf"
    for bad in ("../../x", "/tmp/x", "a/../../../x"):
        with pytest.raises(RobotkitError) as e:
            out_join(out, "meshes", bad, key="sensors.cam.frame")
        assert "would be written outside the output folder" in str(e.value)
    os.symlink(tmp_path, out / "escape")
    with pytest.raises(RobotkitError):
        out_join(out, "escape", "x")
    assert inside(out / "a" / "b", out) and not inside(tmp_path, out)


def test_names_that_become_file_names():
    assert name_problem("ur5_arm-2.0") is None
    assert name_problem("") == "must not be empty"
    assert name_problem("x" * 300) == ("is 300 characters long; names that become file names are at most "
                                       f"{MAX_NAME}")
    assert name_problem("../x").startswith("may contain only ASCII letters")
    assert name_problem("a/b").startswith("may contain only ASCII letters")
    assert file_stem("base_link") == "base_link"
    assert file_stem("arm/link1").startswith("arm_link1-") and file_stem("arm/link1") != file_stem("arm_link1")
    assert len(file_stem("y" * 300)) == MAX_NAME
    assert file_stem("y" * 300) != file_stem("y" * 301)


def test_names_unsafe_on_windows_are_refused():
    from robotkit.paths import name_problem

    assert name_problem("con") == "'con' is a device name on Windows and cannot name a file there"
    assert name_problem("LPT1.txt") == "'LPT1.txt' is a device name on Windows and cannot name a file there"
    assert name_problem("arm.") == "must not end with '.' (Windows drops it from file names)"
    assert name_problem("console") is None and name_problem("com_link") is None
