"""Read a recipe: YAML with line marks, includes, defaults, schema validation.

Every problem found is collected as a :class:`Problem` naming the file, the
line and the dotted key; :func:`load_recipe` raises one :class:`RecipeError`
holding all of them.
"""

from __future__ import annotations

import difflib
import os
import typing
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from robotkit.errors import Problem, RecipeError, display_path, short_number, yaml_syntax_problem
from robotkit.paths import recipe_policy
from robotkit.recipe.expand import convert_units, copy_marks, expand
from robotkit.recipe.schema import RENAMED, Recipe
from robotkit.recipe.yamlsafe import MAX_YAML_BYTES, SafeLoader, yaml_limits

Path_ = tuple  # a key path: ("links", "base", "visual", 0, "mesh")


@dataclass
class Marks:
    """Where each key path of the merged recipe data was written."""

    where: dict[Path_, tuple[str, int]] = field(default_factory=dict)
    # key paths whose value came from ``defaults`` -> the defaults path
    from_defaults: dict[Path_, Path_] = field(default_factory=dict)
    # flat items made by a part instance -> (key path where the part wrote them, instance text)
    origins: dict[Path_, tuple[Path_, str]] = field(default_factory=dict)

    def locate(self, path: Path_) -> tuple[str | None, int | None]:
        for n in range(len(path), -1, -1):
            if path[:n] in self.where:
                return self.where[path[:n]]
        return None, None

    def problem(self, path: Path_, message: str) -> Problem:
        key_path = path
        for n in range(len(path), 0, -1):
            if path[:n] in self.from_defaults:
                key_path = self.from_defaults[path[:n]] + path[n:]
                break
        via = ""
        if self.origins and len(path) >= 2 and path[:2] in self.origins and key_path is path:
            source, via, redirects = self.origins[path[:2]]
            for n in range(len(path), 1, -1):
                if path[2:n] in redirects:  # the value came whole from the instance: its line
                    file, line, key, note = redirects[path[2:n]]
                    return Problem(message + note, file=file, line=line, key=key + dotted(path[n:], nested=True))
            key_path = source + path[2:]
        file, line = self.locate(path)
        return Problem(message + via, file=file, line=line, key=dotted(key_path))


def dotted(path: Path_, nested: bool = False) -> str:
    """``links.base.visual[0]``; ``nested``: the path continues a key (``.visual[0]``)."""
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out or nested else "") + str(part)
    return out


# ---------------------------------------------------------------- YAML with marks


class _PyLoader(yaml.SafeLoader):  # for syntax errors: the pure-Python parser's wording
    pass


def _read_yaml(file: Path, problems: list[Problem]):
    """Parse ``file``; return (data, marks) with one mark per key path."""
    try:
        size = file.stat().st_size
        if size > MAX_YAML_BYTES:
            problems.append(Problem(f"file is {size:,} bytes; robotkit reads YAML files of at most "
                                    f"{MAX_YAML_BYTES:,} bytes", file=str(file)))
            return None, {}
        text = file.read_text(encoding="utf-8")
    except FileNotFoundError:
        problems.append(Problem("file not found", file=str(file)))
        return None, {}
    except (OSError, UnicodeDecodeError) as exc:
        problems.append(Problem(f"cannot read file: {exc}", file=str(file)))
        return None, {}
    limit = yaml_limits(text)
    if limit is not None:
        problems.append(Problem(limit[0], file=str(file), line=limit[1]))
        return None, {}
    try:
        try:
            node = yaml.compose(text, Loader=SafeLoader)
        except yaml.YAMLError:
            node = yaml.compose(text, Loader=_PyLoader)
    except yaml.YAMLError as exc:
        problems.append(yaml_syntax_problem(exc, str(file)))
        return None, {}
    if node is None:
        problems.append(Problem("the file is empty", file=str(file)))
        return None, {}
    marks: dict[Path_, tuple[str, int]] = {}
    constructor = SafeLoader(text)
    data = _construct(node, (), str(file), marks, problems, constructor)
    return data, marks


