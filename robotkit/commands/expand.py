"""``robotkit expand RECIPE``: the flat recipe its arguments, parts and variants expand to."""

from __future__ import annotations

import sys

from robotkit.recipe.flat import flat_yaml


def run(args) -> int:
    sys.stdout.write(flat_yaml(args.recipe, dict(args.arg), args.variant))
    return 0
