"""``robotkit schema``: the recipe's JSON Schema (for editors) or its Markdown reference."""

from __future__ import annotations

from robotkit.recipe.reference import json_schema, markdown


def run(args) -> int:
    print(markdown() if args.markdown else json_schema(part=args.part), end="")
    return 0