def _construct(node, path, file, marks, problems, constructor):
    marks.setdefault(path, (file, node.start_mark.line + 1))
    if isinstance(node, yaml.MappingNode):
        out = {}
        for key_node, value_node in node.value:
            if not isinstance(key_node, yaml.ScalarNode):
                problems.append(Problem("mapping keys must be plain names", file=file,
                                        line=key_node.start_mark.line + 1, key=dotted(path)))
                continue
            key = constructor.construct_object(key_node)
            if not isinstance(key, str):
                key = str(key)
            sub = path + (key,)
            if key in out:
                problems.append(Problem(f"duplicate key (first given on line {marks[sub][1]})",
                                        file=file, line=key_node.start_mark.line + 1, key=dotted(sub)))
                continue
            marks[sub] = (file, key_node.start_mark.line + 1)
            out[key] = _construct(value_node, sub, file, marks, problems, constructor)
        return out
    if isinstance(node, yaml.SequenceNode):
        return [_construct(item, path + (i,), file, marks, problems, constructor)
                for i, item in enumerate(node.value)]
    return constructor.construct_object(node)


# ---------------------------------------------------------------- includes and defaults

MERGED_SECTIONS = ("materials", "links", "joints")


def _gather(file: Path, problems: list[Problem], seen: tuple[Path, ...] = (), reads=None):
    """Read ``file`` and, recursively, the files it includes (inside ``reads``, a
    :class:`robotkit.paths.ReadPolicy`); merge their sections."""
    if reads is None:
        reads = recipe_policy(file)
    data, marks = _read_yaml(file, problems)
    if data is None:
        return None, marks
    if not isinstance(data, dict):
        problems.append(Problem("a recipe must be a mapping of keys", file=str(file), line=1))
        return None, marks
    includes = data.get("include", [])
    if not isinstance(includes, list):
        return data, marks  # the schema reports the type
    for i, inc in enumerate(includes):
        if not isinstance(inc, str):
            continue
        where = marks.get(("include", i), (str(file), None))
        if "\0" in inc:
            problems.append(Problem(f"included file {inc!r} is not a valid file name (it holds a NUL character)",
                                    file=where[0], line=where[1], key=f"include[{i}]"))
            continue
        inc_path = Path(os.path.realpath(file.parent / inc))  # never raises (long names, loops)
        if inc_path in seen or inc_path == file:
            problems.append(Problem(f"'{inc}' includes itself (include cycle)", file=where[0],
                                    line=where[1], key=f"include[{i}]"))
            continue
        if (why := reads.refusal(inc_path)) is not None:
            problems.append(Problem(f"included file '{inc}' {why}", file=where[0], line=where[1], key=f"include[{i}]"))
            continue
        if not os.path.isfile(inc_path):
            problems.append(Problem(f"included file '{inc}' does not exist", file=where[0],
                                    line=where[1], key=f"include[{i}]"))
            continue
        sub, sub_marks = _gather(inc_path, problems, seen + (file,), reads)
        if sub is None:
            continue
        for key in sub:
            if key not in MERGED_SECTIONS + ("include", "urdf_extras"):
                f, line = sub_marks[(key,)]
                problems.append(Problem(
                    f"an included file may only hold {', '.join(MERGED_SECTIONS)}, urdf_extras", file=f, line=line,
                    key=key))
        extras = sub.get("urdf_extras")
        if isinstance(extras, list) and isinstance(data.setdefault("urdf_extras", []), list):
            offset = len(data["urdf_extras"])  # appended after the including file's own
            data["urdf_extras"] = data["urdf_extras"] + extras
            for p, m in sub_marks.items():
                if p[:1] == ("urdf_extras",) and len(p) > 1 and isinstance(p[1], int):
                    marks[("urdf_extras", p[1] + offset) + p[2:]] = m
            marks.setdefault(("urdf_extras",), sub_marks[("urdf_extras",)])
        for section in MERGED_SECTIONS:
            items = sub.get(section)
            if not isinstance(items, dict):
                continue
            target = data.setdefault(section, {})
            if not isinstance(target, dict):
                continue
            if (section,) not in marks:
                marks[(section,)] = sub_marks[(section,)]
            for name, value in items.items():
                if name in target:
                    f, line = marks[(section, name)]
                    f2, line2 = sub_marks[(section, name)]
                    problems.append(Problem(
                        f"defined twice: here and in {_rel(f)}:{line}", file=f2, line=line2, key=f"{section}.{name}"))
                    continue
                target[name] = value
                for p, m in sub_marks.items():
                    if p[:2] == (section, name):
                        marks[p] = m
    return data, marks


