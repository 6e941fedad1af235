"""Expand a xacro file in-process, sandboxed for untrusted input.

xacro (2.1.1, the ROS 2 flavour from PyPI) is used as a library (docs/libraries.md, section 2):
``process_file``, never ``process()``; its state is module-global, so one expansion runs
at a time (a lock) and every patch is undone afterwards.

The sandbox blocks only what would run code, read outside the allowed folders or never end;
ordinary xacro (any macro parameter or property name, block parameters, namespaces,
``xacro.load_yaml``, ``$(dirname)``, ``$(arg)``, math) works as with ``xacro`` itself.

- **Code.** xacro evaluates ``${...}`` with Python's ``eval`` over its symbol table (no
  builtins) and ``$(eval ...)`` with Python's *full* builtins, so a xacro file can run
  ``exec('import os; ...', {})``.  Here every expression is parsed first and refused when it
  names a dunder (``__x``) or reaches an attribute that leads to code, frames or arbitrary
  attributes (``x._y``, ``.format``, ``.mro``, ...); ``$(eval ...)`` runs with a small set
  of harmless builtins; ``python.type`` and ``python.vars`` are removed from the symbols.
  A name is looked up only in the file's own symbols, so a macro parameter called ``type``
  or a property ``_tokens_`` is fine.
- **Reads.** Includes, ``xacro.load_yaml`` and every file opened go through
  :class:`robotkit.paths.ReadPolicy`: the input's project folder and the declared package
  paths.  ``$(find PKG)`` and ``$(find-pkg-share PKG)`` resolve only declared packages.
- **Environment.** ``$(optenv NAME default)`` gives its default and ``$(env NAME)`` is an
  error: an imported recipe does not depend on the environment of whoever imported it
  (pass such values as ``--arg``).
- **Limits.** An expansion stops after :data:`TIME_LIMIT` seconds; integer powers, shifts and
  repetitions with results above :data:`MAX_BITS` bits or :data:`MAX_ITEMS` items, and
  ranges longer than :data:`MAX_ITEMS`, are refused (``${9**9**9}``).

Every error names the file and the line of the element being expanded (xacro itself only
names the file): the parser records each element's line, kept through macro cloning.
"""

from __future__ import annotations

import ast
import contextlib
import io
import math
import os
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from robotkit.errors import Problem, RobotkitError, display_path
from robotkit.paths import ReadPolicy

_LOCK = threading.Lock()

TIME_LIMIT = 60.0
"""Seconds one expansion may take."""
MAX_BITS = 1 << 16
"""Largest integer (in bits) an expression may compute."""
MAX_ITEMS = 1 << 22
"""Longest string, list or range an expression may build."""

