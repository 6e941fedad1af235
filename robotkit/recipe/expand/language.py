"""The recipe language's pieces shared by the whole recipe and by the parts it instantiates.

Where a tree was written (:class:`Source`), the expansion's problems and part files
(:class:`Context`), ``${...}`` in any scalar, ``args:`` (declared with defaults,
bound to given values), ``values:`` and ``if:``.  :mod:`robotkit.recipe.expand` runs the
stage with them; :mod:`robotkit.recipe.expand.parts` expands ``instances:`` with them.
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass

from robotkit.errors import Problem
from robotkit.recipe.expand import expr as _expr
from robotkit.recipe.expand import units as _units

ITEM_SECTIONS = ("links", "joints", "sensors", "actuators")
IDENT_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
WHOLE_RE = re.compile(r"^\$\{([^{}]*)\}$")
PART_RE = re.compile(r"\$\$\{|\$\{([^{}]*)\}")


def dotted(path) -> str:
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else ("." if out else "") + str(part)
    return out


@dataclass
class Source:
    """Where a tree was written: a file's marks and the key path of the tree in that file."""

    where: dict  # key path -> (file, line), of the file (or merged recipe) the tree comes from
    prefix: tuple = ()
    via: str = ""  # " (in instance ...)" for trees expanded inside a part instance

    def sub(self, *keys) -> "Source":
        return Source(self.where, self.prefix + keys, self.via)

    def locate(self, rel=()):
        path = self.prefix + tuple(rel)
        for n in range(len(path), -1, -1):
            if path[:n] in self.where:
                return self.where[path[:n]]
        return None, None

    def problem(self, rel, message: str) -> Problem:
        file, line = self.locate(rel)
        return Problem(message + self.via, file=file, line=line, key=dotted(self.prefix + tuple(rel)) or None)


class Context:
    """Problems and the part definitions visible while expanding."""

    def __init__(self, read_yaml, problems: list[Problem], reads=None):
        self.read_yaml = read_yaml  # file -> (data, marks) (robotkit.recipe.load._read_yaml)
        self.problems = problems
        self.reads = reads  # where part files may be read (robotkit.paths.ReadPolicy)
        self.part_files: dict = {}  # resolved path -> (data, marks)
        self.failures = 0  # expressions that could not be evaluated (reported or quiet)
        self.quiet: set = set()  # (file, line, key) of values left unevaluated by a failure reported elsewhere

    def report(self, src: Source, rel, message: str):
        self.problems.append(src.problem(rel, message))


# ---------------------------------------------------------------- expressions


def evaluate_tree(node, scope: dict, ctx: Context, src: Source, rel=()):
    """A copy of ``node`` with every ``${...}`` replaced by its value."""
    if isinstance(node, dict):
        return {k: evaluate_tree(v, scope, ctx, src, rel + (k,)) for k, v in node.items()}
    if isinstance(node, list):
        return [evaluate_tree(v, scope, ctx, src, rel + (i,)) for i, v in enumerate(node)]
    if isinstance(node, str) and "${" in node:
        return evaluate_string(node, scope, ctx, src, rel)
    return node


UNITS = {unit: to_si for unit, (_, to_si) in _units.UNITS.items()}


def evaluate_string(text: str, scope: dict, ctx: Context, src: Source, rel):
    m = WHOLE_RE.match(text.strip())
    try:
        if m and text.strip() == text:
            return _expr.evaluate(m.group(1), scope, UNITS, _units.KNOWN)
        out, pos = [], 0
        for part in PART_RE.finditer(text):
            out.append(text[pos:part.start()])
            if part.group(0) == "$${":
                out.append("${")
            else:
                current = part.group(1)
                out.append(_expr.show(_expr.evaluate(current, scope, UNITS, _units.KNOWN)))
            pos = part.end()
        out.append(text[pos:])
        result = "".join(out)
        if "${" in result.replace("$${", "") and "${" in text[pos:]:
            raise _expr.ExprError("'${' without its closing '}'")
        return result
    except _expr.Quiet:
        ctx.failures += 1
        p = src.problem(rel, "")
        ctx.quiet.add((p.file, p.line, p.key))
        return text
    except _expr.ExprError as exc:
        ctx.failures += 1
        ctx.report(src, rel, f"in {text.strip()}: {exc}")
        return text


def failed_here(ctx: Context, src: Source, rel) -> bool:
    """Whether an expression written at ``rel`` of ``src`` failed (reported or quiet)."""
    p = src.problem(rel, "")
    where = (p.file, p.line, p.key)
    return where in ctx.quiet or any((q.file, q.line, q.key) == where for q in ctx.problems)


def evaluated(node, scope: dict, ctx: Context, src: Source, rel=()):
    """:func:`evaluate_tree` of a named value: :data:`expr.FAILED` when an expression in it
    failed (its uses then fail quietly instead of adding knock-on problems)."""
    before = ctx.failures
    value = evaluate_tree(node, scope, ctx, src, rel)
    return _expr.FAILED if ctx.failures > before else value


# ---------------------------------------------------------------- arguments


def _kind(default):
    """The type an argument takes, from its default: bool, number, text, or a quantity's dimension."""
    if isinstance(default, bool):
        return "bool"
    if isinstance(default, (int, float)):
        return "number"
    if isinstance(default, str):
        try:
            q = _units.parse(default)
        except ValueError:
            q = None
        if q is not None:
            return q[1]
    return "text"