def _rel(path: str) -> str:
    return display_path(path)


def _deep_merge(base, over, base_path, over_path, marks: Marks):
    """``over`` wins; dictionaries merge key by key."""
    if isinstance(base, dict) and isinstance(over, dict):
        out = dict(over)
        for k, v in base.items():
            if k in over:
                out[k] = _deep_merge(v, over[k], base_path + (k,), over_path + (k,), marks)
            else:
                out[k] = v
                _copy_marks(base_path + (k,), over_path + (k,), marks)
        return out
    return over


def _copy_marks(src: Path_, dst: Path_, marks: Marks):
    for p, m in list(marks.where.items()):
        if p[: len(src)] == src:
            marks.where[dst + p[len(src):]] = m
    marks.from_defaults[dst] = src


LIMITED = ("revolute", "prismatic", "continuous")
"""The joint types that take a ``limit``."""
UNAXED = ("fixed", "floating")
"""The joint types that have no ``axis``."""


def default_applies(kind: str, key: str, item: dict, base: dict) -> bool:
    """Whether the default ``key`` of ``defaults.<kind>`` goes under this link or joint:
    a joint's ``limit`` only under the types that take one (revolute, prismatic, continuous),
    its ``axis`` only under those that move along one (not fixed, floating); everything else
    under every item.  The type is the item's own, else the default's."""
    if kind != "joint" or key not in ("limit", "axis"):
        return True
    jtype = item.get("type", base.get("type"))
    if not isinstance(jtype, str):
        return True  # the schema reports it
    return jtype in LIMITED if key == "limit" else jtype not in UNAXED


def _apply_defaults(data: dict, marks: Marks):
    defaults = data.get("defaults")
    if not isinstance(defaults, dict):
        return
    for kind, section in (("link", "links"), ("joint", "joints")):
        base = defaults.get(kind)
        items = data.get(section)
        if not isinstance(base, dict) or not base or not isinstance(items, dict):
            continue
        for name, value in items.items():
            if value is None:
                value = {}
            if isinstance(value, dict):
                applied = {k: v for k, v in base.items() if default_applies(kind, k, value, base)}
                items[name] = _deep_merge(applied, value, ("defaults", kind), (section, name), marks)


def _absolute_meshes(data: dict, marks: Marks):
    """Turn every mesh and map path into an absolute one, relative to the file that wrote it."""
    worlds = data.get("worlds")
    if isinstance(worlds, dict):
        for name, w in worlds.items():
            if isinstance(w, dict) and isinstance(w.get("map"), str):
                file, _ = marks.locate(("worlds", name, "map"))
                base = Path(file).parent if file else Path.cwd()
                w["map"] = os.path.normpath(str((base / w["map"]).absolute()))
    holders = []
    if isinstance(data.get("links"), dict):
        holders += [(("links", name), link, ("visual", "collision")) for name, link in data["links"].items()]
    for name, link in (data.get("links") or {}).items() if isinstance(data.get("links"), dict) else []:
        if isinstance(link, dict) and isinstance(link.get("collision"), dict) and "source" in link["collision"]:
            holders.append((("links", name, "collision"), link["collision"], ("source",)))
    if isinstance(data.get("sensors"), dict):
        holders += [(("sensors", name, "body"), s.get("body"), ("visual",)) for name, s in data["sensors"].items()
                    if isinstance(s, dict)]
    for prefix, link, kinds in holders:
        if not isinstance(link, dict):
            continue
        for kind in kinds:
            geoms = link.get(kind)
            items = [(None, geoms)] if isinstance(geoms, dict) else (
                list(enumerate(geoms)) if isinstance(geoms, list) else [])
            for i, g in items:
                if isinstance(g, dict) and isinstance(g.get("mesh"), str):
                    path = prefix + (kind,) + (() if i is None else (i,)) + ("mesh",)
                    file, _ = marks.locate(path)
                    base = Path(file).parent if file else Path.cwd()
                    g["mesh"] = os.path.normpath(str((base / g["mesh"]).absolute()))


