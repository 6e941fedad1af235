"""The recipe reference, generated from the schema: JSON Schema for editors, Markdown for people.

``docs/recipe.schema.json`` and ``docs/recipe.md`` are the output of
``robotkit schema`` and ``robotkit schema --markdown``; a test keeps them current.
"""

from __future__ import annotations

import ast
import functools
import inspect
import json
import typing

from pydantic_core import PydanticUndefined

from robotkit.recipe import schema as s
from robotkit.recipe.expand.units import UNITS

SECTIONS = [
    (s.Recipe, "the top level of a recipe"), (s.Metadata, "`metadata`"), (s.Author, "`metadata.authors[]`"),
    (s.Maintainer, "`metadata.maintainers[]`"), (s.Urls, "`metadata.urls`"),
    (s.Material, "`materials.<name>`"), (s.Defaults, "`defaults`"), (s.Link, "`links.<name>`"),
    (s.Geometry, "`links.<name>.visual` / `collision`"), (s.Origin, "`origin`"), (s.Box, "`box`"),
    (s.Cylinder, "`cylinder`"), (s.Sphere, "`sphere`"), (s.Decimate, "`decimate`"),
    (s.Collision, "`links.<name>.collision` (a strategy) / `meshes.collision`"),
    (s.Proxy, "a collision strategy's `urdf` / `sdf` / `mjcf`"), (s.Coacd, "a collision strategy's `coacd`"),
    (s.Inertial, "`links.<name>.inertial`"), (s.Inertia, "`inertial.inertia`"), (s.Contact, "`links.<name>.contact`"),
    (s.Joint, "`joints.<name>`"), (s.Limit, "`joints.<name>.limit`"), (s.Dynamics, "`joints.<name>.dynamics`"),
    (s.Mimic, "`joints.<name>.mimic`"), (s.Loop, "`loops.<name>`"), (s.MeshDefaults, "`meshes`"),
    (s.SelfCollision, "`self_collision`"),
    (s.Sensor, "`sensors.<name>`"), (s.CameraParams, "`sensors.<name>.camera`"),
    (s.LidarParams, "`sensors.<name>.lidar`"), (s.SonarParams, "`sensors.<name>.sonar`"),
    (s.ImuParams, "`sensors.<name>.imu`"), (s.SensorBody, "`sensors.<name>.body`"),
    (s.Actuator, "`actuators.<joint>`"), (s.Motor, "`actuators.<joint>.motor`"), (s.World, "`worlds.<name>`"),
    (s.Arg, "`args.<name>`"), (s.Part, "`parts.<name>` (or a part file)"), (s.Instance, "`instances.<name>`"),
]
"""Every model of the schema, in the reference's order, with the key path it is written at
(:func:`markdown` refuses a model reachable from the recipe that is not listed)."""

DIMENSIONS = {"length": "length", "angle": "angle", "mass": "mass", "position": "joint position"}

TYPES = """Types: a *length* is a number in metres or a quantity with a length unit (``5 cm``), an
*angle* a number in radians or a quantity (``90 deg``), a *mass* a number in kilograms or a
quantity (``300 g``), a *joint position* an angle for revolute and continuous joints and a
length for prismatic ones; any value may be an expression ``${...}``."""

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



@functools.lru_cache(maxsize=1)
def documented() -> None:
    """Every schema model's fields described by their attribute docstrings (a string under the
    field, as pydantic's ``use_attribute_docstrings`` reads them), the models rebuilt so that
    their JSON Schema has them: done here, once, rather than at every import of the schema."""
    from pydantic import BaseModel

    models = [v for v in vars(s).values() if isinstance(v, type) and issubclass(v, BaseModel)
              and v.__module__ == s.__name__]
    for model in models:
        docs = {}
        for cls in reversed(model.__mro__):
            if cls in models:
                docs.update(_attribute_docs(cls))
        for name, field in model.model_fields.items():
            if field.description is None and name in docs:
                field.description = docs[name]
    for model in models:  # in the module's order: a model after the models it holds
        model.model_rebuild(force=True)


