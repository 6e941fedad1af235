"""YAML read safely: libyaml's loader, and the limits checked on a file's events before it is
composed (size, nesting depth, alias expansion), for recipes, parts, includes and map files.
Light on purpose (PyYAML only): ``robotkit world`` reads a map through it without loading the
recipe schema."""

from __future__ import annotations

import yaml


class SafeLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):  # libyaml: 6.8x faster to compose
    pass



MAX_YAML_BYTES = 16 * 2**20
"""Largest recipe, part or included file read."""
MAX_DEPTH = 64
"""Deepest nesting of mappings and lists (libyaml's composer recurses in C: deep nesting crashes it)."""
MAX_NODES = 1_000_000
"""Most values a file may hold once its aliases are expanded (an alias bomb stops here)."""


def yaml_limits(text: str) -> tuple[str, int] | None:
    """(problem, line) when ``text`` nests too deep, has a recursive alias or expands past
    :data:`MAX_NODES` values; None otherwise (syntax errors are left to the composer).

    One pass over libyaml's events, stopping at the first excess, so nothing is built first:
    each anchor's expanded size is known when its node closes; an alias adds that size."""
    open_nodes: list[list] = [[0, None]]  # [expanded size, anchor] per open collection
    sizes: dict[str, int] = {}
    opened = set()
    try:
        for event in yaml.parse(text, Loader=SafeLoader):
            kind = type(event)
            if kind in (yaml.MappingStartEvent, yaml.SequenceStartEvent):
                if len(open_nodes) > MAX_DEPTH:
                    return f"nested deeper than {MAX_DEPTH} levels", event.start_mark.line + 1
                open_nodes.append([1, event.anchor])
                if event.anchor:
                    opened.add(event.anchor)
                continue
            if kind in (yaml.MappingEndEvent, yaml.SequenceEndEvent):
                n, anchor = open_nodes.pop()
                if anchor:
                    sizes[anchor] = n
                    opened.discard(anchor)
            elif kind is yaml.ScalarEvent:
                n = 1
                if event.anchor:
                    sizes[event.anchor] = 1
            elif kind is yaml.AliasEvent:
                if event.anchor in opened:
                    return f"alias '*{event.anchor}' refers to a node that contains it (recursive alias)", \
                        event.start_mark.line + 1
                n = sizes.get(event.anchor, 1)  # undefined: the composer says so
            else:
                continue
            open_nodes[-1][0] += n
            if open_nodes[-1][0] > MAX_NODES or sum(f[0] for f in open_nodes) > MAX_NODES:
                return (f"aliases expand to more than {MAX_NODES:,} values (an alias bomb?)",
                        event.start_mark.line + 1)
    except yaml.YAMLError as exc:  # libyaml 0.2.5 as PyYAML 6.0.4 ships it stops deep nesting itself,
        mark = getattr(exc, "problem_mark", None)  # scanning ahead of the events
        if "maximum nesting depth" in str(getattr(exc, "problem", "")) and mark is not None:
            return f"nested deeper than {MAX_DEPTH} levels", mark.line + 1
        return None  # syntax errors are the composer's to report
    return None
