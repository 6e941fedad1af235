"""Import an existing URDF or xacro description into a recipe (``robotkit import``).

    FILE.xacro ──xacro_expand──▶ URDF text ──urdf_to_recipe──▶ recipe dict ──▶ RECIPE.yaml
    FILE.urdf  ────────────────▶

:func:`import_file` is the entry point.  Inertials are kept as given (explicit) unless
``recompute_inertials``, or unless check would report them (no real body has them, they do not
fit their geometry, their mass is MeshLab's volume at density 1: robotkit.importer.fit), each
change stated;
what the recipe cannot express is carried verbatim in
``urdf_extras`` or reported in ``ImportResult.warnings``.  Nothing is written when the
input has problems (RobotkitError, one line each).
"""

from __future__ import annotations

import filecmp
import os
import shutil
from dataclasses import dataclass, field, replace
from pathlib import Path

from pydantic import ValidationError

from robotkit import urdfxml
from robotkit.errors import Problem, RobotkitError, display_path
from robotkit.importer.checked import with_companions
from robotkit.importer.defaults import factor_defaults
from robotkit.importer.fit import misfits
from robotkit.importer.inertials import POLICIES, report_recomputed
from robotkit.importer.meshes import mark_open_meshes
from robotkit.importer.parsing import shown
from robotkit.importer.package_xml import package_metadata, with_own_package
from robotkit.importer.recipe_writer import dump_recipe, name_mesh_folders, wrap
from robotkit.importer.urdf_to_recipe import Converted, urdf_to_recipe
from robotkit.importer.xacro_expand import check_package_paths, expand
from robotkit.model.load import load_robots
from robotkit.paths import inside, recipe_policy, widened
from robotkit.recipe.schema import Recipe

XACRO_NAMESPACES = ("http://www.ros.org/wiki/xacro", "http://ros.org/wiki/xacro", "http://wiki.ros.org/xacro")


@dataclass
class ImportResult:
    recipe_path: Path
    robot: str
    warnings: list[str] = field(default_factory=list)
    inputs: list[str] = field(default_factory=list)
    """Every file read: the input, xacro includes and YAML files, meshes."""
    copied: list[str] = field(default_factory=list)
    """Mesh files copied next to the recipe (``copy_meshes``)."""
    inertials: dict[str, dict] = field(default_factory=dict)
    """With ``recompute_inertials``: per link, the given and the recomputed inertial."""
    extras: list[str] = field(default_factory=list)
    """A label per element carried verbatim in ``urdf_extras``."""
    repairs: dict[str, str] = field(default_factory=dict)
    """Per link whose inertial the recipe changes from the original: what was wrong and what it does."""
    joint_notes: dict[str, str] = field(default_factory=dict)
    """Per joint the recipe changes from the original (a mimic of a fixed joint, lower == upper)."""
    left_out: list[str] = field(default_factory=list)
    """Elements of the original the recipe leaves out, and why (each in the recipe's header too)."""


def is_xacro(path: Path, text: str) -> bool:
    return path.name.endswith(".xacro") or any(ns in text for ns in XACRO_NAMESPACES)


@dataclass
class Read:
    """What a reader makes of an input file: the URDF it describes, the other files it read."""

    urdf: str
    includes: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)


def _read_xacro(source: Path, raw: str, packages: dict[str, str], args: dict[str, str]) -> Read:
    expanded = expand(source, packages, args)
    return Read(expanded.text, list(expanded.includes), list(expanded.warnings))


def _read_urdf(source: Path, raw: str, packages: dict[str, str], args: dict[str, str]) -> Read:
    warnings = [f"{display_path(source)} is not a xacro file; --arg {', '.join(args)} ignored"] if args else []
    return Read(raw, [], warnings)


READERS = {
    "xacro": (is_xacro, _read_xacro),
    "urdf": (lambda path, text: True, _read_urdf),
}
"""Input formats, tried in order: name -> (accepts(path, text), read(path, text, packages, args)).
A reader turns its format into URDF text, which :mod:`robotkit.importer.urdf_to_recipe` maps
onto the recipe; another format is another entry here."""


