"""Values that repeat across an imported recipe's joints (or links) go to its ``defaults:``.

A leaf value (``limit.effort``, ``dynamics.damping``, ``type``...) becomes a default when it
is shared by more than half of the items it applies to (the loader's rule,
:func:`robotkit.recipe.load.default_applies`) and by at least three, and the recipe gets
shorter for it.  The items holding that value drop it; the others keep their own value, and
an item that has none says so: the schema's default where the field has one
(``axis: [1, 0, 0]``, ``friction: 0``), ``null`` where it has none (``limit: null``).  So
the merged recipe is the same recipe, value for value (tests/importer/test_import.py checks it on
every robot of the corpus).
"""

from __future__ import annotations

import copy
import json

from robotkit.importer.recipe_writer import section_text
from robotkit.recipe import schema
from robotkit.recipe.load import default_applies

CANDIDATES = {
    "joints": (("type",), ("axis",), ("limit", "effort"), ("limit", "velocity"), ("dynamics", "damping"),
               ("dynamics", "friction")),
    "links": (("collision",), ("contact", "mu1"), ("contact", "mu2"), ("contact", "kp"), ("contact", "kd")),
}
"""The key paths that may become defaults: what a robot's joints (or links) share by design.
Names (parent, child, mimic), poses, inertials and geometry are each item's own."""

KIND = {"joints": "joint", "links": "link"}
MIN_SHARED = 3


def factor_defaults(recipe: dict) -> dict:
    """Move the values the recipe's joints and links share into ``recipe["defaults"]`` (in
    place); returns the defaults written (empty when none shortens the recipe)."""
    written: dict = {}
    for section, paths in CANDIDATES.items():
        items = recipe.get(section)
        if not isinstance(items, dict) or len(items) < MIN_SHARED:
            continue
        kind = KIND[section]
        base: dict = {}
        groups: dict[str, list[tuple]] = {}
        for path in paths:
            groups.setdefault(path[0], []).append(path)
        sizes: dict[int, tuple] = {}  # id -> (value, its text's length): the kept items are measured once

        def size(key: str, value) -> int:
            if id(value) not in sizes:
                sizes[id(value)] = (value, len(section_text(key, value)))
            return sizes[id(value)][1]

        for group in groups.values():  # a mapping's values together (limit: effort and velocity), else one by one
            for tried in [group] + ([[p] for p in group] if len(group) > 1 else []):
                trial_base, trial = copy.deepcopy(base), items
                for path in tried:
                    value = _shared(trial, path, kind, trial_base)
                    if value is not _NONE:
                        _set(trial_base, path, value)
                        trial = {name: _without(item, path, value, kind, trial_base) for name, item in trial.items()}
                if trial is items:  # nothing shared: nothing to weigh
                    continue
                before = size(section, items) + (size(kind, base) if base else 0)
                after = size(section, trial) + size(kind, trial_base)
                if after < before:
                    base, items = trial_base, trial
        if base:
            recipe[section] = items
            written[kind] = base
    if written:
        recipe["defaults"] = written
    return written


_NONE = object()


def _applies(path: tuple, item: dict, kind: str, base: dict) -> bool:
    return default_applies(kind, path[0], item, base)


def _shared(items: dict, path: tuple, kind: str, base: dict):
    """The value at ``path`` that more than half of the items it applies to hold (and at least
    three), or _NONE."""
    counts: dict[str, int] = {}
    mappings = False  # an item's own mapping is merged into a default mapping, not put in its place
    applicable = 0
    for item in items.values():
        if not isinstance(item, dict) or not _applies(path, item, kind, base):
            continue
        applicable += 1
        found = _get(item, path)
        if found is not _NONE and found is not None:
            key = json.dumps(found, sort_keys=True)
            counts[key] = counts.get(key, 0) + 1
            mappings = mappings or isinstance(found, dict)
    if not counts:
        return _NONE
    key, count = min(counts.items(), key=lambda kv: (-kv[1], kv[0]))
    if count < MIN_SHARED or 2 * count <= applicable:
        return _NONE
    value = json.loads(key)
    if isinstance(value, dict) and len(counts) > 1 and mappings:  # the Iris: rotors' cylinder, the body's box
        return _NONE
    return value


def _without(item, path: tuple, value, kind: str, base: dict):
    """The item as written under ``base``: ``value`` at ``path`` dropped, an absent value said."""
    if not isinstance(item, dict) or not _applies(path, item, kind, base):
        return item
    if any(_get(item, path[:i]) is None for i in range(1, len(path))):
        return item  # a mapping on the way said absent (``limit: null``): nothing goes under it
    item = copy.deepcopy(item)
    found = _get(item, path)
    if found is not _NONE and found == value:
        _drop(item, path)
    elif found is _NONE:
        _say_absent(item, path, kind)
    return item


def _say_absent(item: dict, path: tuple, kind: str) -> None:
    """Write what an absent value at ``path`` means, so the default does not fill it: the
    schema's default for the field, else null (at the first level that is absent)."""
    model = schema.Joint if kind == "joint" else schema.Link
    node = item
    for i, key in enumerate(path):
        field = model.model_fields[key]
        if key not in node:
            default = field.default
            if hasattr(default, "model_dump"):
                default = None  # a sub-model's default: absent means "none given"
            node[key] = copy.deepcopy(default)
            order = list(model.model_fields)  # in its place among the keys: axis after origin
            ordered = sorted(node.items(), key=lambda kv: order.index(kv[0]) if kv[0] in order else len(order))
            node.clear()
            node.update(ordered)
            return
        if i == len(path) - 1:
            return
        node = node[key]
        model = _model_of(field)


def _model_of(field):
    import typing

    from pydantic import BaseModel

    for arg in typing.get_args(field.annotation) or (field.annotation,):
        if isinstance(arg, type) and issubclass(arg, BaseModel):
            return arg
    raise TypeError(f"no model in {field.annotation!r}")


def _get(item: dict, path: tuple):
    node = item
    for key in path:
        if not isinstance(node, dict) or key not in node:
            return _NONE
        node = node[key]
    return node


def _set(tree: dict, path: tuple, value) -> None:
    for key in path[:-1]:
        tree = tree.setdefault(key, {})
    tree[path[-1]] = value


def _drop(item: dict, path: tuple) -> None:
    """Remove ``path`` and the mappings it leaves empty (an absent mapping gets the default's)."""
    nodes = [item]
    for key in path[:-1]:
        nodes.append(nodes[-1][key])
    del nodes[-1][path[-1]]
    for node, key in zip(reversed(nodes[:-1]), reversed(path[:-1])):
        if node[key] == {}:
            del node[key]
