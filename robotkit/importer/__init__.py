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


def is_xacro(path: Path, text: str) -> bool:
    return path.name.endswith(".xacro") or any(ns in text for ns in XACRO_NAMESPACES)


def import_file(path: str | os.PathLike, out_recipe: str | os.PathLike, package_paths: dict[str, str] | None = None,
                args: dict[str, str] | None = None, recompute_inertials: bool = False, copy_meshes: bool = False,
                density: float | None = None) -> ImportResult:
    """Import the URDF or xacro file ``path`` into the recipe ``out_recipe``.

    ``package_paths`` maps ROS package names to folders (``$(find PKG)``, ``package://PKG``);
    ``args`` are xacro arguments.  With ``recompute_inertials`` each link's inertial is
    computed from its geometry (collision geometry when it has some), keeping the given
    mass, or at ``density`` when given; the differences are reported per link.
    ``copy_meshes`` copies the meshes below the recipe's folder (``meshes/``) instead of
    referencing them where they are.
    """
    from robotkit.importer.package_xml import package_metadata
    from robotkit.importer.urdf_to_recipe import dump_recipe, urdf_to_recipe
    from robotkit.importer.xacro_expand import check_package_paths, expand

    if density is not None and not density > 0:
        raise RobotkitError(Problem(f"density must be > 0 (got {density!r})"))
    source = Path(path).absolute()
    out = Path(out_recipe).absolute()
    packages = check_package_paths(package_paths or {})
    try:
        raw = source.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise RobotkitError(Problem("file not found", file=str(source))) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise RobotkitError(Problem(f"cannot read file: {exc}", file=str(source))) from None
    warnings: list[str] = []
    inputs = [str(source)]
    if is_xacro(source, raw):
        expanded = expand(source, packages, args or {})
        text = expanded.text
        warnings.extend(expanded.warnings)
        inputs.extend(expanded.includes)
    else:
        text = raw
        if args:
            warnings.append(f"{display_path(source)} is not a xacro file; --arg {', '.join(args)} ignored")

    conv = urdf_to_recipe(text, source, out, packages, copy_meshes=copy_meshes,
                          recompute_inertials=recompute_inertials, density=density)
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
    _validate(recipe, source)

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
        header.append("inertials as given in the original (explicit)")
    text_out = dump_recipe(recipe, header)
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
            _check_resolves(tmp, source, _element_lines(text) if text is raw else {}, conv.invalid_inertias)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    os.replace(tmp, out)

    result = ImportResult(out, recipe["robot"], warnings, inputs, copied, extras=list(conv.extras))
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


def _check_resolves(recipe_file: Path, source: Path, lines: dict, invalid_inertias: set[str]) -> None:
    """Load and resolve the written recipe as the build will.  Given inertias that the
    build rejects were reported as warnings already: the recipe is still written, so that
    the user can correct them in it.  Problems name the imported file and, for a URDF, the
    line of the link or joint (the recipe is not written when there are any)."""
    from dataclasses import replace

    from robotkit.tasks import load_robots

    try:
        load_robots([recipe_file])
    except RobotkitError as exc:
        keys = {f"links.{name}.inertial.inertia" for name in invalid_inertias}
        rest = []
        for p in exc.problems:
            if p.key in keys:
                continue
            if p.file == str(recipe_file):
                parts = (p.key or "").split(".")
                p = replace(p, file=str(source), line=lines.get(tuple(parts[:2])))
            rest.append(p)
        if rest:
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


# ---------------------------------------------------------------- meshes that are not closed


_CLOSED: dict[tuple, bool] = {}


def mesh_is_closed(source: str, scale) -> bool:
    """Whether robotkit's mesh task accepts the mesh without ``open_mesh: hull``."""
    from robotkit.errors import MeshError
    from robotkit.mesh.io import load_mesh, volume_mesh

    st = os.stat(source)
    key = (source, tuple(scale), st.st_mtime_ns, st.st_size)
    if key not in _CLOSED:
        try:
            volume_mesh(load_mesh(source, scale), "error", os.path.basename(source))
            _CLOSED[key] = True
        except MeshError:
            _CLOSED[key] = False
    return _CLOSED[key]


