"""Import an SDF file or a Gazebo model folder into a recipe (``robotkit import model.sdf`` or
``robotkit import MODEL_FOLDER``), read through libsdformat.

    model.sdf ──ign sdf -p (libsdformat)──▶ links, joints, shapes, inertials, frames, sensors,
    plugins, model.config metadata ──▶ RECIPE.yaml (+ a ledger of what it cannot hold)

:func:`import_sdf` is the entry point.  What the recipe cannot hold, and each repair, is on the
ledger (one line per element), printed and in the recipe's header.  With a ``build`` (recipe,
folder -> the rebuilt model.sdf), the recipe is built in a temporary folder and the rebuilt
model.sdf compared with the original through libsdformat (:mod:`robotkit.importer.sdf.verify`).
Nothing is written when the file cannot be read or the recipe would be invalid."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from robotkit.errors import Problem, RobotkitError
from robotkit.importer.checked import Imported, outside_reads, resolves, validate_recipe
from robotkit.importer.defaults import factor_defaults
from robotkit.importer.mjcf.ledger import Ledger
from robotkit.importer.names import joints_apart_from_links, package_name, renamed_robot
from robotkit.importer.recipe_writer import dump_recipe, name_mesh_folders
from robotkit.importer.sdf.contacts import add_contacts
from robotkit.importer.sdf.extras import add_extras
from robotkit.importer.sdf.model import read_model
from robotkit.importer.sdf.names import recipe_names
from robotkit.importer.sdf.shapes import add_shapes
from robotkit.importer.sdf.source import read
from robotkit.importer.sdf.tree import build_tree, take_chain_masses
from robotkit.importer.sdf.verify import Verdict, verify
from robotkit.paths import widened
from robotkit.urdfxml import is_element


def convert(path, out: Path):
    """(recipe dict, ledger, source, model, tree, repaired links, mesh files) of an SDF file or model folder."""
    src = read(path)
    ledger = Ledger()
    if src.refused:
        ledger.add(str(src.path), "the file", "all", f"libsdformat refuses it ({src.refused}): read from its own "
                   "XML, as Gazebo classic loads it")
    _joints_apart_from_links(src, src.model, "", ledger)
    try:
        m = read_model(src.model, str(src.path))
    except ValueError as exc:  # a number that is none, in a file libsdformat refused
        why = f"libsdformat refuses it ({src.refused}), and its XML holds " if src.refused else "it holds "
        raise RobotkitError(Problem(f"{why}a value that is not a number: {exc}", file=str(src.path))) from None
    recipe_names(src, m, ledger)
    tree = build_tree(src, m, ledger)
    materials: dict = {}
    repaired: dict = {}
    files = add_shapes(src, m, tree, out, ledger, materials, repaired)
    take_chain_masses(src, tree, ledger)
    surfaces = add_contacts(src, m, tree, ledger)
    recipe: dict = {"robot": package_name(m.name)}
    meta = _metadata(src.config)
    if meta:
        recipe["metadata"] = meta
    if tree.base == "free":
        recipe["base"] = "free"
    add_extras(src, m, tree, recipe, ledger, surfaces)
    if len(ledger):  # the build copies it into report.json
        recipe.setdefault("metadata", {})["ledger"] = ledger.lines()
    if materials:
        recipe["materials"] = materials
    recipe["links"], recipe["joints"] = tree.links, tree.joints
    return recipe, ledger, src, m, tree, repaired, files


def _joints_apart_from_links(src, model, scope: str, ledger) -> None:
    """Joints named like a link of their model, in the model and in each nested model (turtlebot
    includes create, whose joint 'left_wheel' moves its link 'left_wheel'), renamed, stated."""
    renamed = joints_apart_from_links([c for c in model if is_element(c)])
    for old, new in renamed.items():
        src.renamed[scope + new] = scope + old
        ledger.add(src.where("joint", scope + old), f"joint '{scope + old}'", "all", f"renamed '{scope + new}' (a "
                   "link has its name: libsdformat refuses the pair)")
    for nested in (c for c in model if is_element(c) and c.tag == "model"):
        _joints_apart_from_links(src, nested, f"{scope}{nested.get('name', '')}/", ledger)


def _metadata(config: dict) -> dict:
    out: dict = {}
    if config.get("version"):
        out["version"] = config["version"]
    if config.get("description"):
        out["description"] = config["description"]
    if config.get("authors"):
        out["authors"] = config["authors"]
    return out


def import_sdf(path, out_recipe, build=None) -> Imported:
    """Import the SDF file or model folder ``path`` into ``out_recipe``; ``build(recipe, folder)``
    builds a recipe into a folder and returns the rebuilt model.sdf's path (the verification's)."""
    out = Path(out_recipe).absolute()
    recipe, ledger, src, m, tree, repaired, files = convert(path, out)
    name_mesh_folders(recipe)
    validate_recipe(recipe, src.path)
    _factor_defaults(recipe)
    comments = {"links": {**{n: _chain_comment(tree, n) for n in tree.chain_links}, **tree.link_notes, **repaired}, "joints": tree.notes}
    how = "read through libsdformat" if src.via == "libsdformat" else "read from its XML (libsdformat refuses it)"
    header = [f"Imported by robotkit from {Path(os.path.relpath(src.path, out.parent)).as_posix()} (SDF, {how})"]
    renamed = renamed_robot(m.name, recipe["robot"], "SDF")
    header += renamed + ledger.block()
    read_dirs, root, outside = outside_reads(files, out)
    notes = renamed + outside
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp")
    try:
        with widened(read_dirs):
            tmp.write_text(dump_recipe(recipe, header, comments), encoding="utf-8")
            resolves(tmp, src.path)
            verdict = _verified(m, tree, set(repaired), tmp, build)
        if verdict is not None:
            tmp.write_text(dump_recipe(recipe, header + verdict.lines(), comments), encoding="utf-8")
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    os.replace(tmp, out)
    return Imported(out, recipe["robot"], ledger.lines(), verdict, [str(src.path), *files], notes, root)


def _chain_comment(tree, link: str) -> str:
    head = "a link of a joint the recipe writes as a chain (ball, universal): "
    if link in tree.moved:
        return head + (f"a point mass taken from link '{tree.moved[link]}' at the joint's centre, which every axis "
                       "of the joint leaves fixed (the dynamics unchanged)")
    return head + "a point mass, added (on the ledger)"


def _factor_defaults(recipe: dict) -> None:
    """:func:`factor_defaults` with each link's shapes and inertial set aside: measuring them is
    most of its time (a ragdoll's 18 s of 23), and a shared collision as a link default would be
    merged into a link's own (a box and a cylinder in one)."""
    shapes = ("visual", "collision", "inertial")
    aside = {name: {k: link[k] for k in shapes if k in link} for name, link in recipe["links"].items()}
    recipe["links"] = {name: {k: v for k, v in link.items() if k not in shapes} for name, link in recipe["links"].items()}
    factor_defaults(recipe)
    recipe["links"] = {name: {**link, **aside[name]} for name, link in recipe["links"].items()}


def _verified(m, tree, repaired: set, recipe: Path, build) -> Verdict | None:
    if build is None:
        return None
    with tempfile.TemporaryDirectory(prefix="robotkit-import-") as folder:
        return verify(m, tree, repaired, build(recipe, folder))
