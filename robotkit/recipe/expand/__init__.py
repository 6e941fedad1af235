"""Expansion: the recipe language on top of the flat recipe.

Between reading YAML (robotkit.recipe.load, line marks per key path) and
validating against the schema, this stage turns

- ``args:`` (defaults, overridden by ``--arg NAME:=VALUE`` and by ``variants:``),
- ``values:`` (named values),
- ``${...}`` expressions in any scalar (robotkit.recipe.expand.expr),
- quantities with units, ``5 cm``, ``90 deg``, ``300 g`` (robotkit.recipe.expand.units),
- ``parts:`` and ``instances:`` (prefixed, placed, optionally mirrored; robotkit.recipe.expand.parts),
- ``if:`` on links, joints, sensors, actuators and instances

into one flat recipe per variant, with line marks for every key: a problem in
an instance of a part names the part's file:line and key, and the instance.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field

from robotkit.errors import Problem, display_path
from robotkit.paths import recipe_policy
from robotkit.recipe.expand import units as _units
from robotkit.recipe.expand.language import (
    ITEM_SECTIONS, Context, Source, bind_args, declare_args, declare_values, evaluate_tree, keep,
)
from robotkit.recipe.expand.parts import expand_instances

CONTROL = ("args", "values", "parts", "instances", "variants")
VERBATIM = ("urdf_extras", "mjcf_extras")  # raw XML, copied as written (it may hold ${...} of its own)


@dataclass
class Expanded:
    """One flat recipe (one variant): the data, and where each flat item was written."""

    variant: str | None
    data: dict
    # (section, name) of a flat item -> (Source of the item, its key path in that source)
    items: dict = field(default_factory=dict)
    arg_names: tuple = ()
    files: tuple = ()  # part files read (dependencies even when no item of theirs is kept)
    # (file, line, key) of values a failed expression left unevaluated, its problem reported
    # where it failed: validation adds none of its own there
    quiet: frozenset = frozenset()


# ---------------------------------------------------------------- the stage


def expand(data: dict, where: dict, file: str, overrides: dict[str, str], read_yaml, problems: list[Problem],
           ignore_unknown_args: bool = False) -> list[Expanded]:
    """The flat recipe(s) of ``data``: one per variant (one when there are none)."""
    ctx = Context(read_yaml, problems, recipe_policy(file))
    top = Source(where)
    if not any(k in data for k in CONTROL) and not overrides and not _has_if(data) and not _has_dollar(
            {k: v for k, v in data.items() if k not in VERBATIM}):
        return [Expanded(None, data)]
    declared = declare_args(data.get("args"), {}, ctx, top.sub("args"))
    arg_line = top.locate(("args",)) if "args" in data else (file, None)
    cli = Source({(): arg_line})  # --arg problems name the option, at the recipe's args block
    if ignore_unknown_args:
        overrides = {k: v for k, v in overrides.items() if k in declared}
    variants = data.get("variants")
    if variants is not None and not (isinstance(variants, dict) and all(
            isinstance(v, dict) or v is None for v in variants.values())):
        ctx.report(top, ("variants",), "must be a mapping of variant names to argument values")
        variants = None
    out = []
    for variant, given in (variants or {None: {}}).items():
        vsrc = top.sub("variants", variant) if variant is not None else top
        values = bind_args(declared, given or {}, ctx, "the recipe", lambda n: (vsrc, (n,)), from_text=False)
        values = bind_args(declared, overrides, ctx, "the recipe", lambda n: (cli, (f"--arg {n}",)),
                           from_text=True, base=values)
        scope = declare_values(data.get("values"), values, ctx, top.sub("values"))
        flat = {}
        for key, value in data.items():
            if key in CONTROL:
                continue
            flat[key] = evaluate_tree(value, scope, ctx, top.sub(key)) if key not in ITEM_SECTIONS + VERBATIM \
                else value
        result = Expanded(variant, flat, arg_names=tuple(declared))
        for section in ITEM_SECTIONS:
            items = data.get(section)
            if not isinstance(items, dict):
                if section in data:
                    flat[section] = evaluate_tree(items, scope, ctx, top.sub(section))
                continue
            kept = {}
            for name, item in items.items():
                item = evaluate_tree(item, scope, ctx, top.sub(section, name))
                if keep(item, ctx, top, (section, name)):
                    kept[name] = item
            flat[section] = kept
        if "instances" in data:
            parts_env = [(data.get("parts"), top.sub("parts"), scope, file)]
            expand_instances(data["instances"], top.sub("instances"), scope, parts_env, ctx, flat, result.items,
                             default_units=data.get("units") if isinstance(data.get("units"), str) else "m",
                             chain=())
        elif "parts" in data and not isinstance(data["parts"], dict):
            ctx.report(top, ("parts",), "must be a mapping of part names to definitions or files")
        if variant is not None and isinstance(flat.get("robot"), str):
            flat["robot"] = f"{flat['robot']}_{variant}"
        out.append(result)
    for result in out:
        result.files = tuple(sorted(p for p, (d, _) in ctx.part_files.items() if d is not None))
        result.quiet = frozenset(ctx.quiet)
    return out


def _has_if(data: dict) -> bool:
    return any(isinstance(items, dict) and any(isinstance(v, dict) and "if" in v for v in items.values())
               for items in (data.get(s) for s in ITEM_SECTIONS))


def _has_dollar(node) -> bool:
    if isinstance(node, dict):
        return any(_has_dollar(v) for v in node.values())
    if isinstance(node, list):
        return any(_has_dollar(v) for v in node)
    return isinstance(node, str) and "${" in node


def convert_units(data: dict, problem) -> dict:
    """Quantities -> SI numbers in the flat recipe (after ``defaults:`` are merged)."""
    return _units.convert(data, problem)


def copy_marks(expanded: Expanded, where: dict) -> tuple[dict, dict]:
    """Line marks of the flat recipe: the recipe's own, plus every instance item's, copied from
    where it was written.  Returns (where, origins): origins maps a flat item's key path to
    (its key path in its source, the instance text, its redirects: robotkit.recipe.expand.parts
    ._part_items) for messages."""
    out = dict(where)
    origins = {}
    index: dict = {}
    for (section, name), (src, path, redirects) in expanded.items.items():
        depth = len(path)
        key = (id(src.where), depth)
        if key not in index:
            groups: dict = {}
            for p, m in src.where.items():
                if len(p) >= depth:
                    groups.setdefault(p[:depth], []).append((p[depth:], m))
            index[key] = groups
        dst = (section, name)
        for rest, m in index[key].get(path, []):
            out[dst + rest] = m
        origins[dst] = (path, src.via, redirects)
    return out, origins


def deepcopy(data):
    return copy.deepcopy(data)


def display(path) -> str:
    return display_path(path)