def import_file(path: str | os.PathLike, out_recipe: str | os.PathLike, package_paths: dict[str, str] | None = None,
                args: dict[str, str] | None = None, recompute_inertials: bool = False, copy_meshes: bool = False,
                density: float | None = None, inertia_policy: str | None = None) -> ImportResult:
    """Import the URDF or xacro file ``path`` into the recipe ``out_recipe``.

    ``package_paths`` maps ROS package names to folders (``$(find PKG)``, ``package://PKG``);
    ``args`` are xacro arguments.  With ``recompute_inertials`` each link's inertial is
    computed from its geometry (collision geometry when it has some), keeping the given
    mass, or at ``density`` when given; the differences are reported per link.  Otherwise a
    physical inertial is kept as given and one that no real body has gets ``inertia_policy``
    (keep, repair, recompute, estimate; see robotkit.importer.inertials.chosen_inertial), with a
    comment above its link saying what was wrong; by default (None) the repair, and where the
    tensor, given or repaired, does not fit the link's geometry by check's rule, a recompute, and
    where the mass is the geometry's volume at density 1 (MeshLab's; check's implied density),
    mass and tensor from the geometry at the recipe's density (robotkit.importer.fit); ``keep``
    keeps them.  ``copy_meshes`` copies every mesh below the recipe's folder
    (``meshes/PKG/...``) instead of referencing it where it is; the meshes outside the recipe's
    project, which its build may not read, are copied whatever it says, with their package's
    licence files.
    """
    fit = inertia_policy is None  # the default: a repair that does not fit the geometry is recomputed
    inertia_policy = inertia_policy or "repair"
    if inertia_policy not in POLICIES:
        raise RobotkitError(Problem(f"inertia policy '{inertia_policy}' is not one of {', '.join(POLICIES)}"))
    if density is not None and not density > 0:
        raise RobotkitError(Problem(f"density must be > 0 (got {density!r})"))
    source = Path(path).absolute()
    out = Path(out_recipe).absolute()
    packages = with_own_package(source, check_package_paths(package_paths or {}))
    raw = _read_input(source)
    read = next(reader for accepts, reader in READERS.values() if accepts(source, raw))
    got = read(source, raw, packages, args or {})
    lines = _element_lines(got.urdf) if got.urdf is raw else {}
    policy = recipe_policy(out)
    copy = True if copy_meshes else (lambda p: not policy.allows(p))  # the build reads only its project
    overrides: dict[str, tuple[str, str]] = {}
    while True:  # twice when a repaired tensor does not fit its geometry: then recomputed
        warnings, inputs = list(got.warnings), [str(source), *got.includes]
        conv = urdf_to_recipe(got.urdf, source, out, packages, copy_meshes=copy, recompute_inertials=recompute_inertials,
                              density=density, inertia_policy=inertia_policy, lines=bool(lines), overrides=overrides)
        warnings.extend(conv.warnings)
        inputs.extend(sorted({m.source for m in conv.meshes.values()}))
        recipe = _finished_recipe(conv, source, warnings, recompute_inertials)
        header = _header(source, out, args, recompute_inertials, density, inertia_policy, fit) + [
            line for note in conv.left_out for line in wrap(note)]
        text_out = dump_recipe(recipe, header, {"links": conv.repairs, "joints": conv.joint_notes})
        copied = _copy_meshes(conv.copies, source, out)
        tmp, robot = _write_checked(text_out, out, source, lines,
                                    with_companions(m.recipe_path for m in conv.meshes.values()), warnings)
        more, kept = misfits(robot, conv.explicit, fit)
        if not set(more) - set(overrides):
            break
        tmp.unlink()
        overrides.update(more)
    os.replace(tmp, out)
    warnings.extend(f"{_where(source, lines, name)}link '{name}': {why}" for name, why in kept.items())
    result = ImportResult(out, recipe["robot"], warnings, inputs, copied, extras=list(conv.extras),
                          repairs=dict(conv.repairs), joint_notes=dict(conv.joint_notes),
                          left_out=list(conv.left_out))
    if recompute_inertials:
        report_recomputed(out, conv, result)
    return result


def _where(source: Path, lines: dict, link: str) -> str:
    line = lines.get(("links", link))
    return f"{shown(source)}{f':{line}' if line else ''}: "


def _read_input(source: Path) -> str:
    try:
        return source.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise RobotkitError(Problem("file not found", file=str(source))) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise RobotkitError(Problem(f"cannot read file: {exc}", file=str(source))) from None


def _finished_recipe(conv: Converted, source: Path, warnings: list[str], recompute_inertials: bool) -> dict:
    """The converted recipe with the source package's metadata, ``open_mesh`` where inertials
    are computed from open meshes and mesh folder values; schema-checked, then with the values
    most links and joints share moved to ``defaults:``."""
    recipe = conv.recipe
    metadata, ros, md_warnings = package_metadata(source)
    warnings.extend(md_warnings)
    if metadata:
        recipe["metadata"] = metadata
    if ros == "ros1":  # ros2 is the default
        recipe["ros"] = ros
    mark_open_meshes(conv, recipe, warnings, recompute_inertials)
    name_mesh_folders(recipe)
    _validate(recipe, source)
    factor_defaults(recipe)  # after the check: the schema reads links and joints with their defaults merged
    return recipe


