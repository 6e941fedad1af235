"""``robotkit import FILE [--package-path PKG=DIR]... [--arg NAME:=VALUE]... -o RECIPE.yaml``

Wiring (robotkit/cli.py): ``add_parser(sub)`` in ``_parser()`` and ``"import": run`` in the
command table of ``main()``, inside its ``RobotkitError`` handler.
"""

from __future__ import annotations

import argparse
import os
import sys


def _package_path(text: str) -> tuple[str, str]:
    name, sep, folder = text.partition("=")
    if not sep or not name or not folder:
        raise argparse.ArgumentTypeError(f"'{text}' is not PKG=DIR")
    return name, folder


def _xacro_arg(text: str) -> tuple[str, str]:
    name, sep, value = text.partition(":=")
    if not sep or not name:
        raise argparse.ArgumentTypeError(f"'{text}' is not NAME:=VALUE")
    return name, value


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "import", help="turn an existing URDF or xacro file into a recipe",
        description="Expand FILE (.urdf, or .xacro with $(find PKG) and package://PKG resolved through "
                    "--package-path) and write a recipe that builds into an equivalent URDF. Physical "
                    "inertials are kept as given, the others get --inertia-policy (each stated in a comment "
                    "above its link) unless --recompute-inertials; <gazebo>, <transmission> and other "
                    "elements the recipe cannot express are carried verbatim in urdf_extras.")
    p.add_argument("file", metavar="FILE", help="URDF or xacro file")
    p.add_argument("-o", "--output", required=True, metavar="RECIPE.yaml", help="recipe file to write")
    p.add_argument("--package-path", action="append", type=_package_path, default=[], metavar="PKG=DIR",
                   help="folder of ROS package PKG (repeatable)")
    p.add_argument("--arg", action="append", type=_xacro_arg, default=[], metavar="NAME:=VALUE",
                   help="xacro argument (repeatable)")
    p.add_argument("--inertia-policy", choices=("keep", "repair", "recompute", "estimate"), default="repair",
                   help="for each link whose given inertia no real body has: keep it (the import stops on it, "
                        "as the build would), repair it with the smallest change (default), recompute it from "
                        "the link's geometry or estimate it from its bounding primitive, keeping the mass "
                        "(a link without geometry is repaired)")
    p.add_argument("--recompute-inertials", action="store_true",
                   help="compute every link's inertial from its geometry, physical or not (keeping each "
                        "link's mass, or at --density) and report the difference per link")
    p.add_argument("--density", type=float, metavar="KG_M3",
                   help="with --recompute-inertials: density in kg/m^3 instead of keeping the given masses")
    p.add_argument("--copy-meshes", action="store_true",
                   help="copy the meshes below the recipe's folder (meshes/) instead of referencing them")
    return p


def run(args) -> int:
    from robotkit.importer import import_file

    if args.density is not None and not args.recompute_inertials:
        print("robotkit: error: --density needs --recompute-inertials", file=sys.stderr)
        return 2
    packages: dict[str, str] = {}
    for name, folder in args.package_path:
        packages[name] = folder
    result = import_file(args.file, args.output, packages, dict(args.arg),
                         recompute_inertials=args.recompute_inertials, copy_meshes=args.copy_meshes,
                         density=args.density, inertia_policy=args.inertia_policy)
    for w in result.warnings:
        print(f"warning: {w}", file=sys.stderr)
    print(f"wrote {os.path.relpath(result.recipe_path)} (robot {result.robot})")
    return 0