def _attribute_docs(cls) -> dict[str, str]:
    """The docstrings under the annotated attributes of ``cls``'s own body."""
    body = ast.parse(inspect.cleandoc("\n" + inspect.getsource(cls))).body[0].body
    return {a.target.id: inspect.cleandoc(b.value.value) for a, b in zip(body, body[1:])
            if isinstance(a, ast.AnnAssign) and isinstance(a.target, ast.Name) and isinstance(b, ast.Expr)
            and isinstance(b.value, ast.Constant) and isinstance(b.value.value, str)}


def json_schema(part: bool = False) -> str:
    """The JSON Schema of a recipe (or, ``part``, of a part file)."""
    documented()
    data = _expressions((s.Part if part else s.Recipe).model_json_schema())
    data["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    data["title"] = "robotkit part" if part else "robotkit recipe"
    return json.dumps(data, indent=2, sort_keys=True) + "\n"


def _anchor(model) -> str:
    return model.__name__.lower()


def _type(tp) -> str:
    import types

    from pydantic import BaseModel

    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin is typing.Annotated:
        dims = [m.kind for m in args[1:] if isinstance(m, s.Dim)]
        return DIMENSIONS[dims[0]] if dims else _type(args[0])
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_type(a) for a in args if a is not type(None))
    if origin is list:
        return f"list of {_type(args[0])}"
    if origin is dict:
        return f"mapping of name to {_type(args[1])}"
    if origin is typing.Literal:
        return " / ".join(f"`{a}`" for a in args)
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return f"[{tp.__name__}](#{_anchor(tp)})"
    return {float: "number", str: "text", int: "integer", bool: "true/false", dict: "mapping"}.get(
        tp, getattr(tp, "__name__", str(tp)))


def _annotation(field):
    """A field's type with its own metadata (a Dim) put back (pydantic keeps them apart)."""
    return typing.Annotated[(field.annotation, *field.metadata)] if field.metadata else field.annotation


def _models(tp, found: set):
    """Every schema model reachable from type ``tp`` into ``found``."""
    from pydantic import BaseModel

    if isinstance(tp, str):  # a forward reference pydantic resolved: the field's annotation has it
        return
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        if tp in found:
            return
        found.add(tp)
        for field in tp.model_fields.values():
            _models(field.annotation, found)
        return
    for a in typing.get_args(tp):
        _models(a, found)


def _default(field) -> str:
    if field.default is PydanticUndefined and field.default_factory is None:
        return "required"
    if field.default is None:
        return ""
    return json.dumps(field.default.model_dump() if hasattr(field.default, "model_dump") else field.default)


def _section(model, title: str) -> list[str]:
    lines = [f'<a id="{_anchor(model)}"></a>', "", f"## {model.__name__}: {title}", ""]
    doc = inspect.cleandoc(model.__doc__ or "")
    if doc and not doc.startswith(("!!!", "Usage docs")):
        lines += [doc, ""]
    lines += ["| key | type | default | meaning |", "|---|---|---|---|"]
    for name, field in model.model_fields.items():
        desc = (field.description or "").replace("\n", " ").replace("|", "\\|")
        tp = _type(_annotation(field)).replace("|", "\\|")
        lines.append(f"| `{field.alias or name}` | {tp} | {_default(field)} | {desc} |")
    return lines + [""]


def markdown() -> str:
    """The reference: one section per schema model (every key of the JSON Schema)."""
    documented()
    reachable: set = set()
    _models(s.Recipe, reachable)
    missing = sorted(m.__name__ for m in reachable - {m for m, _ in SECTIONS})
    if missing:
        raise AssertionError(f"robotkit.recipe.reference.SECTIONS lacks {', '.join(missing)}")
    lines = ["# Recipe reference", "",
             "Generated from `robotkit/recipe/schema.py` by `robotkit schema --markdown`; do not edit.",
             "", (s.__doc__ or "").split("\n\n", 1)[1].strip(), "", TYPES, "",
             "Sections: " + ", ".join(f"[{m.__name__}](#{_anchor(m)})" for m, _ in SECTIONS) + ".", ""]
    for model, title in SECTIONS:
        lines += _section(model, title)
    return "\n".join(lines)