def _open_meshes(conv, recipe: dict, warnings: list[str], recompute: bool) -> None:
    """A mesh that is not a closed volume needs ``open_mesh: hull`` only where an inertial is
    computed from it (robotkit accepts open meshes that are only drawn and collided)."""
    open_by_link: dict[str, list[tuple[str, str]]] = {}
    for (link, kind, _i), use in conv.meshes.items():
        if not mesh_is_closed(use.source, use.scale):
            names = open_by_link.setdefault(link, [])
            if (kind, os.path.basename(use.source)) not in names:
                names.append((kind, os.path.basename(use.source)))
    top_level = []
    for link, found in open_by_link.items():
        spec = recipe["links"][link].get("inertial")
        if spec == "none" or (isinstance(spec, dict) and "inertia" in spec):
            continue  # no inertial is computed from the link's geometry
        source = spec.get("source", "visual") if isinstance(spec, dict) else "visual"
        read = [name for kind, name in found if kind == source]
        if not read:
            continue
        files = ", ".join(dict.fromkeys(read))
        if isinstance(spec, dict):
            spec["open_mesh"] = "hull"
            warnings.append(f"link '{link}': mesh {files} is not a closed volume; its recomputed inertial "
                            "uses the convex hull (open_mesh: hull)")
        else:
            top_level.append(f"{link} ({files})")
    if top_level:
        recipe["open_mesh"] = "hull"
        warnings.append("meshes that are not closed volumes on links whose inertial is computed from them: "
                        f"{'; '.join(top_level)}; the recipe sets open_mesh: hull")


# ---------------------------------------------------------------- recomputed inertials


def _facts(mesh) -> dict:
    """Unit-density mass properties of one mesh, as robotkit's mesh task records them."""
    import numpy as np

    from robotkit.mesh.inertia import mesh_mass_properties
    from robotkit.mesh.io import load_mesh, volume_mesh

    m = load_mesh(mesh.source, mesh.scale)
    bbox_min, bbox_max = m.bounds
    vol, _, _, _ = volume_mesh(m, mesh.open_mesh, os.path.basename(mesh.source))
    props = mesh_mass_properties(vol.vertices, vol.faces)
    return {"volume": props.volume, "com": [float(v) for v in props.com],
            "inertia": [[float(v) for v in row] for row in np.asarray(props.inertia)],
            "bbox_min": [float(v) for v in bbox_min], "bbox_max": [float(v) for v in bbox_max]}


def _report_recomputed(recipe_file: Path, conv, result: ImportResult) -> None:
    import numpy as np

    from robotkit.model.resolve import finalize_link_inertial
    from robotkit.tasks import load_robots

    (_, robot), = load_robots([recipe_file])
    facts: dict[str, dict] = {}
    for link in robot.links:
        if link.inertial_spec.mode not in ("mass", "density") or link.name not in conv.explicit:
            continue
        for g in link.source_geoms():
            if g.shape.mesh is not None and g.shape.mesh.key not in facts:
                facts[g.shape.mesh.key] = _facts(g.shape.mesh)
        new = finalize_link_inertial(link, facts)
        given = conv.explicit[link.name]
        t = given["inertia"]
        I0 = np.array([[t["ixx"], t["ixy"], t["ixz"]], [t["ixy"], t["iyy"], t["iyz"]], [t["ixz"], t["iyz"], t["izz"]]])
        I1 = new.tensor()
        com_shift = float(np.linalg.norm(np.asarray(new.com) - np.asarray(given["com"])))
        rel = float(np.linalg.norm(I1 - I0) / max(np.linalg.norm(I0), 1e-300))
        result.inertials[link.name] = {
            "given": {"mass": given["mass"], "com": list(given["com"]), "inertia": I0.tolist()},
            "computed": {"mass": new.mass, "com": list(new.com), "inertia": I1.tolist()},
            "com_shift": com_shift, "inertia_rel_diff": rel,
        }
        mass = (f"mass {new.mass:.6g} kg (given {given['mass']:.6g})" if link.inertial_spec.mode == "density"
                else f"mass {new.mass:.6g} kg kept")
        d0 = ", ".join(f"{v:.4g}" for v in np.diag(I0))
        d1 = ", ".join(f"{v:.4g}" for v in np.diag(I1))
        result.warnings.append(
            f"link '{link.name}': recomputed inertial from its {link.inertial_spec.source} geometry: {mass}; "
            f"centre of mass moved {com_shift * 1000:.3g} mm; inertia tensor differs by {rel * 100:.3g}% "
            f"(diagonal given {d0}, now {d1} kg m^2)")