def _copy_meshes(copies: dict[str, str], source: Path, out: Path) -> list[str]:
    """Copy the meshes (destination -> source) below the recipe's folder; nothing is copied when
    one would land outside it (a package:// path climbing out with ../)."""
    outside = [Problem(f"mesh '{display_path(src)}' would be copied to {display_path(dest)}, outside the "
                       f"recipe's folder {display_path(out.parent)}", file=str(source))
               for dest, src in sorted(copies.items()) if not inside(dest, out.parent)]
    if outside:
        raise RobotkitError(outside)
    copied = []
    for dest, src in sorted(copies.items()):
        if not (os.path.isfile(dest) and filecmp.cmp(src, dest, shallow=False)):
            os.makedirs(os.path.dirname(dest), exist_ok=True)
            shutil.copyfile(src, dest)
        copied.append(dest)
    return copied


def _header(source: Path, out: Path, args: dict[str, str] | None, recompute_inertials: bool,
            density: float | None, inertia_policy: str, fit: bool = False) -> list[str]:
    """The recipe's header comment: where it came from and how its inertials were decided."""
    header = [f"Imported by robotkit from {Path(os.path.relpath(source, out.parent)).as_posix()}"]
    if args:
        header.append("xacro arguments: " + " ".join(f"{k}:={v}" for k, v in args.items()))
    if recompute_inertials:
        header.append("inertials recomputed from the geometry "
                      + ("at the recipe's density" if density is not None else "keeping each link's given mass"))
    else:
        header.append("inertials as given in the original (explicit); those no real body has: "
                      f"{inertia_policy} (--inertia-policy)")
        if fit:
            header.append("a tensor, given or repaired, that does not fit the link's geometry (check's inertia-box "
                          "rule): recompute, or estimate without a closed geometry; a mass that is its geometry's "
                          "volume at density 1 (MeshLab's): computed from it at the recipe's density")
    return header


def _write_checked(text: str, out: Path, source: Path, lines: dict, read: list[str], warnings: list[str]):
    """Write the recipe next to ``out`` and load and resolve it as the build will (``read``:
    the mesh files a build of it reads, whose folders outside its project it may read):
    (the file written, which the caller moves onto ``out``, the robot)."""
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    outside = sorted({os.path.dirname(p) for p in read if not recipe_policy(out).allows(p)})
    if outside:
        common = os.path.commonpath(outside)
        warnings.append(f"the recipe reads files outside its project {display_path(recipe_policy(out).roots[0])}: "
                        f"build it with --root {display_path(common)}")
    try:
        with widened(outside):  # the package paths the user declared
            return tmp, _check_resolves(tmp, source, lines)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _validate(recipe: dict, source: Path) -> None:
    """Schema check before anything is written (a failure here is an input the recipe
    cannot express, reported by key)."""
    try:
        Recipe.model_validate(recipe)
    except ValidationError as exc:
        problems = []
        for err in exc.errors(include_url=False):
            key = ".".join(str(p) for p in err["loc"])
            problems.append(Problem(f"the imported recipe would be invalid: {key}: {err['msg']}", file=str(source)))
        raise RobotkitError(problems) from None


def _check_resolves(recipe_file: Path, source: Path, lines: dict) -> None:
    """Load and resolve the written recipe as the build will (given inertias that no real body
    has were repaired by the import, each stated in the recipe).  Problems name the imported
    file and, for a URDF, the line of the link or joint (the recipe is not written when there
    are any)."""
    try:
        (_, robot), = load_robots([recipe_file])
        return robot
    except RobotkitError as exc:
        rest = []
        for p in exc.problems:
            if p.file == str(recipe_file):
                parts = (p.key or "").split(".")
                p = replace(p, file=str(source), line=lines.get(tuple(parts[:2])))
            rest.append(p)
        raise RobotkitError(rest) from None


def _element_lines(urdf_text: str) -> dict[tuple[str, str], int]:
    """(``links`` or ``joints``, name) -> line of that element in a URDF's text."""
    try:
        root = urdfxml.parse_text(urdf_text).getroot()
    except urdfxml.MalformedXML:
        return {}
    return {(tag + "s", e.get("name").lstrip("/")): e.sourceline for tag in ("link", "joint")
            for e in root.iter(tag) if e.get("name")}  # '/base_link' is imported as base_link


def import_mjcf(path, out_recipe, build=None):
    """Import an MJCF file (robotkit.importer.mjcf.import_mjcf: MuJoCo is imported on first use)."""
    from robotkit.importer.mjcf import import_mjcf as _import

    return _import(path, out_recipe, build)


def import_sdf(path, out_recipe, build=None):
    """Import an SDF file or a Gazebo model folder (robotkit.importer.sdf.import_sdf)."""
    from robotkit.importer.sdf import import_sdf as _import

    return _import(path, out_recipe, build=build)
