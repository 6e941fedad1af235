"""``robotkit import FILE [--package-path PKG=DIR]... [--arg NAME:=VALUE]... -o RECIPE.yaml``:
a URDF or xacro file into a recipe (:func:`robotkit.importer.import_file`)."""

from __future__ import annotations

import os
import shlex
import sys

from robotkit.importer import import_file

NOTES = ("metadata from ",)
"""What the import says that is information, not a warning (the importer lists it among its warnings)."""


def run(args) -> int:
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
