"""The one Jinja environment every emitter renders through.

Search path, in order: a recipe's own template folder (when given), the
templates shipped inside the wheel (``robotkit/templates``), and the
repository's top-level ``templates/`` (development checkout).
StrictUndefined turns a missing context value into an error instead of an
empty string; autoescaping keeps every attribute and text well-formed XML.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

_PKG = Path(__file__).resolve().parent.parent


def template_dirs(extra: tuple[str, ...] = ()) -> list[str]:
    dirs = [str(Path(d)) for d in extra]
    for d in (_PKG / "templates", _PKG.parent / "templates"):
        if d.is_dir():
            dirs.append(str(d))
    return dirs


SIGNIFICANT_DIGITS = 15
"""Resolution of every number the emitters write: 15 significant digits (at most 5e-15
relative, far below any physical tolerance; 15 is the decimal precision every float64 holds,
C's DBL_DIG), so sums of the decimals a recipe gives print as those decimals (0.1 + 0.0175 is
written 0.1175, not 0.11750000000000001) while computed values keep all but the noise digit."""


def fmt(x: float) -> str:
    """``x`` rounded to :data:`SIGNIFICANT_DIGITS`, then the shortest text that reads back as that
    float64 (no -0, no exponent surprises)."""
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"cannot write non-finite number {x!r}")
    x = float(f"{x:.{SIGNIFICANT_DIGITS}g}")
    if x == 0.0:
        return "0"
    text = repr(x)
    if text.endswith(".0"):
        text = text[:-2]
    return text


def vec(values) -> str:
    return " ".join(fmt(v) for v in values)


def each(items, line) -> str:
    """``line``, a ``str.format`` pattern naming the item ``it`` (``{it.pos}``), for every item, joined.

    For long lists (a world's 10^5 collision boxes): the pattern is read once, each field
    taken from all the items at once (``operator.attrgetter``) and the pieces joined, instead
    of a Jinja loop's attribute lookup and escaping per value.  The values are escaped all
    the same: when the text holds more markup characters than the pattern's own, it is made
    again through markupsafe's escaping formatter.
    """
    import itertools
    import operator
    import string

    import markupsafe

    items = list(items)
    pattern = str(line)
    parts = list(string.Formatter().parse(pattern))
    own = "".join(literal for literal, *_ in parts)
    fields = [f for _, f, spec, conv in parts if f is not None]
    if all(f == "it" or (f.startswith("it.") and "[" not in f) for f in fields) and \
            not any(spec or conv for _, f, spec, conv in parts if f is not None):
        columns = []
        for literal, f, _, _ in parts:
            columns.append(itertools.repeat(literal, len(items)))
            if f is not None:
                values = items if f == "it" else map(operator.attrgetter(f[3:]), items)
                columns.append(map(format, values))
        text = "".join(itertools.chain.from_iterable(zip(*columns)))
    else:
        text = "".join([pattern.format(it=it) for it in items])
    if any(text.count(c) != own.count(c) * len(items) for c in "<>&\"'"):
        safe = markupsafe.Markup(pattern)
        text = "".join([safe.format(it=it) for it in items])
    return markupsafe.Markup(text)


@functools.lru_cache(maxsize=8)
def environment(extra: tuple[str, ...] = ()):
    import jinja2
    import markupsafe

    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(template_dirs(extra)),
        undefined=jinja2.StrictUndefined,
        autoescape=True,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
    )
    env.filters["fmt"] = fmt
    env.filters["vec"] = vec
    env.filters["each"] = each
    env.filters["py"] = lambda v: markupsafe.Markup(repr(v))  # a Python literal, for launch/*.launch.py
    return env


def render(template: str, extra_dirs: tuple[str, ...] = (), **context) -> str:
    """Render ``template`` (a path below a template folder) with ``context``."""
    return environment(tuple(extra_dirs)).get_template(template).render(**context)
