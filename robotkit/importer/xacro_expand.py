"""Expand a xacro file in-process, with ``$(find PKG)`` resolved through a package map,
and with xacro's expression evaluation locked down for untrusted input.

xacro (2.1.1, the ROS 2 flavour from PyPI) is used as a library (LIBRARIES.md section 2):
``process_file``, never ``process()``; its state is module-global, so one expansion runs
at a time (a lock) and every patch is undone afterwards.

Untrusted files.  xacro evaluates ``${...}`` with Python's ``eval`` over a table of exposed
names and rejects names that start with ``__``; ``$(eval ...)`` only rejects the text
``__`` and then evaluates with Python's *full* builtins, so a xacro file can run
``exec('import os; ...', {})`` (measured: it creates files).  While a file is expanded
here:

- every expression (``${...}``, ``$(eval ...)``, the ``!degrees``-style YAML units) is
  parsed and refused unless it is a plain expression over names and attributes that do
  not start with ``_`` and that are not introspection or code-execution hooks (``exec``,
  ``eval``, ``open``, ``getattr``, ``vars``, ``type``, ``format``, frame and code
  attributes, ...);
- ``$(eval ...)`` runs with a small set of harmless builtins instead of all of them;
- the symbol table of ``${...}`` lacks ``python.vars`` and ``python.type``.

What stays possible is what xacro's own restricted evaluation allows: arithmetic, the
math functions, ``xacro.load_yaml`` (YAML safe-loaded), reading files through
``xacro:include`` and ``$(env ...)``.  A file can still make expansion slow or large
(``${9**9**9}``); run imports of untrusted files with a time limit.
"""

from __future__ import annotations

import ast
import contextlib
import io
import os
import threading
from dataclasses import dataclass, field
from pathlib import Path

from robotkit.errors import Problem, RobotkitError

_LOCK = threading.Lock()

# names that must never be called or reached from an expression
DENIED_NAMES = frozenset({
    "exec", "eval", "compile", "open", "input", "breakpoint", "help", "exit", "quit",
    "getattr", "setattr", "delattr", "hasattr", "vars", "dir", "globals", "locals", "type",
    "object", "super", "memoryview", "classmethod", "staticmethod", "property",
})
# attributes that lead from a value to code, frames or arbitrary attributes
DENIED_ATTRS = DENIED_NAMES | frozenset({
    "format", "format_map", "mro", "gi_frame", "gi_code", "gi_yieldfrom", "cr_frame", "cr_code",
    "cr_await", "ag_frame", "ag_code", "ag_await", "f_back", "f_globals", "f_locals", "f_builtins",
    "f_code", "f_trace", "tb_frame", "tb_next", "co_code", "co_consts", "func_globals", "func_code",
    "im_func", "im_self", "system", "popen", "spawn", "fork", "load_module", "exec_module",
})
# builtins for $(eval ...): what xacro's ${...} exposes, minus introspection
SAFE_BUILTINS = {name: __builtins__[name] if isinstance(__builtins__, dict) else getattr(__builtins__, name)
                 for name in ("list", "dict", "map", "len", "str", "float", "int", "bool", "min", "max",
                              "round", "abs", "all", "any", "sorted", "range", "sum", "tuple", "zip",
                              "enumerate", "reversed", "set", "frozenset", "divmod", "isinstance", "ord",
                              "repr", "slice", "filter", "complex", "hash", "True", "False", "None")}


class UnsafeExpression(Exception):
    """An expression in the file tried something the import does not allow."""


class _MissingPackage(Exception):
    def __init__(self, package: str):
        super().__init__(package)
        self.package = package


