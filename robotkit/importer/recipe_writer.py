"""Writing an imported recipe for people: top-level keys in order, a blank line between
sections, flow style for short vectors and mappings, numbers in the shortest form that
round-trips, and a comment above each link or joint the import changed from the original."""

from __future__ import annotations

import functools
import posixpath
import re
from collections import Counter


TOP_KEYS = ("robot", "units", "density", "ros", "metadata", "values", "materials", "defaults", "links", "joints",
            "urdf_extras", "mjcf_extras")


def fmt(x: float) -> str:
    """Shortest text that reads back as the same float64 (integral values without '.0')."""
    x = float(x)
    if x == 0:
        return "0"
    if x.is_integer() and abs(x) < 1e16:
        return str(int(x))
    text = repr(x)
    if "e" in text and "." not in text.split("e")[0]:
        mantissa, exp = text.split("e")
        text = f"{mantissa}.0e{exp}"
    return text


class _FlowList(list):
    pass


class _FlowMap(dict):
    pass


@functools.lru_cache(maxsize=None)
def _dumper():
    """The recipe's YAML dumper (one class for the process): libyaml's emitter when PyYAML has it
    (3 times faster than PyYAML's own, the same text), with robotkit's representers."""
    import yaml

    class Dumper(getattr(yaml, "CSafeDumper", yaml.SafeDumper)):
        pass

    def float_rep(dumper, value):
        text = fmt(value)
        tag = "tag:yaml.org,2002:int" if re.fullmatch(r"-?\d+", text) else "tag:yaml.org,2002:float"
        return dumper.represent_scalar(tag, text)

    def str_rep(dumper, value):
        if "\n" in value:
            return dumper.represent_scalar("tag:yaml.org,2002:str", value, style="|")
        return dumper.represent_scalar("tag:yaml.org,2002:str", value)

    Dumper.add_representer(float, float_rep)
    Dumper.add_representer(str, str_rep)
    Dumper.add_representer(_FlowList, lambda d, v: d.represent_sequence("tag:yaml.org,2002:seq", v, flow_style=True))
    Dumper.add_representer(_FlowMap, lambda d, v: d.represent_mapping("tag:yaml.org,2002:map", v.items(),
                                                                      flow_style=True))
    Dumper.add_representer(dict, lambda d, v: d.represent_mapping("tag:yaml.org,2002:map", v.items(),
                                                                  flow_style=False))
    Dumper.ignore_aliases = lambda self, data: True
    return Dumper


def _styled(value, width: int):
    """Flow style for number lists and for mappings short enough to read on one line."""
    if isinstance(value, list):
        if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
            return _FlowList(value)
        return [_styled(v, width - 2) for v in value]
    if isinstance(value, dict):
        inner = {k: _styled(v, width - 2) for k, v in value.items()}
        flat = all(not isinstance(v, (dict, list)) or isinstance(v, (_FlowList, _FlowMap)) for v in inner.values())
        if flat and all(not (isinstance(v, str) and "\n" in v) for v in inner.values()):
            candidate = _FlowMap(inner)
            if len(_dump_one(candidate)) <= width:
                return candidate
        return inner
    return value


def _dump_one(value) -> str:
    import yaml

    return yaml.dump(value, Dumper=_dumper(), default_flow_style=False, sort_keys=False, width=10**9,
                     allow_unicode=True).strip()


def dump_recipe(recipe: dict, header: list[str] | None = None,
                comments: dict[str, dict[str, str]] | None = None) -> str:
    """The recipe as readable YAML: top-level keys in order, a blank line between sections,
    flow style for short vectors and mappings; ``comments[section][name]`` goes above that
    entry (e.g. what an import repaired on a link)."""
    import yaml

    parts = []
    for line in header or []:
        parts.append(f"# {line}".rstrip() + "\n")
    keys = [k for k in TOP_KEYS if k in recipe] + [k for k in recipe if k not in TOP_KEYS]
    scalars = [k for k in keys if not isinstance(recipe[k], (dict, list))]
    sections = [k for k in keys if k not in scalars]
    dumper = _dumper()
    opts = dict(Dumper=dumper, default_flow_style=False, sort_keys=False, width=10**9, allow_unicode=True)
    parts.append(yaml.dump({k: recipe[k] for k in scalars}, **opts))
    for key in sections:
        parts.append("\n" + section_text(key, recipe[key], (comments or {}).get(key)))
    return "".join(parts)


def section_text(key: str, value, notes: dict[str, str] | None = None) -> str:
    """One top-level section as :func:`dump_recipe` writes it; ``notes[name]`` goes above that
    entry of ``links`` or ``joints``."""
    import yaml

    opts = dict(Dumper=_dumper(), default_flow_style=False, sort_keys=False, width=10**9, allow_unicode=True)
    if key == "values":
        styled = dict(value)
    elif key == "materials":
        styled = {name: _styled(m, 200) for name, m in value.items()}
    elif key in ("links", "joints"):
        if notes:
            text = [f"{key}:\n"]
            for name, entry in value.items():
                for line in wrap(notes.get(name, "")):
                    text.append(f"  # {line}\n")
                entry_text = yaml.dump({name: _styled_entry(entry)}, **opts)
                text.append("".join(f"  {line}" if line.strip() else line
                                    for line in entry_text.splitlines(keepends=True)))
            return "".join(text)
        styled = {name: _styled_entry(entry) for name, entry in value.items()}
    else:
        styled = _styled(value, 100)
    return yaml.dump({key: styled}, **opts)


def wrap(text: str, width: int = 96) -> list[str]:
    import textwrap

    return textwrap.wrap(text, width, break_long_words=False, break_on_hyphens=False) if text else []


def _styled_entry(entry: dict) -> dict:
    """A link or joint: its own keys in block style, each value as compact as reads well."""
    return {k: _styled(v, 110 - len(k)) for k, v in entry.items()}


def name_mesh_folders(recipe: dict) -> dict[str, str]:
    """Each mesh folder that two or more meshes share becomes a named value (``values:
    {kuka_iiwa_meshes: ../kuka_iiwa/meshes}``) and those meshes ``${kuka_iiwa_meshes}/link_0.stl``:
    the folder is written once.  Names come from the folder's last two parts, numbered apart.
    Returns name -> folder (added to ``recipe["values"]``)."""
    uses = []
    for link in recipe.get("links", {}).values():
        for key in ("visual", "collision"):
            value = link.get(key)
            for g in value if isinstance(value, list) else [value]:
                if isinstance(g, dict) and isinstance(g.get("mesh"), str) and "${" not in g["mesh"]:
                    uses.append(g)
    folders = Counter(posixpath.dirname(g["mesh"]) for g in uses)
    taken = set(recipe.get("values", {})) | set(recipe.get("args", {}))
    names: dict[str, str] = {}
    for folder, count in sorted(folders.items()):
        if count < 2 or not folder:
            continue
        parts = [part for part in folder.split("/") if part not in ("", ".", "..")]
        base = re.sub(r"[^A-Za-z0-9_]", "_", "_".join(parts[-2:])) or "meshes"
        if not re.match(r"[A-Za-z_]", base):
            base = "_" + base
        name, n = base, 2
        while name in taken:
            name, n = f"{base}_{n}", n + 1
        taken.add(name)
        names[folder] = name
    for g in uses:
        folder, file = posixpath.split(g["mesh"])
        if folder in names:
            g["mesh"] = f"${{{names[folder]}}}/{file}"
    added = {name: folder for folder, name in names.items()}
    if added:
        recipe.setdefault("values", {}).update(added)
    return added
