"""``robotkit expand RECIPE``: the flat recipe its arguments, parts and variants expand to."""

from __future__ import annotations

import sys

from robotkit.commands.inputs import package_paths
from robotkit.recipe.flat import flat_yaml


def run(args) -> int:
    if package_paths(args.package_path) is None:  # a recipe needs none, but a malformed one is bad input
        return 2
    sys.stdout.write(flat_yaml(args.recipe, dict(args.arg), args.variant))
    return 0
