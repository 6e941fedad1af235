"""``robotkit import FILE [--package-path PKG=DIR]... [--arg NAME:=VALUE]... -o RECIPE.yaml``:
a URDF or xacro file into a recipe (:func:`robotkit.importer.import_file`), or an MJCF file
(:func:`robotkit.importer.import_mjcf`) or an SDF file or Gazebo model folder
(:func:`robotkit.importer.import_sdf`), each verified by building the recipe in a temporary folder."""

from __future__ import annotations

import os
import shlex
import sys
from pathlib import Path

from robotkit.commands.inputs import SUFFIXES
from robotkit.importer import import_file

NOTES = ("metadata from ",)
"""What the import says that is information, not a warning (the importer lists it among its warnings)."""


def run(args) -> int:
    kind = "sdf" if Path(args.file).is_dir() else SUFFIXES.get(Path(args.file).suffix.lower())
    if kind in ("mjcf", "sdf"):
        return run_mjcf(args, kind)
    if args.density is not None and not args.recompute_inertials:
        print("robotkit: error: --density needs --recompute-inertials", file=sys.stderr)
        return 2
    packages = dict(args.package_path)
    result = import_file(args.file, args.output, packages, dict(args.arg),
                         recompute_inertials=args.recompute_inertials, copy_meshes=args.copy_meshes,
                         density=args.density, inertia_policy=args.inertia_policy)
    for w in result.warnings:  # where the metadata came from is information, not a warning
        print(f"{'note' if w.startswith(NOTES) else 'warning'}: {w}", file=sys.stderr)
    recipe = os.path.relpath(result.recipe_path)
    if result.copied:
        meshes = os.path.join(os.path.dirname(recipe), "meshes", "")
        print(f"copied {len(result.copied)} file{'s' if len(result.copied) > 1 else ''} to {meshes} "
              "(meshes outside the project, which its build does not read, with their packages' licences)"
              if not args.copy_meshes else f"copied {len(result.copied)} files to {meshes}")
    print(f"wrote {recipe} (robot {result.robot}); build it with:")
    print(f"robotkit build {shlex.quote(recipe)}")
    return 0


VERIFIED_OUTPUTS = "outputs: [mjcf, urdf]  # what the verification compares\n"
"""The formats the verification's build writes (the recipe's ``outputs:``): the MJCF it compares
in MuJoCo and the URDF it loads in Pinocchio; nothing else (the SDF, the ROS package...)."""


def build_mjcf(recipe: Path, folder: str) -> Path:
    """Build ``recipe`` into ``folder`` (no report, only :data:`VERIFIED_OUTPUTS`, from a copy
    beside it, so that its mesh paths read the same; no self-collision matrix: the verification
    compares no contacts, its rollouts run without them); the rebuilt MJCF's path."""
    from robotkit.emit.layout import robot_layout
    from robotkit.pipeline.runner import build

    recipe = Path(recipe)
    copy = recipe.with_name(f".{recipe.name}.verify.yaml")
    copy.write_text(recipe.read_text(encoding="utf-8").rstrip("\n") + "\n" + VERIFIED_OUTPUTS, encoding="utf-8")
    try:
        result = build([copy], folder, report=False, matrix=False)
    finally:
        copy.unlink(missing_ok=True)
    return robot_layout(Path(folder) / result.robots[0]).mjcf


def build_sdf(recipe: Path, folder: str) -> Path:
    """Build ``recipe`` into ``folder`` (no report); the rebuilt model.sdf's path."""
    from robotkit.emit.layout import robot_layout
    from robotkit.pipeline.runner import build

    result = build([recipe], folder, report=False)
    return robot_layout(Path(folder) / result.robots[0]).sdf


def run_mjcf(args, kind: str = "mjcf") -> int:
    """An MJCF or SDF import: the ledger and the verification printed; 1 when the rebuild disagrees."""
    from robotkit.importer import import_mjcf, import_sdf

    if kind == "sdf":
        result = import_sdf(args.file, args.output, build=build_sdf)
    else:
        result = import_mjcf(args.file, args.output, build=build_mjcf)
    for line in result.notes:
        print(f"note: {line}", file=sys.stderr)
    for line in result.ledger:
        print(f"ledger: {line}", file=sys.stderr)
    for line in result.verdict.lines():
        print(line)
    recipe = os.path.relpath(result.recipe_path)
    root = f"--root {shlex.quote(result.root)} " if result.root else ""
    print(f"wrote {recipe} (robot {result.robot}); build it with:")
    print(f"robotkit build {root}{shlex.quote(recipe)}")
    return 0 if result.verdict.ok else 1