# ---------------------------------------------------------------- schema errors

_TAGS = {"keyword", "shape", "shapes", "number", "vector", "strategy"}


def _fields_at(model, loc):
    """The field names a model accepts at ``loc`` (for did-you-mean)."""
    from pydantic import BaseModel

    tp = model
    for part in loc:
        tp = _unwrap(tp)
        if isinstance(part, int) or part in _TAGS:
            args = typing.get_args(tp)
            tp = args[0] if args else tp
            continue
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            if part not in tp.model_fields:
                return []
            tp = tp.model_fields[part].annotation
        elif typing.get_origin(tp) is dict:
            tp = typing.get_args(tp)[1]
        else:
            return []
    tp = _unwrap(tp)
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return list(tp.model_fields)
    return []


def _unwrap(tp):
    """Strip Annotated, Optional and unions down to the model or container that matters."""
    while True:
        origin = typing.get_origin(tp)
        if origin is typing.Annotated:
            tp = typing.get_args(tp)[0]
            continue
        if origin in (typing.Union, getattr(__import__("types"), "UnionType")):
            from pydantic import BaseModel

            args = [a for a in typing.get_args(tp) if a is not type(None)]
            pick = [a for a in args if isinstance(_unwrap(a), type) and issubclass(_unwrap(a), BaseModel)]
            pick = pick or [a for a in args if typing.get_origin(_unwrap(a)) in (list, dict)]
            tp = pick[0] if pick else args[0]
            continue
        return tp


def _num(x) -> str:
    return short_number(x) if isinstance(x, float) else str(x)


