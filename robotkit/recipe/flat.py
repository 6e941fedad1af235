"""``robotkit expand``: the flat recipe a recipe expands to, as YAML (one document per variant).

The flat recipe has no arguments, expressions, units, parts, conditions or
variants left: numbers are SI, every link and joint is written out, and mesh
paths are relative to the recipe's folder.  It validates and builds the same robot.
"""

from __future__ import annotations

import os

from robotkit.recipe.load import load_recipes


def flat_data(loaded) -> dict:
    """The validated recipe as plain data, without the keys that hold their defaults."""
    data = loaded.recipe.model_dump(mode="json", by_alias=True, exclude_defaults=True)
    base = os.path.dirname(str(loaded.file))

    def rel(node):
        if isinstance(node, dict):
            return {k: (os.path.relpath(v, base) if k in ("mesh", "map") and isinstance(v, str)
                        and os.path.isabs(v) else rel(v)) for k, v in node.items()}
        if isinstance(node, list):
            return [rel(v) for v in node]
        return node

    data = rel(data)
    data.pop("defaults", None)  # already merged into every link and joint
    data.pop("include", None)  # already merged too
    return {"robot": data.pop("robot"), **data}


def flat_yaml(file: str, args: dict[str, str] | None = None, variant: str | None = None) -> str:
    import yaml

    loaded = load_recipes(file, args, variant)
    class Dumper(yaml.SafeDumper):
        pass

    def text(dumper, value):  # raw XML as a block, as a person writes it
        return dumper.represent_scalar("tag:yaml.org,2002:str", value, style="|" if "\n" in value else None)

    Dumper.add_representer(str, text)
    docs = []
    for one in loaded:
        head = f"# variant {one.variant}\n" if one.variant is not None else ""
        data = flat_data(one)
        extras = data.pop("urdf_extras", None)
        body = yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=100)
        if extras:
            body += yaml.dump({"urdf_extras": extras}, Dumper=Dumper, sort_keys=False, default_flow_style=False,
                              width=100)
        docs.append(head + body)
    return "---\n".join(docs)
