"""Import an existing URDF or xacro description into a recipe (``robotkit import``).

    FILE.xacro ──xacro_expand──▶ URDF text ──urdf_to_recipe──▶ recipe dict ──▶ RECIPE.yaml
    FILE.urdf  ────────────────▶

:func:`import_file` is the entry point.  Inertials are kept as given (explicit) unless
``recompute_inertials``; what the recipe cannot express is carried verbatim in
``urdf_extras`` or reported in ``ImportResult.warnings``.  Nothing is written when the
input has problems (RobotkitError, one line each).
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path

from robotkit.errors import Problem, RobotkitError, display_path

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
    from robotkit.importer.xacro_expand import expand

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
                density: float | None = None, inertia_policy: str = "repair") -> ImportResult:
    """Import the URDF or xacro file ``path`` into the recipe ``out_recipe``.

    ``package_paths`` maps ROS package names to folders (``$(find PKG)``, ``package://PKG``);
    ``args`` are xacro arguments.  With ``recompute_inertials`` each link's inertial is
    computed from its geometry (collision geometry when it has some), keeping the given
    mass, or at ``density`` when given; the differences are reported per link.  Otherwise a
    physical inertial is kept as given and one that no real body has gets ``inertia_policy``
    (keep, repair, recompute, estimate; see robotkit.importer.inertials.chosen_inertial), with a
    comment above its link saying what was wrong.
    ``copy_meshes`` copies the meshes below the recipe's folder (``meshes/``) instead of
    referencing them where they are.
    """
    from robotkit.importer.defaults import factor_defaults
    from robotkit.importer.meshes import _open_meshes
    from robotkit.importer.package_xml import package_metadata, with_own_package
    from robotkit.importer.recipe_writer import name_mesh_folders
    from robotkit.importer.urdf_to_recipe import dump_recipe, urdf_to_recipe
    from robotkit.importer.xacro_expand import check_package_paths

    from robotkit.importer.inertials import POLICIES

    if inertia_policy not in POLICIES:
        raise RobotkitError(Problem(f"inertia policy '{inertia_policy}' is not one of {', '.join(POLICIES)}"))
    if density is not None and not density > 0:
        raise RobotkitError(Problem(f"density must be > 0 (got {density!r})"))
    source = Path(path).absolute()
    out = Path(out_recipe).absolute()
    packages = with_own_package(source, check_package_paths(package_paths or {}))
    try:
        raw = source.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise RobotkitError(Problem("file not found", file=str(source))) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise RobotkitError(Problem(f"cannot read file: {exc}", file=str(source))) from None
    warnings: list[str] = []
    inputs = [str(source)]
    read = next(reader for accepts, reader in READERS.values() if accepts(source, raw))
    got = read(source, raw, packages, args or {})
    text = got.urdf
    warnings.extend(got.warnings)
    inputs.extend(got.includes)

    conv = urdf_to_recipe(text, source, out, packages, copy_meshes=copy_meshes,
                          recompute_inertials=recompute_inertials, density=density, inertia_policy=inertia_policy)
    warnings.extend(conv.warnings)
    inputs.extend(sorted({m.source for m in conv.meshes.values()}))
    recipe = conv.recipe
    metadata, ros, md_warnings = package_metadata(source)
    warnings.extend(md_warnings)
    if metadata:
        recipe["metadata"] = metadata
    if ros == "ros1":  # ros2 is the default
        recipe["ros"] = ros
    _open_meshes(conv, recipe, warnings, recompute_inertials)
    name_mesh_folders(recipe)
    _validate(recipe, source)
    factor_defaults(recipe)  # after the check: the schema reads links and joints with their defaults merged

    from robotkit.paths import inside

    outside = [Problem(f"mesh '{display_path(src)}' would be copied to {display_path(dest)}, outside the "
                       f"recipe's folder {display_path(out.parent)}", file=str(source))
               for dest, src in sorted(conv.copies.items()) if not inside(dest, out.parent)]
    if outside:  # a package:// path climbing out with ../: nothing is written
        raise RobotkitError(outside)
    copied = []
    for dest, src in sorted(conv.copies.items()):
        if not (os.path.isfile(dest) and _same_bytes(src, dest)):
            os.makedirs(os.path.dirname(dest), exist_ok=True)
            shutil.copyfile(src, dest)
        copied.append(dest)

    header = [f"Imported by robotkit from {Path(os.path.relpath(source, out.parent)).as_posix()}"]
    if args:
        header.append("xacro arguments: " + " ".join(f"{k}:={v}" for k, v in args.items()))
    if recompute_inertials:
        header.append("inertials recomputed from the geometry "
                      + ("at the recipe's density" if density is not None else "keeping each link's given mass"))
    else:
        header.append("inertials as given in the original (explicit); those no real body has: "
                      f"{inertia_policy} (--inertia-policy)")
    from robotkit.importer.recipe_writer import _wrap

    header += [line for note in conv.left_out for line in _wrap(note)]
    text_out = dump_recipe(recipe, header, {"links": conv.repairs, "joints": conv.joint_notes})
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp")
    tmp.write_text(text_out, encoding="utf-8")
    from robotkit.paths import recipe_policy, widened

    read = [] if copy_meshes else [m.source for m in conv.meshes.values()]  # what a build of the recipe reads
    outside = sorted({os.path.dirname(p) for p in read if not recipe_policy(out).allows(p)})
    if outside:
        common = os.path.commonpath(outside)
        warnings.append(f"the recipe reads files outside its project {display_path(recipe_policy(out).roots[0])}: "
                        f"build it with --root {display_path(common)}")
    try:
        with widened(outside):  # the package paths the user declared
            _check_resolves(tmp, source, _element_lines(text) if text is raw else {})
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    os.replace(tmp, out)

    from robotkit.importer.inertials import _report_recomputed

    result = ImportResult(out, recipe["robot"], warnings, inputs, copied, extras=list(conv.extras),
                          repairs=dict(conv.repairs), joint_notes=dict(conv.joint_notes),
                          left_out=list(conv.left_out))
    if recompute_inertials:
        _report_recomputed(out, conv, result)
    return result


def _same_bytes(a: str, b: str) -> bool:
    import filecmp

    return filecmp.cmp(a, b, shallow=False)


def _validate(recipe: dict, source: Path) -> None:
    """Schema check before anything is written (a failure here is an input the recipe
    cannot express, reported by key)."""
    from pydantic import ValidationError

    from robotkit.recipe.schema import Recipe

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
    from dataclasses import replace

    from robotkit.model.load import load_robots

    try:
        load_robots([recipe_file])
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
    from lxml import etree

    try:
        root = etree.fromstring(urdf_text.encode("utf-8"), etree.XMLParser(resolve_entities=False, no_network=True,
                                                                           huge_tree=False))
    except etree.XMLSyntaxError:
        return {}
    return {(tag + "s", e.get("name")): e.sourceline for tag in ("link", "joint") for e in root.iter(tag)
            if e.get("name")}