def _message(err: dict) -> str:
    kind = err["type"]
    ctx = {k: _num(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else v
           for k, v in err.get("ctx", {}).items()}
    got = err.get("input")
    if kind == "extra_forbidden":
        return "unknown key"
    if kind == "missing":
        return "required key is missing"
    if kind == "greater_than":
        return f"must be > {ctx['gt']}"
    if kind == "greater_than_equal":
        return f"must be >= {ctx['ge']}"
    if kind == "less_than":
        return f"must be < {ctx['lt']}"
    if kind == "less_than_equal":
        return f"must be <= {ctx['le']}"
    if kind == "finite_number":
        return f"must be a finite number (got {got!r})"
    if kind in ("float_parsing", "float_type", "int_parsing", "int_type"):
        return f"must be a number (got {got!r})"
    if kind == "string_type":
        return f"must be a string (got {got!r})"
    if kind == "bool_type" or kind == "bool_parsing":
        return f"must be true or false (got {got!r})"
    if kind == "literal_error":
        return f"must be one of {ctx['expected']} (got {got!r})"
    if kind in ("dict_type", "model_type", "model_attributes_type"):
        return f"must be a mapping (got {got!r})"
    if kind == "list_type":
        return f"must be a list (got {got!r})"
    if kind in ("too_short", "too_long"):
        if ctx.get("field_type") == "List":
            n = ctx.get("min_length") if kind == "too_short" else ctx.get("max_length")
            return f"must have {n} values (got {ctx.get('actual_length')})"
    if kind == "value_error":
        return str(ctx.get("error", err["msg"]))
    if kind in ("union_tag_invalid", "union_tag_not_found"):
        return f"has the wrong form (got {got!r})"
    msg = err["msg"]
    return msg[:1].lower() + msg[1:]


def schema_problems(exc, marks: Marks, model) -> list[Problem]:
    out: list[Problem] = []
    seen = set()
    for err in exc.errors(include_url=False):
        loc = tuple(p for p in err["loc"] if p not in _TAGS and p != "[key]")
        msg = _message(err)
        if err["type"] == "extra_forbidden" and len(loc) == 1 and loc[0] in RENAMED:
            msg = f"renamed to '{RENAMED[loc[0]]}' (same values)"
        elif err["type"] == "extra_forbidden" and loc:
            choices = _fields_at(model, [p for p in err["loc"][:-1]])
            close = difflib.get_close_matches(str(loc[-1]), choices, n=1)
            if close:
                msg += f" (did you mean '{close[0]}'?)"
            elif choices:
                msg += f" (expected one of: {', '.join(choices)})"
        problem = marks.problem(loc, msg)
        if str(problem) not in seen:
            seen.add(str(problem))
            out.append(problem)
    return out


# ---------------------------------------------------------------- entry point


@dataclass
class LoadedRecipe:
    file: Path
    recipe: "object"  # robotkit.recipe.schema.Recipe
    marks: Marks
    files: list[str]  # every YAML file read (for dependency tracking)
    partial: bool | str = False  # True: invalid parts were neutralised; "tree": joints dropped too
    problems: list[Problem] = field(default_factory=list)  # found while loading (the recipe is then partial)
    variant: str | None = None  # the variant of the recipe this is (robotkit.recipe.expand)
    arg_names: tuple[str, ...] = ()  # the arguments the recipe declares


def read_recipes(file: str | os.PathLike, args: dict[str, str] | None = None,
                 ignore_unknown_args: bool = False, variant: str | None = None) -> list[LoadedRecipe]:
    """Read, expand and validate a recipe: one LoadedRecipe per variant (one when it has none).

    Never raises for bad input: each result carries its ``problems`` and, when it can, a
    recipe with the invalid parts neutralised, so later stages can add their own problems
    (robotkit.model.resolve.resolve_checked).  ``args``: ``--arg`` overrides, name -> text;
    ``variant`` (``--variant``): only that variant (a recipe without it: one result, its problem).
    """
    file = Path(file).absolute()
    problems: list[Problem] = []
    data, where = _gather(file, problems)
    if data is None:
        return [LoadedRecipe(file=file, recipe=None, marks=Marks(where=where), files=[str(file)],
                             partial=True, problems=problems)]
    expanded = expand(data, where, str(file), dict(args or {}), _read_yaml, problems,
                      ignore_unknown_args=ignore_unknown_args)
    out = []
    for exp in expanded:
        shared = list(problems)
        if exp.items:
            flat_where, origins = copy_marks(exp, where)
            marks = Marks(where=flat_where, origins=origins)
        else:
            marks = Marks(where=dict(where) if len(expanded) > 1 else where)
        loaded = _validate(file, exp.data, marks, shared, exp.variant, exp.quiet)
        loaded.arg_names = exp.arg_names
        loaded.files = sorted(set(loaded.files) | set(exp.files))
        out.append(loaded)
    return out if variant is None else _one_variant(out, variant, file)


def _one_variant(loaded: list[LoadedRecipe], variant: str, file: Path) -> list[LoadedRecipe]:
    """The results of ``variant`` alone; when the recipe has no such variant, one result without
    a recipe whose problems are that one, after the recipe's own."""
    chosen = [one for one in loaded if one.variant == variant]
    if chosen:
        return chosen
    names = [one.variant for one in loaded if one.variant is not None]
    close = difflib.get_close_matches(variant, names, n=1)
    known = f"variants: {', '.join(names)}" if names else "the recipe has no variants"
    hint = f"did you mean '{close[0]}'? " if close else ""
    problems = [p for one in loaded for p in one.problems]
    problems = [p for i, p in enumerate(problems) if p not in problems[:i]]
    problems.insert(0, Problem(f"no variant named '{variant}' ({hint}{known})", file=str(file), key="--variant"))
    files = sorted({f for one in loaded for f in one.files})
    return [LoadedRecipe(file=file, recipe=None, marks=loaded[0].marks, files=files, partial=True, problems=problems)]


def _validate(file: Path, data: dict, marks: Marks, problems: list[Problem], variant,
              quiet: frozenset = frozenset()) -> LoadedRecipe:
    from pydantic import ValidationError

    _apply_defaults(data, marks)
    convert_units(data, lambda path, msg: problems.append(marks.problem(path, msg)))
    _absolute_meshes(data, marks)
    recipe = None
    partial = False
    try:
        recipe = Recipe.model_validate(data)
    except ValidationError as exc:
        taken = {(p.file, p.line, p.key) for p in problems} | quiet
        problems.extend(p for p in schema_problems(exc, marks, Recipe) if (p.file, p.line, p.key) not in taken)
        recipe, partial = _salvage(data, exc)
    unique = []
    for p in problems:
        if p not in unique:
            unique.append(p)
    files = sorted({f for f, _ in marks.where.values() if f})
    return LoadedRecipe(file=file, recipe=recipe, marks=marks, files=files, partial=partial, problems=unique,
                        variant=variant)


def sort_problems(problems: list[Problem], file) -> list[Problem]:
    """The recipe's own file first, then by file and line."""
    return sorted(problems, key=lambda p: (p.file != str(file), p.file or "", p.line or 0))


def load_recipes(file: str | os.PathLike, args: dict[str, str] | None = None,
                 variant: str | None = None) -> list[LoadedRecipe]:
    """:func:`read_recipes`, raising RecipeError with every loading problem."""
    loaded = read_recipes(file, args, variant=variant)
    problems = [p for one in loaded for p in one.problems]
    if problems:
        unique = []
        for p in problems:
            if p not in unique:
                unique.append(p)
        raise RecipeError(sort_problems(unique, loaded[0].file))
    return loaded


def load_recipe(file: str | os.PathLike, args: dict[str, str] | None = None,
                variant: str | None = None) -> LoadedRecipe:
    """The recipe (its first variant, or ``variant``), raising RecipeError with every loading problem."""
    return load_recipes(file, args, variant)[0]


def _salvage(data: dict, exc):
    """The recipe with its invalid parts replaced by neutral ones, for further checking.

    Returns (recipe or None, partial): None when the remaining data still fails.
    """
    from pydantic import ValidationError

    data = dict(data)
    bad_links, bad_joints, bad_top = set(), set(), set()
    bad_entries: dict[str, set] = {}
    for err in exc.errors(include_url=False):
        loc = err["loc"]
        if len(loc) >= 2 and loc[0] == "links":
            bad_links.add(loc[1])
        elif len(loc) >= 2 and loc[0] == "joints":
            bad_joints.add(loc[1])
        elif len(loc) >= 2 and loc[0] in ("materials", "sensors", "actuators", "worlds") \
                and isinstance(data.get(loc[0]), dict):
            bad_entries.setdefault(loc[0], set()).add(loc[1])
        elif loc:
            bad_top.add(loc[0])
        else:
            return None, True
    for section, names in bad_entries.items():
        data[section] = {k: v for k, v in data[section].items() if k not in names}
    if "robot" in bad_top:
        data["robot"] = "robot"
        bad_top.discard("robot")
    for key in bad_top:
        if key in ("links", "joints", "materials") and not isinstance(data.get(key), dict):
            data[key] = {}
        elif key not in ("links", "joints", "materials"):
            data.pop(key, None)
    dropped = False
    if isinstance(data.get("links"), dict):
        data["links"] = {k: ({} if k in bad_links else v) for k, v in data["links"].items()}
    if isinstance(data.get("joints"), dict):
        joints = {}
        for name, j in data["joints"].items():
            if name not in bad_joints:
                joints[name] = j
            elif isinstance(j, dict) and isinstance(j.get("parent"), str) and isinstance(j.get("child"), str):
                joints[name] = {"type": "fixed", "parent": j["parent"], "child": j["child"]}
            else:
                dropped = True
        data["joints"] = joints
    try:
        return Recipe.model_validate(data), True if not dropped else "tree"
    except ValidationError:
        return None, True
