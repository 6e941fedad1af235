"""``${...}`` expressions: a small evaluator over Python's ``ast`` with a whitelist.

No ``eval``: the expression is parsed with ``ast.parse(mode="eval")`` and only
numbers, strings, true/false, names from the scope, arithmetic, comparisons,
``and``/``or``/``not``, ``a if c else b`` and calls of the functions in
:data:`FUNCTIONS` are evaluated.  Sizes are capped (expression length, node
count, exponents, integer size, string length) so no expression can exhaust
the machine.  A number followed by a unit (``1 cm``, ``90deg``) is a quantity: it is
replaced by its SI number before parsing (``${body_width + 1 cm}`` is ``body_width + 0.01``).
"""

from __future__ import annotations

import ast
import difflib
import io
import keyword
import math
import operator
import tokenize

MAX_LENGTH = 500  # characters of one expression
MAX_NODES = 200  # AST nodes of one expression
MAX_EXPONENT = 1000  # |b| in a ** b
MAX_INT_BITS = 1024  # integers beyond 2**1024 are refused
MAX_STRING = 1000  # characters of a string result

CONSTANTS = {"pi": math.pi, "e": math.e, "tau": math.tau, "true": True, "false": False,
             "True": True, "False": False}


def _num(*xs):
    for x in xs:
        if isinstance(x, bool) or not isinstance(x, (int, float)):
            raise ExprError(f"expects numbers (got {x!r})")


def _fn(f, n):
    def call(*args):
        if n is not None and len(args) != n:
            raise ExprError(f"takes {n} argument{'s' * (n != 1)} (got {len(args)})")
        _num(*args)
        return f(*args)
    return call


FUNCTIONS = {
    **{name: _fn(getattr(math, name), 1) for name in (
        "sqrt", "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "exp", "log10",
        "log2", "radians", "degrees", "floor", "ceil", "fabs")},
    "atan2": _fn(math.atan2, 2), "hypot": _fn(math.hypot, None), "log": _fn(math.log, None),
    "abs": _fn(abs, 1), "round": _fn(round, None), "min": _fn(min, None), "max": _fn(max, None),
    "int": _fn(int, 1), "float": _fn(float, 1),
}


class ExprError(ValueError):
    """An expression that cannot be evaluated; the message says why."""


class Quiet(ExprError):
    """An expression that uses a value whose own expression failed: its problem is reported
    already, so this one is not (no knock-on errors)."""


class Failed:
    """The value of a name whose expression could not be evaluated (see :class:`Quiet`)."""

    def __repr__(self):
        return "<failed>"


FAILED = Failed()


_BIN = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
        ast.FloorDiv: operator.floordiv, ast.Mod: operator.mod, ast.Pow: operator.pow}
_CMP = {ast.Eq: operator.eq, ast.NotEq: operator.ne, ast.Lt: operator.lt, ast.LtE: operator.le,
        ast.Gt: operator.gt, ast.GtE: operator.ge}
_SYMBOL = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.FloorDiv: "//", ast.Mod: "%",
           ast.Pow: "**"}


def evaluate(text: str, scope: dict, units: dict | None = None, known_units: str = ""):
    """The value of expression ``text`` with the names in ``scope`` (and the constants).

    ``units``: unit name -> function converting a number to SI; a number followed by one of
    them (``1 cm``) is that SI number; ``known_units`` lists them for the message of an unknown one."""
    if len(text) > MAX_LENGTH:
        raise ExprError(f"longer than {MAX_LENGTH} characters")
    text = quantities(text.strip(), units or {}, known_units)
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError as exc:
        raise ExprError("invalid syntax" if exc.msg == "invalid syntax" else f"invalid syntax ({exc.msg})") from None
    if sum(1 for _ in ast.walk(tree)) > MAX_NODES:
        raise ExprError(f"more than {MAX_NODES} terms")
    return _Eval(scope).visit(tree.body)


def quantities(text: str, units: dict, known: str = "") -> str:
    """``text`` with every number followed by a unit of ``units`` (``1 cm``, ``90deg``) replaced by
    its SI number in parentheses; a number followed by another name that is not a keyword is an
    unknown unit."""
    try:
        tokens = list(tokenize.generate_tokens(io.StringIO(text).readline))
    except (tokenize.TokenError, SyntaxError, IndentationError):
        return text  # the parser says what is wrong
    starts = [0]
    for line in text.splitlines(keepends=True):
        starts.append(starts[-1] + len(line))
    out, pos = [], 0
    for number, unit in zip(tokens, tokens[1:]):
        if number.type != tokenize.NUMBER or unit.type != tokenize.NAME:
            continue
        if unit.string not in units:
            if keyword.iskeyword(unit.string):
                continue
            raise ExprError(f"unknown unit '{unit.string}' in '{number.string} {unit.string}'"
                            + (f" ({known})" if known else ""))
        try:
            value = units[unit.string](float(number.string) if any(c in number.string for c in ".eE")
                                       else int(number.string, 0))
        except ValueError:
            raise ExprError(f"'{number.string} {unit.string}' is not a quantity") from None
        begin = starts[number.start[0] - 1] + number.start[1]
        out += [text[pos:begin], f"({value!r})"]
        pos = starts[unit.end[0] - 1] + unit.end[1]
    return "".join(out) + text[pos:]


