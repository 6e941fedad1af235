"""The recipe reference, generated from the schema: JSON Schema for editors, Markdown for people.

``docs/recipe.schema.json`` and ``docs/recipe.md`` are the output of
``robotkit schema`` and ``robotkit schema --markdown``; a test keeps them current.
"""

from __future__ import annotations

import json
import typing

from pydantic_core import PydanticUndefined

from robotkit.recipe import schema as s
from robotkit.recipe.expand.units import UNITS

SECTIONS = [
    (s.Recipe, "recipe (top level)"), (s.Metadata, "metadata"), (s.Author, "metadata.authors[]"),
    (s.Material, "materials.<name>"), (s.Defaults, "defaults"), (s.Link, "links.<name>"),
    (s.Geometry, "links.<name>.visual / collision"), (s.Origin, "origin"), (s.Box, "box"),
    (s.Cylinder, "cylinder"), (s.Sphere, "sphere"), (s.Inertial, "links.<name>.inertial"),
    (s.Inertia, "inertial.inertia"), (s.Joint, "joints.<name>"), (s.Limit, "joints.<name>.limit"),
    (s.Dynamics, "joints.<name>.dynamics"), (s.Mimic, "joints.<name>.mimic"),
    (s.Arg, "args.<name>"), (s.Part, "parts.<name> (or a part file)"), (s.Instance, "instances.<name>"),
]

EXPRESSION = r"\$\{[^{}]*\}"


def _quantity_pattern(kind: str) -> str:
    units = "|".join(sorted((u for u, (dim, _) in UNITS.items() if kind == "position" or dim == kind),
                            key=lambda u: (-len(u), u)))
    return rf"^\s*([-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?|{EXPRESSION})\s*({units})\s*$"


def _expressions(node):
    """Let every number and true/false also be an expression (and a length, angle or mass a
    quantity with its unit), so editors accept what the expansion stage understands."""
    if isinstance(node, list):
        return [_expressions(v) for v in node]
    if not isinstance(node, dict):
        return node
    node = {k: _expressions(v) for k, v in node.items()}
    if node.get("type") in ("number", "integer", "boolean"):
        meta = {k: node.pop(k) for k in ("default", "description", "title") if k in node}
        alts = [node, {"type": "string", "pattern": rf"^\s*{EXPRESSION}\s*$"}]
        if "x-unit" in node:
            alts.append({"type": "string", "pattern": _quantity_pattern(node["x-unit"])})
        return {"anyOf": alts, **meta}
    return node



def json_schema(part: bool = False) -> str:
    """The JSON Schema of a recipe (or, ``part``, of a part file)."""
    data = _expressions((s.Part if part else s.Recipe).model_json_schema())
    data["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    data["title"] = "robotkit part" if part else "robotkit recipe"
    return json.dumps(data, indent=2, sort_keys=True) + "\n"


def _type(tp) -> str:
    import types

    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin is typing.Annotated:
        return _type(args[0])
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_type(a) for a in args if a is not type(None))
    if origin is list:
        return f"list of {_type(args[0])}"
    if origin is dict:
        return f"mapping of name to {_type(args[1])}"
    if origin is typing.Literal:
        return " / ".join(f"`{a}`" for a in args)
    return {float: "number", str: "text", int: "integer", bool: "true/false", dict: "mapping"}.get(
        tp, getattr(tp, "__name__", str(tp)))


def markdown() -> str:
    lines = ["# Recipe reference", "",
             "Generated from `robotkit/recipe/schema.py` by `robotkit schema --markdown`; do not edit.",
             "", (s.__doc__ or "").split("\n\n", 1)[1].strip(), ""]
    for model, title in SECTIONS:
        lines += [f"## {title}", ""]
        doc = (model.__doc__ or "").strip()
        if doc and not doc.startswith(("!!!", "Usage docs")):
            lines += [doc, ""]
        lines += ["| key | type | default | meaning |", "|---|---|---|---|"]
        for name, field in model.model_fields.items():
            default = "required" if field.default is PydanticUndefined and field.default_factory is None else (
                "" if field.default is None else json.dumps(
                    field.default.model_dump() if hasattr(field.default, "model_dump") else field.default))
            desc = (field.description or "").replace("\n", " ").replace("|", "\\|")
            tp = _type(field.annotation).replace("|", "\\|")
            lines.append(f"| `{field.alias or name}` | {tp} | {default} | {desc} |")
        lines.append("")
    return "\n".join(lines)