# names that must never be called or reached from an expression
DENIED_NAMES = frozenset({
    "exec", "eval", "compile", "open", "input", "breakpoint", "help", "exit", "quit",
    "getattr", "setattr", "delattr", "hasattr", "vars", "dir", "globals", "locals", "type",
    "object", "super", "memoryview", "classmethod", "staticmethod", "property",
})
# attributes that lead from a value to code, frames or arbitrary attributes (a YAML key such
# as ``type`` or ``object`` read as ``cfg.joint.type`` is the file's own data)
DENIED_ATTRS = frozenset({
    "exec", "eval", "compile", "open", "breakpoint", "getattr", "setattr", "delattr", "globals", "locals", "vars",
}) | frozenset({
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


def check_expression(expr: str, defined=lambda name: False) -> None:
    """Raise :class:`UnsafeExpression` unless ``expr`` is a harmless Python expression.

    ``defined(name)`` says whether the file itself defines ``name`` (a property, a macro
    parameter, an argument): such a name is the file's own value, whatever it is called.
    """
    try:
        tree = ast.parse(expr.strip(), mode="eval")
    except SyntaxError:
        return  # xacro reports the syntax error itself
    found = []  # (position of the name's end, reason): report the first in reading order
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            name = node.id
            if not name.startswith("__") and defined(name):
                continue
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


class ExpansionLimit(Exception):
    """The expansion would take too long or build too large a value."""


class _Limits:
    """Arithmetic that refuses huge results, and the expansion's deadline."""

    def __init__(self, seconds: float):
        self.deadline = time.monotonic() + seconds
        self.seconds = seconds

    def tick(self):
        if time.monotonic() > self.deadline:
            raise ExpansionLimit(f"the expansion takes longer than {self.seconds:g} s")

    @staticmethod
    def _bits(x) -> float:
        return abs(x).bit_length() if isinstance(x, int) and not isinstance(x, bool) else 0

    def pow(self, a, b):
        if isinstance(a, int) and isinstance(b, int) and b > 0 and abs(a) > 1:
            if b * math.log2(abs(a)) > MAX_BITS:
                raise ExpansionLimit(f"{a}**{b} has more than {MAX_BITS} bits")
        return a ** b

    def mul(self, a, b):
        for seq, n in ((a, b), (b, a)):
            if isinstance(seq, (str, list, tuple, bytes)) and isinstance(n, int) and len(seq) * n > MAX_ITEMS:
                raise ExpansionLimit(f"a repetition of more than {MAX_ITEMS} items")
        if self._bits(a) + self._bits(b) > MAX_BITS:
            raise ExpansionLimit(f"a product of more than {MAX_BITS} bits")
        return a * b

    def lshift(self, a, b):
        if isinstance(b, int) and b + self._bits(a) > MAX_BITS:
            raise ExpansionLimit(f"a shift beyond {MAX_BITS} bits")
        return a << b

    def range(self, *args):
        r = range(*args)
        if len(r) > MAX_ITEMS:
            raise ExpansionLimit(f"a range of more than {MAX_ITEMS} items")
        return r


_OPS = {ast.Pow: "__rk_pow", ast.Mult: "__rk_mul", ast.LShift: "__rk_lshift"}


class _Guard(ast.NodeTransformer):
    """``a ** b``, ``a * b``, ``a << b`` become calls of the :class:`_Limits` checks."""

    def visit_BinOp(self, node):
        self.generic_visit(node)
        fn = _OPS.get(type(node.op))
        if fn is None:
            return node
        return ast.copy_location(ast.Call(ast.Name(fn, ast.Load()), [node.left, node.right], []), node)


def _compile_guarded(expr: str):
    tree = _Guard().visit(ast.parse(expr.strip(), mode="eval"))
    return compile(ast.fix_missing_locations(tree), "<expression>", "eval")


def _guard_symbols(limits: _Limits) -> dict:
    return {"__rk_pow": limits.pow, "__rk_mul": limits.mul, "__rk_lshift": limits.lshift}


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
    blocked: str | None = None  # a read or an environment variable the sandbox refused
    location: tuple[str, int] | None = None  # (file, line) of the element being expanded
    repairs: list[str] = field(default_factory=list)  # warnings: what the expansion read otherwise than xacro 2


class _Blocked(Exception):
    pass


_LOC = "robotkit.location"


class _KeepOnClone:
    """minidom user-data handler: a cloned or imported node keeps the source location."""

    def handle(self, operation, key, data, src, dst):
        if dst is not None:
            dst.setUserData(key, data, self)


_KEEP = _KeepOnClone()


def _parse_with_lines(source, file: str):
    """minidom parse that records (file, line) on every element (xacro's own parse does not)."""
    from xml.dom import expatbuilder

    class Builder(expatbuilder.ExpatBuilderNS):
        def start_element_handler(self, name, attributes):
            super().start_element_handler(name, attributes)
            self.curNode.setUserData(_LOC, (file, self._parser.CurrentLineNumber), _KEEP)

    builder = Builder()
    if isinstance(source, str):
        return builder.parseString(source)
    return builder.parseFile(source)


LEGACY_TAGS = ("arg", "property", "include", "if", "unless", "insert_block", "macro")
"""The tags ROS 1 xacro (before Noetic) read without the ``xacro:`` prefix, with a deprecation
warning and a sed command that adds it; xacro 2 passes them through as URDF, so such a property is
never defined (KUKA KR210's ``<property name="deg" .../>``)."""


def prefix_legacy_tags(doc, file: str) -> list[str]:
    """Give the ``xacro:`` prefix to LEGACY_TAGS without one, in place, in a file that declares
    the xacro namespace (one obvious reading: ROS 1 xacro's); one warning per tag name, with the
    line of its first use and how many."""
    root = doc.documentElement
    uri = root.getAttribute("xmlns:xacro") if root is not None else ""
    if not uri:
        return []
    found: dict[str, list[int]] = {}
    for node in list(root.getElementsByTagName("*")):
        if node.prefix is None and node.tagName in LEGACY_TAGS:
            loc = node.getUserData(_LOC)
            found.setdefault(node.tagName, []).append(loc[1] if loc else 0)
            doc.renameNode(node, uri, "xacro:" + node.tagName)
    out = []
    for tag, lines in found.items():
        times = f" ({len(lines)} tags)" if len(lines) > 1 else ""
        out.append(f"{_show(file)}:{lines[0]}: xacro: <{tag}> without the xacro: prefix{times} read as "
                   f"<xacro:{tag}>, as ROS 1 xacro read it (xacro 2 leaves it unexpanded)")
    return out


def _node_location(node) -> tuple[str, int] | None:
    while node is not None:
        get = getattr(node, "getUserData", None)
        loc = get(_LOC) if get is not None else None
        if loc is not None:
            return loc
        node = getattr(node, "parentNode", None)
    return None


def _failing_location(tb, eval_all_code) -> tuple[str, int] | None:
    """The element xacro was expanding when it failed: ``node`` in the innermost ``eval_all``."""
    loc = None
    while tb is not None:
        if tb.tb_frame.f_code is eval_all_code:
            found = _node_location(tb.tb_frame.f_locals.get("node"))
            loc = found or loc
        tb = tb.tb_next
    return loc


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


def expand(path: str | os.PathLike, package_paths: dict[str, str], args: dict[str, str] | None = None,
           roots=(), time_limit: float | None = None) -> Expanded:
    """Expand the xacro file ``path``; ``$(find PKG)`` looks PKG up in ``package_paths``.

    Files are read only inside ``path``'s project, ``roots`` and the package folders
    (:class:`robotkit.paths.ReadPolicy`).  Raises RobotkitError (one line, naming the file
    and line) for a missing package, a missing argument, an unsafe expression, a blocked read,
    a limit, or any other xacro error.
    """
    import xacro  # heavy, and it replaces minidom's writer for the whole process: only when expanding

    path = Path(path).absolute()
    if not path.is_file():
        raise RobotkitError(Problem("file not found", file=str(path)))
    sandbox = _Sandbox(path, dict(package_paths), dict(args or {}), roots,
                       _Limits(TIME_LIMIT if time_limit is None else time_limit))
    stderr = io.StringIO()
    with _LOCK, sandbox.installed():
        with contextlib.redirect_stderr(stderr):
            doc = sandbox.process()
        includes = sorted({os.path.abspath(f) for f in xacro.all_includes})
    warnings = sandbox.state.repairs + [
        f"{_show(path)}: xacro: {line.strip()}" for line in stderr.getvalue().splitlines()
        if line.strip() and not line.startswith(" ") and "when processing file" not in line]
    return Expanded(_document_text(doc), includes, warnings)


def _document_text(doc) -> str:
    """The expanded document as URDF text, without xacro's banner comments."""
    root = doc.documentElement
    for el in [root, *root.getElementsByTagName("*")]:  # xacro:attribute leaves its value a number, on which
        for attr in el.attributes.values():  # xacro's writer fails; every other attribute is str() of its value
            if not isinstance(attr.value, str):
                attr.value = str(attr.value)
    return '<?xml version="1.0"?>\n' + root.toxml() + "\n"


class _Sandbox:
    """One expansion's replacements for xacro's functions (reads, substitutions, evaluation)
    and what they found (:class:`_State`).  :meth:`installed` puts them in place and restores
    xacro's own afterwards."""

    def __init__(self, path: Path, packages: dict[str, str], args: dict[str, str], roots, limits: _Limits):
        import xacro
        import xacro.substitution_args as sa

        self.path, self.packages, self.args, self.limits = path, packages, args, limits
        self.state = _State()
        self.policy = ReadPolicy.for_file(path, extra_roots=roots, packages=packages)
        self.guards = _guard_symbols(limits)
        self.original_abs = xacro.abs_filename_spec
        self.original_parse = xacro.parse
        self.original_resolve = sa.resolve_args
        self.original_eval_all = xacro.eval_all

    # ---- substitutions and reads

    def find(self, pkg):
        try:
            return self.packages[pkg]
        except KeyError:
            self.state.missing = pkg
            raise _MissingPackage(pkg) from None

    def env(self, name):
        self.state.blocked = (f"$(env {name}) is blocked: an imported file does not read the environment "
                              f"(give the value as an argument, or use $(optenv {name} DEFAULT))")
        raise _Blocked(name)

    @staticmethod
    def optenv(name, default=""):
        return default

    def allowed(self, file: str) -> str:
        problem = self.policy.problem(os.path.normpath(file))
        if problem is not None:
            self.state.blocked = f"reading {problem.message}"
            raise _Blocked(file)
        return file

    def abs_filename_spec(self, spec):
        return self.allowed(self.original_abs(spec))

    def parse(self, inp, filename=None):
        import xacro

        if inp is None:
            full = os.path.join(xacro.root_dir or "", filename) if not os.path.isabs(filename) else filename
            self.allowed(full)
            try:
                f = open(full, "rb")
            except OSError as e:
                xacro.filestack.pop()
                raise xacro.XacroException(f"{e.strerror}: {e.filename}", exc=e) from None
            with f:
                doc = _parse_with_lines(f, full)
            self.state.repairs += prefix_legacy_tags(doc, full)
            return doc
        if isinstance(inp, str):
            return _parse_with_lines(inp, xacro.filestack[-1] if xacro.filestack else str(self.path))
        return self.original_parse(inp, filename)

    def resolve_args(self, arg_str, context=None, filename=None):
        import xacro

        if arg_str and "$(find-pkg-share " in arg_str:
            arg_str = arg_str.replace("$(find-pkg-share ", "$(find ")
        if context is not None and xacro.filestack:  # xacro 2.1 never tells $(dirname) the file
            context["filename"] = xacro.filestack[-1]
        return self.original_resolve(arg_str, context, filename)

    # ---- evaluation

    def eval_all(self, node, macros, symbols):
        self.limits.tick()
        return self.original_eval_all(node, macros, symbols)

    def safe_eval(self, expr, globals, locals=None):
        self.limits.tick()
        try:
            check_expression(expr, lambda name: name in globals)
        except UnsafeExpression as exc:
            self.state.unsafe = (expr.strip(), str(exc))
            raise
        code = _compile_guarded(expr)
        dict.update(globals, __builtins__={}, **self.guards)  # disable default builtins (as xacro does)
        return eval(code, globals, locals)

    def eval(self, s, context):
        """``$(eval ...)``: xacro's own version evaluates with Python's full builtins (see the module docstring)."""
        import xacro.substitution_args as sa

        self.limits.tick()
        if "arg" not in context:
            context["arg"] = {}

        def arg(name):
            return sa.convert_value(sa._eval_arg(name, args=context["arg"]), "auto")

        def dirname():
            return sa._eval_dirname(context["filename"])

        functions = {"arg": arg, "dirname": dirname}
        functions.update({k: v for k, v in sa._eval_dict.items() if not k.startswith("_")})
        functions.update(find=self.find, env=self.env, optenv=self.optenv)
        names = sa._DictWrapper(context["arg"], functions)
        try:
            check_expression(s, lambda name: name in context["arg"] or name in functions)
        except UnsafeExpression as exc:
            self.state.unsafe = (s.strip(), str(exc))
            raise
        builtins = dict(SAFE_BUILTINS, range=self.limits.range)
        return str(eval(_compile_guarded(s), {"__builtins__": builtins, **self.guards}, names))

    def symbols(self):
        """xacro's global symbols without ``python.type`` and ``python.vars``, with a bounded range."""
        import xacro

        symbols = xacro.create_global_symbols()
        python_ns = symbols.get("python")
        if python_ns is not None:
            for name in ("vars", "type"):
                dict.pop(python_ns, name, None)
            if "range" in python_ns:
                dict.__setitem__(python_ns, "range", self.limits.range)
        if "range" in symbols:
            symbols["range"] = self.limits.range
        return symbols

    # ---- installing and running

    @contextlib.contextmanager
    def installed(self):
        """xacro with this sandbox's functions in place; everything restored afterwards."""
        import xacro
        import xacro.substitution_args as sa
        import yaml

        replacements = {
            (xacro, "safe_eval"): self.safe_eval, (xacro, "_global_symbols"): self.symbols(),
            (xacro, "abs_filename_spec"): self.abs_filename_spec, (xacro, "parse"): self.parse,
            (xacro, "eval_all"): self.eval_all, (sa, "_eval"): self.eval, (sa, "_eval_find"): self.find,
            (sa, "_eval_env"): self.env, (sa, "_eval_optenv"): self.optenv, (sa, "resolve_args"): self.resolve_args,
        }
        saved = {key: getattr(*key) for key in replacements}
        saved_dict = {k: sa._eval_dict.get(k) for k in ("find", "env", "optenv")}
        # xacro.load_yaml registers its unit tags (!degrees...) on yaml.SafeLoader, in place
        own = yaml.SafeLoader.__dict__.get("yaml_constructors")
        saved_constructors = dict(own) if own is not None else None
        try:
            for (module, name), value in replacements.items():
                setattr(module, name, value)
            sa._eval_dict.update(find=self.find, env=self.env, optenv=self.optenv)
            xacro.all_includes.clear()
            yield
        finally:
            for (module, name), value in saved.items():
                setattr(module, name, value)
            for k, v in saved_dict.items():
                if v is None:
                    sa._eval_dict.pop(k, None)
                else:
                    sa._eval_dict[k] = v
            if saved_constructors is None:
                if "yaml_constructors" in yaml.SafeLoader.__dict__:
                    del yaml.SafeLoader.yaml_constructors
            else:
                yaml.SafeLoader.yaml_constructors = saved_constructors
            xacro.all_includes.clear()
            xacro.init_stacks(None)

    def process(self):
        """xacro's expansion of the file (the sandbox installed); its errors as RobotkitError."""
        import xml.parsers.expat

        import xacro
        import xacro.substitution_args as sa
        import yaml

        try:
            return xacro.process_file(str(self.path), mappings=self.args)
        except (xacro.XacroException, sa.SubstitutionException, _MissingPackage, UnsafeExpression,
                _Blocked, ExpansionLimit, xml.parsers.expat.ExpatError, OSError, NameError, KeyError,
                TypeError, ValueError, SyntaxError, AttributeError, ZeroDivisionError, IndexError,
                OverflowError, MemoryError, yaml.YAMLError, RecursionError) as exc:
            where = xacro.filestack[-1] if xacro.filestack and xacro.filestack[-1] else str(self.path)
            self.state.location = _failing_location(exc.__traceback__, self.original_eval_all.__code__)
            raise RobotkitError(_problem(exc, self.state, where, self.path)) from None


def _show(path) -> str:
    return display_path(str(path))


def _problem(exc: BaseException, state: _State, where: str, top: Path) -> Problem:
    import xml.parsers.expat

    line, parsing = None, where  # xacro's file stack: the file being parsed
    if state.location is not None:
        where, line = state.location
    limit = exc if isinstance(exc, ExpansionLimit) else getattr(exc, "exc", None)
    if isinstance(limit, ExpansionLimit):
        return Problem(f"xacro: expansion stopped: {limit}", file=where, line=line)
    if state.blocked is not None:
        return Problem(state.blocked, file=where, line=line)

    if state.unsafe is not None:
        expr, reason = state.unsafe
        if len(expr) > 80:
            expr = expr[:77] + "..."
        return Problem(f"refusing to evaluate xacro expression '{expr}': {reason} "
                       "(an imported file may only compute values)", file=where, line=line)
    if state.missing is not None:
        pkg = state.missing
        return Problem(f"package '{pkg}' not found; give --package-path {pkg}=DIR", file=where, line=line)
    if isinstance(exc, xml.parsers.expat.ExpatError):
        return Problem(f"not well-formed XML: {xml.parsers.expat.ErrorString(exc.code)}",
                       file=parsing, line=exc.lineno)
    if isinstance(exc, FileNotFoundError):
        missing = exc.filename or str(exc)
        if os.path.abspath(str(missing)) == str(top):
            return Problem("file not found", file=str(top))
        return Problem(f"file not found: {_show(missing)}", file=where, line=line)
    if isinstance(exc, RecursionError):
        return Problem("xacro: expansion recurses without end (a macro that calls itself?)", file=where, line=line)
    inner = getattr(exc, "exc", None)
    import xacro.substitution_args as sa

    if isinstance(exc, sa.ArgException) or isinstance(inner, sa.ArgException):
        name = str(inner or exc)
        return Problem(f"xacro argument '{name}' is not set; give --arg {name}:=VALUE", file=where, line=line)
    if isinstance(inner, FileNotFoundError):
        return Problem(f"file not found: {_show(inner.filename or str(inner))}", file=where, line=line)
    message = " ".join(str(exc).split())
    if not message:
        message = type(exc).__name__
    return Problem(f"xacro: {message}", file=where, line=line)