class _Eval:
    def __init__(self, scope: dict):
        self.scope = scope

    def visit(self, node):
        method = getattr(self, "v_" + type(node).__name__, None)
        if method is None:
            raise ExprError(f"'{ast.unparse(node)}' is not allowed (numbers, names, arithmetic, comparisons, "
                            "'and', 'or', 'not', 'a if c else b' and math functions only)")
        value = method(node)
        if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > MAX_INT_BITS:
            raise ExprError("number too large")
        if isinstance(value, float) and math.isinf(value):
            raise ExprError("number too large")
        if isinstance(value, float) and math.isnan(value):
            raise ExprError("result is not a number (nan)")
        if isinstance(value, str) and len(value) > MAX_STRING:
            raise ExprError(f"text longer than {MAX_STRING} characters")
        return value

    def v_Constant(self, node):
        if isinstance(node.value, (int, float, str)) and not isinstance(node.value, complex):
            return node.value
        raise ExprError(f"'{ast.unparse(node)}' is not allowed")

    def v_Name(self, node):
        if node.id in self.scope:
            value = self.scope[node.id]
            if value is FAILED:
                raise Quiet(f"'{node.id}' could not be evaluated")
            if not isinstance(value, (bool, int, float, str)):  # a value the schema will reject too
                raise ExprError(f"'{node.id}' is not a number, true/false or text (got {show(value)})")
            return value
        if node.id in CONSTANTS:
            return CONSTANTS[node.id]
        if node.id in FUNCTIONS:
            raise ExprError(f"'{node.id}' is a function: call it as {node.id}(...)")
        known = sorted(set(self.scope) | {"pi", "e", "tau"})
        close = difflib.get_close_matches(node.id, known, n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise ExprError(f"unknown name '{node.id}'{hint}")

    def v_BinOp(self, node):
        op = type(node.op)
        if op not in _BIN:
            raise ExprError(f"operator '{ast.unparse(node)}' is not allowed")
        a, b = self.visit(node.left), self.visit(node.right)
        if isinstance(a, str) or isinstance(b, str):
            if op is ast.Add and isinstance(a, str) and isinstance(b, str):
                return a + b
            raise ExprError(f"cannot apply '{_SYMBOL[op]}' to {a!r} and {b!r}")
        if op is ast.Pow:
            if abs(b) > MAX_EXPONENT:
                raise ExprError("exponent too large")
            if isinstance(a, int) and isinstance(b, int) and abs(a) > 1 and b * max(1, abs(a).bit_length()) > MAX_INT_BITS:
                raise ExprError("number too large")
        try:
            return _BIN[op](a, b)
        except ZeroDivisionError:
            raise ExprError("division by zero") from None
        except OverflowError:
            raise ExprError("number too large") from None
        except TypeError:
            raise ExprError(f"cannot apply '{_SYMBOL[op]}' to {a!r} and {b!r}") from None

    def v_UnaryOp(self, node):
        v = self.visit(node.operand)
        if isinstance(node.op, ast.Not):
            return not v
        if isinstance(v, str) or isinstance(node.op, ast.Invert):
            raise ExprError(f"'{ast.unparse(node)}' is not allowed")
        return -v if isinstance(node.op, ast.USub) else +v

    def v_BoolOp(self, node):
        if isinstance(node.op, ast.And):
            v = True
            for n in node.values:
                v = self.visit(n)
                if not v:
                    return v
            return v
        v = False
        for n in node.values:
            v = self.visit(n)
            if v:
                return v
        return v

    def v_Compare(self, node):
        left = self.visit(node.left)
        for op, right_node in zip(node.ops, node.comparators):
            if type(op) not in _CMP:
                raise ExprError(f"'{ast.unparse(node)}' is not allowed")
            right = self.visit(right_node)
            try:
                if not _CMP[type(op)](left, right):
                    return False
            except TypeError:
                raise ExprError(f"cannot compare {left!r} and {right!r}") from None
            left = right
        return True

    def v_IfExp(self, node):
        return self.visit(node.body) if self.visit(node.test) else self.visit(node.orelse)

    def v_Call(self, node):
        if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS or node.keywords:
            name = ast.unparse(node.func)
            raise ExprError(f"unknown function '{name}' (known: {', '.join(sorted(FUNCTIONS))})")
        args = [self.visit(a) for a in node.args]
        try:
            return FUNCTIONS[node.func.id](*args)
        except ExprError as exc:
            raise ExprError(f"{node.func.id}() {exc}") from None
        except OverflowError:
            raise ExprError(f"{node.func.id}(): number too large") from None
        except (ValueError, TypeError) as exc:
            raise ExprError(f"{node.func.id}(): {exc}") from None


def show(value) -> str:
    """A value as text inside a larger string (``${a}_link``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value) if isinstance(value, float) else str(value)
