"""``robotkit import FILE [--package-path PKG=DIR]... [--arg NAME:=VALUE]... -o RECIPE.yaml``:
a URDF or xacro file into a recipe (:func:`robotkit.importer.import_file`)."""

from __future__ import annotations

import os
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
    print(f"wrote {os.path.relpath(result.recipe_path)} (robot {result.robot})")
    return 0
