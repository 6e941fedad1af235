"""The textures a copied visual mesh names travel with it, also from outside its own folder (a
Gazebo model's ``meshes/x.dae`` naming ``../materials/textures/x.png``), within the read rules."""

from __future__ import annotations

import shutil
from pathlib import Path

from robotkit.pipeline.runner import build

PNG = b"\x89PNG\r\n\x1a\n" + b"robotkit test texture"


def _gazebo_model(folder: Path, assets: Path) -> Path:
    """A Gazebo model's layout: meshes/body.dae whose image is ../materials/textures/skin.png."""
    dae = (assets / "ur_description" / "meshes" / "ur5" / "visual" / "wrist3.dae").read_text(encoding="utf-8")
    dae = dae.replace("<library_images/>", "<library_images><image id=\"skin\">"
                      "<init_from>../materials/textures/skin.png</init_from></image></library_images>", 1)
    (folder / "meshes").mkdir(parents=True)
    (folder / "materials" / "textures").mkdir(parents=True)
    (folder / "meshes" / "body.dae").write_text(dae, encoding="utf-8")
    (folder / "materials" / "textures" / "skin.png").write_bytes(PNG)
    return folder


def test_texture_above_the_mesh_folder_lands_where_the_copy_names_it(tmp_path, assets):
    model = _gazebo_model(tmp_path / "model", assets)
    (model / "robot.yaml").write_text("robot: textured\nlinks:\n  body: {visual: {mesh: meshes/body.dae}}\n")
    build([model / "robot.yaml"], tmp_path / "out")
    robot = tmp_path / "out" / "textured"
    copy = robot / "meshes" / "visual" / "body.dae"
    assert copy.read_bytes() == (model / "meshes" / "body.dae").read_bytes()
    # the path written in the copied DAE resolves, as RViz and Gazebo resolve it
    assert (copy.parent / "../materials/textures/skin.png").read_bytes() == PNG
    assert sorted(p.relative_to(robot).as_posix() for p in (robot / "meshes").rglob("*.png")) == [
        "meshes/materials/textures/skin.png"]


def test_texture_outside_the_project_is_not_read(tmp_path, assets, monkeypatch):
    model = _gazebo_model(tmp_path / "model", assets)
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)
    recipe = model / "meshes" / "robot.yaml"  # its project is meshes/: the texture is outside it
    recipe.write_text("robot: textured\nlinks:\n  body: {visual: {mesh: body.dae}}\n")
    build([recipe], tmp_path / "out")
    robot = tmp_path / "out" / "textured"
    assert (robot / "meshes" / "visual" / "body.dae").is_file()
    assert not list((robot / "meshes").rglob("*.png"))


def test_import_names_the_root_that_holds_the_textures(tmp_path, assets, monkeypatch):
    from robotkit.importer.checked import outside_reads

    model = _gazebo_model(tmp_path / "model", assets)
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)
    (tmp_path / "proj").mkdir()
    read, root, notes = outside_reads([str(model / "meshes" / "body.dae")], tmp_path / "proj" / "robot.yaml")
    assert read == [str(model / "materials" / "textures"), str(model / "meshes")]
    assert root == str(model)
    assert notes == [f"the recipe reads files outside its project {tmp_path / 'proj'}: build it with --root {model}"]
    shutil.rmtree(model / "materials")
    assert outside_reads([str(model / "meshes" / "body.dae")], tmp_path / "proj" / "robot.yaml")[1] == str(
        model / "meshes")