def coerce(value, kind: str, from_text: bool):
    """``value`` as an argument of ``kind``; raises ValueError with the reason."""
    if from_text and kind != "text":
        import yaml

        try:
            value = yaml.safe_load(value) if value.strip() else value
        except yaml.YAMLError:
            pass
    if kind == "bool":
        if not isinstance(value, bool):
            raise ValueError(f"must be true or false (got {value!r})")
        return value
    if kind == "text":
        return value if isinstance(value, str) else _expr.show(value)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return value
    if isinstance(value, str) and kind != "number":
        try:
            q = _units.parse(value)
        except ValueError as exc:
            raise ValueError(str(exc)) from None
        if q is not None:
            if q[1] != kind:
                raise ValueError(f"must be {_units.ARTICLE[kind]} (got '{value}')")
            return q[0]
    want = "a number" if kind == "number" else f"{_units.ARTICLE[kind]} (a number in SI units or with a unit)"
    raise ValueError(f"must be {want} (got {value!r})")


def _si(value):
    """A quantity string (``5 cm``) as its SI number; anything else unchanged."""
    if isinstance(value, str):
        try:
            q = _units.parse(value)
        except ValueError:
            return value
        if q is not None:
            return q[0]
    return value


def declare_args(block, scope: dict, ctx: Context, src: Source):
    """{name: (kind, default value, choices)} of an ``args:`` block (defaults may use earlier args)."""
    out = {}
    if block is None:
        return out
    if not isinstance(block, dict):
        ctx.report(src, (), f"must be a mapping of argument names to defaults (got {block!r})")
        return out
    local = dict(scope)
    for name, spec in block.items():
        if not IDENT_RE.match(name) or name in _expr.FUNCTIONS or name in _expr.CONSTANTS:
            ctx.report(src, (name,), "an argument name must be a plain identifier (letters, digits, '_'), "
                                     "not a function or constant name")
            continue
        choices = None
        if isinstance(spec, dict):
            extra = [k for k in spec if k not in ("default", "description", "choices")]
            if extra:
                ctx.report(src, (name, extra[0]), "unknown key (expected one of: default, description, choices)")
            if "default" not in spec:
                ctx.report(src, (name,), "an argument needs a 'default'")
                continue
            default = spec["default"]
            choices = spec.get("choices")
            where = (name, "default")
            if choices is not None and not isinstance(choices, list):
                ctx.report(src, (name, "choices"), f"must be a list (got {choices!r})")
                choices = None
        else:
            default, where = spec, (name,)
        if isinstance(default, (dict, list)) or default is None:
            ctx.report(src, where, f"a default must be a number, true/false or text (got {default!r})")
            continue
        default = evaluated(default, local, ctx, src, where)
        if default is _expr.FAILED:
            out[name] = ("text", default, None)
            local[name] = default
            continue
        kind = _kind(default)
        value = _si(default) if kind not in ("bool", "number", "text") else default
        if choices is not None and default not in choices and value not in choices:
            ctx.report(src, where, f"the default {default!r} is not one of the choices")
        out[name] = (kind, value, choices)
        local[name] = value
    return out


def bind_args(declared: dict, given: dict, ctx: Context, what: str, locate, from_text: bool,
              base: dict | None = None) -> dict:
    """Argument values: the defaults with ``given`` ({name: value}) applied and checked.

    ``locate(name)`` -> (Source, rel) where the given value was written; unknown names and wrong
    types are problems."""
    values = dict(base) if base is not None else {name: v for name, (kind, v, choices) in declared.items()}
    for name, value in given.items():
        src, rel = locate(name)
        if name not in declared:
            close = difflib.get_close_matches(name, list(declared), n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else (
                f" (arguments: {', '.join(declared)})" if declared else f" ({what} declares no arguments)")
            ctx.report(src, rel, f"unknown argument '{name}' of {what}{hint}")
            continue
        kind, _, choices = declared[name]
        if failed_here(ctx, src, rel):
            values[name] = _expr.FAILED  # its expression's problem is reported: no knock-on ones
            continue
        try:
            v = coerce(value, kind, from_text)
        except ValueError as exc:
            ctx.report(src, rel, f"argument '{name}' {exc}")
            continue
        if choices is not None and v not in choices and value not in choices:
            ctx.report(src, rel, f"argument '{name}' must be one of {', '.join(map(repr, choices))} (got {value!r})")
            continue
        values[name] = v
    return values


def declare_values(block, scope: dict, ctx: Context, src: Source) -> dict:
    """The named values of a ``values:`` block, in order (each may use the ones before it)."""
    if block is None:
        return scope
    if not isinstance(block, dict):
        ctx.report(src, (), f"must be a mapping of names to values (got {block!r})")
        return scope
    scope = dict(scope)
    for name, v in block.items():
        if not IDENT_RE.match(name) or name in _expr.FUNCTIONS or name in _expr.CONSTANTS:
            ctx.report(src, (name,), "a value name must be a plain identifier (letters, digits, '_'), "
                                     "not a function or constant name")
            continue
        scope[name] = _si(evaluated(v, scope, ctx, src, (name,)))
    return scope


# ---------------------------------------------------------------- conditions


def keep(item, ctx: Context, src: Source, rel) -> bool:
    """False when the item's ``if:`` is false; the key is removed from the item."""
    if not isinstance(item, dict) or "if" not in item:
        return True
    cond = item.pop("if")
    if isinstance(cond, bool):
        return cond
    if isinstance(cond, str) and "${" in cond:
        return True  # the expression's own problem is already reported
    ctx.report(src, rel + ("if",), f"must be true or false (got {cond!r})")
    return True