def check_expression(expr: str) -> None:
    """Raise :class:`UnsafeExpression` unless ``expr`` is a harmless Python expression."""
    try:
        tree = ast.parse(expr.strip(), mode="eval")
    except SyntaxError:
        return  # xacro reports the syntax error itself
    found = []  # (position of the name's end, reason): report the first in reading order
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            name = node.id
        elif isinstance(node, ast.Attribute):
            name = node.attr
        elif isinstance(node, ast.NamedExpr):
            found.append(((node.lineno, node.col_offset), "assignment expressions ':=' are not allowed"))
            continue
        else:
            continue
        where = (node.end_lineno or 0, node.end_col_offset or 0)
        if name.startswith("_"):
            found.append((where, f"names starting with '_' ({name!r}) are not allowed"))
        elif name in (DENIED_NAMES if isinstance(node, ast.Name) else DENIED_ATTRS):
            found.append((where, f"{name!r} is not allowed"))
    if found:
        raise UnsafeExpression(min(found)[1])


@dataclass
class Expanded:
    """The result of expanding one xacro file."""

    text: str
    """The URDF text (the expanded document, whitespace as in the sources)."""
    includes: list[str] = field(default_factory=list)
    """Every file xacro read besides the input (includes, load_yaml'd files)."""
    warnings: list[str] = field(default_factory=list)


@dataclass
class _State:
    missing: str | None = None
    unsafe: tuple[str, str] | None = None  # (expression, reason)


def check_package_paths(package_paths: dict[str, str]) -> dict[str, str]:
    """Absolute package folders; a problem for each that is not a folder."""
    out, problems = {}, []
    for name, folder in package_paths.items():
        path = Path(folder).expanduser()
        if not path.is_dir():
            problems.append(Problem(f"--package-path {name}={folder}: no such folder"))
            continue
        out[name] = str(path.resolve())
    if problems:
        raise RobotkitError(problems)
    return out


def expand(path: str | os.PathLike, package_paths: dict[str, str], args: dict[str, str] | None = None) -> Expanded:
    """Expand the xacro file ``path``; ``$(find PKG)`` looks PKG up in ``package_paths``.

    Raises RobotkitError (one line, naming the file) for a missing package, a missing
    argument, an unsafe expression or any other xacro error.
    """
    import xml.parsers.expat

    import xacro
    import xacro.substitution_args as sa
    import yaml

    path = Path(path).absolute()
    if not path.is_file():
        raise RobotkitError(Problem("file not found", file=str(path)))
    packages = dict(package_paths)
    args = dict(args or {})
    state = _State()

    def find(pkg):
        try:
            return packages[pkg]
        except KeyError:
            state.missing = pkg
            raise _MissingPackage(pkg) from None

    original_safe_eval = xacro.safe_eval

    def guarded_safe_eval(expr, globals, locals=None):
        try:
            check_expression(expr)
        except UnsafeExpression as exc:
            state.unsafe = (expr.strip(), str(exc))
            raise
        return original_safe_eval(expr, globals, locals)

    def guarded_eval(s, context):
        # xacro's own version evaluates with Python's full builtins (see the module docstring)
        try:
            check_expression(s)
        except UnsafeExpression as exc:
            state.unsafe = (s.strip(), str(exc))
            raise
        if "arg" not in context:
            context["arg"] = {}

        def arg(name):
            return sa.convert_value(sa._eval_arg(name, args=context["arg"]), "auto")

        def dirname():
            return sa._eval_dirname(context["filename"])

        functions = {"arg": arg, "dirname": dirname}
        functions.update({k: v for k, v in sa._eval_dict.items() if not k.startswith("_")})
        functions["find"] = find
        return str(eval(s, {"__builtins__": dict(SAFE_BUILTINS)}, sa._DictWrapper(context["arg"], functions)))

    symbols = xacro.create_global_symbols()
    python_ns = symbols.get("python")
    if python_ns is not None:
        for name in ("vars", "type"):
            dict.pop(python_ns, name, None)

    saved = {
        (xacro, "safe_eval"): xacro.safe_eval,
        (xacro, "_global_symbols"): xacro._global_symbols,
        (sa, "_eval"): sa._eval,
        (sa, "_eval_find"): sa._eval_find,
    }
    saved_find_fn = sa._eval_dict.get("find")
    # xacro.load_yaml registers its unit tags (!degrees...) on yaml.SafeLoader, in place
    own = yaml.SafeLoader.__dict__.get("yaml_constructors")
    saved_constructors = dict(own) if own is not None else None
    stderr = io.StringIO()
    with _LOCK:
        try:
            xacro.safe_eval = guarded_safe_eval
            xacro._global_symbols = symbols
            sa._eval = guarded_eval
            sa._eval_find = find
            sa._eval_dict["find"] = find
            xacro.all_includes.clear()
            with contextlib.redirect_stderr(stderr):
                try:
                    doc = xacro.process_file(str(path), mappings=args)
                except (xacro.XacroException, sa.SubstitutionException, _MissingPackage, UnsafeExpression,
                        xml.parsers.expat.ExpatError, OSError, NameError, KeyError, TypeError, ValueError,
                        SyntaxError, AttributeError, ZeroDivisionError, IndexError, yaml.YAMLError,
                        RecursionError) as exc:
                    where = xacro.filestack[-1] if xacro.filestack and xacro.filestack[-1] else str(path)
                    raise RobotkitError(_problem(exc, state, where, path)) from None
            includes = sorted({os.path.abspath(f) for f in xacro.all_includes})
        finally:
            for (module, name), value in saved.items():
                setattr(module, name, value)
            if saved_find_fn is not None:
                sa._eval_dict["find"] = saved_find_fn
            if saved_constructors is None:
                if "yaml_constructors" in yaml.SafeLoader.__dict__:
                    del yaml.SafeLoader.yaml_constructors
            else:
                yaml.SafeLoader.yaml_constructors = saved_constructors
            xacro.all_includes.clear()
            xacro.init_stacks(None)
    # the document without xacro's banner comments
    root = doc.documentElement
    text = '<?xml version="1.0"?>\n' + root.toxml() + "\n"
    warnings = [f"{_show(path)}: xacro: {line.strip()}" for line in stderr.getvalue().splitlines()
                if line.strip() and not line.startswith(" ") and "when processing file" not in line]
    return Expanded(text, includes, warnings)


