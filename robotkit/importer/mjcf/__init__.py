"""Import an MJCF file into a recipe (``robotkit import model.xml``), read through MuJoCo.

    model.xml ──MuJoCo (MjSpec, compiled MjModel)──▶ links, joints, shapes, inertials,
    actuators, poses, excludes, mimics ──▶ RECIPE.yaml (+ a ledger of what it cannot hold)

:func:`import_mjcf` is the entry point.  What the recipe cannot hold is on the ledger (one line
per element: where, what, which formats, what happened), printed and in the recipe's header.
With a ``build`` (recipe, folder -> the rebuilt MJCF), the recipe is built in a temporary
folder and the rebuilt MJCF compared with the original in MuJoCo
(:mod:`robotkit.importer.mjcf.verify`); the result is in the header too.  Nothing is written
when MuJoCo refuses the file or the recipe would be invalid."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

from robotkit.importer.checked import Imported, outside_reads, resolves, validate_recipe
from robotkit.importer.defaults import factor_defaults
from robotkit.importer.mjcf.actuators import add_actuators
from robotkit.importer.mjcf.chainmass import CHAIN_POINT_MASS
from robotkit.importer.mjcf.contacts import add_contacts
from robotkit.importer.mjcf.extras import add_equalities, add_excludes, add_poses, ledger_rest
from robotkit.importer.mjcf.geoms import add_geoms
from robotkit.importer.mjcf.inertials import add_inertials
from robotkit.importer.mjcf.ledger import Ledger
from robotkit.importer.mjcf.source import read
from robotkit.importer.mjcf.sensors import add_imus
from robotkit.importer.mjcf.sites import add_sites
from robotkit.importer.mjcf.tree import build_tree
from robotkit.importer.mjcf.verbatim import add_verbatim
from robotkit.importer.mjcf.verify import Verdict, verify
from robotkit.importer.names import package_name, renamed_robot
from robotkit.importer.recipe_writer import dump_recipe, name_mesh_folders
from robotkit.paths import widened


def convert(path: str | os.PathLike, out: Path) -> tuple[dict, Ledger, object, object]:
    """(recipe dict, ledger, the source, the link tree) of an MJCF file."""
    src = read(path)
    ledger = Ledger()
    tree = build_tree(src, ledger)
    materials: dict = {}
    add_geoms(src, tree, out, ledger, materials)
    add_inertials(src, tree, ledger)
    add_contacts(src, tree, ledger)
    recipe: dict = {"robot": package_name(_model_name(src))}
    if tree.base == "free":
        recipe["base"] = "free"
    add_actuators(src, tree, recipe, ledger)
    add_equalities(src, tree, recipe, ledger)
    add_excludes(src, tree, recipe, ledger)
    add_imus(src, tree, recipe, ledger)
    add_sites(src, tree, ledger)
    add_verbatim(src, tree, recipe, ledger)
    add_poses(src, tree, recipe, ledger)
    ledger_rest(src, tree, ledger)
    if len(ledger):  # the build copies it into report.json
        recipe["metadata"] = {"ledger": ledger.lines()}
    if materials:
        recipe["materials"] = materials
    recipe["links"], recipe["joints"] = tree.links, tree.joints
    return recipe, ledger, src, tree


def _model_name(src) -> str:
    return src.spec.modelname or src.path.stem


def import_mjcf(path: str | os.PathLike, out_recipe: str | os.PathLike, build=None) -> Imported:
    """Import the MJCF file ``path`` into ``out_recipe``; ``build(recipe, folder)`` builds a
    recipe into a folder and returns the rebuilt MJCF's path (the verification's)."""
    out = Path(out_recipe).absolute()
    recipe, ledger, src, tree = convert(path, out)
    name_mesh_folders(recipe)
    validate_recipe(recipe, src.path)
    _factor_defaults(recipe)
    comments = {"links": {n: _chain_comment(src, tree, n) for n in tree.chain_links}
                | {n: "an MJCF site: a frame (no mass, no shape)" for n in tree.sites.values()}, "joints": tree.notes}
    header = [f"Imported by robotkit from {Path(os.path.relpath(src.path, out.parent)).as_posix()} (MJCF, "
              "read through MuJoCo: inertials, shapes and poses as MuJoCo compiled them)"]
    renamed = renamed_robot(_model_name(src), recipe["robot"], "MJCF")
    header += renamed + ledger.block()
    files = [str(src.mesh_file(d)) for d in range(src.model.nmesh) if src.mesh_file(d) is not None]
    read, root, outside = outside_reads(files, out)
    notes = renamed + outside
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp")
    try:
        body = dump_recipe(recipe, None, comments)  # once: the verdict joins the header after the build
        with widened(read):  # the original's meshes, where they are
            tmp.write_text(_comments(header) + body, encoding="utf-8")
            resolves(tmp, src.path)
            verdict = _verified(src, tree, tmp, build)
        if verdict is not None:
            tmp.write_text(_comments(header + verdict.lines()) + body, encoding="utf-8")
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    os.replace(tmp, out)
    return Imported(out, recipe["robot"], ledger.lines(), verdict, [str(src.path), *map(str, src.includes()), *files],
                    notes, root)


def _chain_comment(src, tree, link: str) -> str:
    """The comment above a link of a body's joint chain (robotkit.importer.mjcf.chainmass)."""
    head = "a link of a body's joint chain (MuJoCo moves a body through its joints in order): "
    if link in tree.moved:
        return head + (f"a point mass of {CHAIN_POINT_MASS:g} kg taken from body '{tree.link_of[tree.moved[link]]}', "
                       "where the joints after it leave it fixed in the body (the dynamics unchanged)")
    return head + "a point mass of a millionth of the lightest body, added (on the ledger)"


def _comments(lines: list[str]) -> str:
    """The header as :func:`dump_recipe` writes it."""
    return "".join(f"# {line}".rstrip() + "\n" for line in lines)


def _verified(src, tree, recipe: Path, build) -> Verdict | None:
    if build is None:
        return None
    with tempfile.TemporaryDirectory(prefix="robotkit-import-") as folder:
        return verify(src, tree, build(recipe, folder))


def _factor_defaults(recipe: dict) -> None:
    """:func:`factor_defaults` with each link's shapes and inertial set aside (a short token for
    each distinct collision value, which is a candidate): they weigh the same before and after,
    but measuring them is most of its time (a Menagerie robot's hundreds of shapes)."""
    kept: dict[str, object] = {}
    tokens: dict[str, str] = {}

    def token(value):
        if isinstance(value, str):
            return value
        key = json.dumps(value, sort_keys=True)
        tokens.setdefault(key, f"shapes{len(tokens)}")
        kept[tokens[key]] = value
        return tokens[key]

    aside = {name: {k: link[k] for k in ("visual", "inertial") if k in link} for name, link in recipe["links"].items()}
    recipe["links"] = {name: {k: (0 if k in ("visual", "inertial") else token(v) if k == "collision" else v)
                              for k, v in link.items()} for name, link in recipe["links"].items()}
    factor_defaults(recipe)
    back = lambda k, v: kept.get(v, v) if k == "collision" and isinstance(v, str) else v  # noqa: E731
    recipe["links"] = {name: {k: (aside[name][k] if k in ("visual", "inertial") else back(k, v))
                              for k, v in link.items()} for name, link in recipe["links"].items()}
    link_defaults = recipe.get("defaults", {}).get("link", {})
    if "collision" in link_defaults:
        link_defaults["collision"] = back("collision", link_defaults["collision"])