def _show(path) -> str:
    from robotkit.errors import display_path

    return display_path(str(path))


def _problem(exc: BaseException, state: _State, where: str, top: Path) -> Problem:
    import xml.parsers.expat

    if state.unsafe is not None:
        expr, reason = state.unsafe
        if len(expr) > 80:
            expr = expr[:77] + "..."
        return Problem(f"refusing to evaluate xacro expression '{expr}': {reason} "
                       "(an imported file may only compute values)", file=where)
    if state.missing is not None:
        pkg = state.missing
        return Problem(f"package '{pkg}' not found; give --package-path {pkg}=DIR", file=where)
    if isinstance(exc, xml.parsers.expat.ExpatError):
        return Problem(f"not well-formed XML: {xml.parsers.expat.ErrorString(exc.code)}",
                       file=where, line=exc.lineno)
    if isinstance(exc, FileNotFoundError):
        missing = exc.filename or str(exc)
        if os.path.abspath(str(missing)) == str(top):
            return Problem("file not found", file=str(top))
        return Problem(f"file not found: {_show(missing)}", file=where)
    if isinstance(exc, RecursionError):
        return Problem("xacro: expansion recurses without end (a macro that calls itself?)", file=where)
    inner = getattr(exc, "exc", None)
    import xacro.substitution_args as sa

    if isinstance(exc, sa.ArgException) or isinstance(inner, sa.ArgException):
        name = str(inner or exc)
        return Problem(f"xacro argument '{name}' is not set; give --arg {name}:=VALUE", file=where)
    if isinstance(inner, FileNotFoundError):
        return Problem(f"file not found: {_show(inner.filename or str(inner))}", file=where)
    message = " ".join(str(exc).split())
    if not message:
        message = type(exc).__name__
    return Problem(f"xacro: {message}", file=where)
