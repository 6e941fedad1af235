"""The one reader of URDF XML: a file or a text into an lxml element tree with source lines.

Hardened for descriptions from anywhere: entities in text are not expanded (libxml2 expands
them in attribute values only, under its amplification limit, which refuses a "billion laughs"),
nothing is fetched from the network, no DTD is loaded, and libxml2's size and depth limits stay
on (``huge_tree`` off).  Any declared XML version is accepted, as urdfdom (TinyXML2) accepts it:
PyBullet's humanoid says ``version="0.0"``, which libxml2 alone refuses.

A text is read as text (its declared encoding is ignored, as Python's own XML readers do for a
``str``); a file as bytes, in the encoding it declares.  With ``comments=False`` the tree has
the shape Python's ElementTree gives: comments and processing instructions dropped, the text
around them joined, so that iterating an element yields elements only.

lxml is imported when a file is read (it is heavy for the no-op build path).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

_VERSION = re.compile(rb'^(\s*<\?xml\s+version\s*=\s*["\'])(?!1\.)[^"\']*')


class MalformedXML(ValueError):
    """A URDF that is not well-formed XML.  ``str()`` is libxml2's description (with ``line``);
    ``expat`` is Python's expat's (``"mismatched tag: line 1, column 18"``, with ``expat_line``),
    the words the import and the lints report, or None when only libxml2 refuses the text."""

    def __init__(self, message: str, line: int | None, expat: str | None, expat_line: int | None):
        super().__init__(message)
        self.line = line
        self.expat = expat
        self.expat_line = expat_line


def parse_file(path: str | os.PathLike, *, comments: bool = False):
    """The lxml ElementTree of the URDF file ``path``.  Raises MalformedXML, or OSError when the
    file cannot be read."""
    return _parse(Path(path).read_bytes(), None, comments)


def parse_text(text: str, *, comments: bool = False):
    """The lxml ElementTree of the URDF ``text``.  Raises MalformedXML."""
    return _parse(text.encode("utf-8"), "utf-8", comments)


def is_element(node) -> bool:
    """Whether an lxml node is an element (not a comment, processing instruction or entity)."""
    return isinstance(node.tag, str)


def _parse(data: bytes, encoding: str | None, comments: bool):
    from lxml import etree  # heavy: imported when a URDF is read

    data = _VERSION.sub(rb"\g<1>1.0", data)
    parser = etree.XMLParser(encoding=encoding, resolve_entities=False, no_network=True, load_dtd=False,
                             huge_tree=False, remove_comments=not comments, remove_pis=not comments)
    try:
        return etree.ElementTree(etree.fromstring(data, parser))
    except etree.XMLSyntaxError as exc:
        raise MalformedXML(str(exc), exc.lineno, *_expat_words(data, encoding)) from None


def _expat_words(data: bytes, encoding: str | None) -> tuple[str | None, int | None]:
    """Python's expat's description of the first error in ``data`` and its line (None, None when
    expat reads it), for callers whose messages have always given expat's words."""
    import xml.etree.ElementTree as ElementTree  # describes an error lxml found; reads no tree

    try:
        ElementTree.fromstring(data.decode(encoding) if encoding else data)
    except ElementTree.ParseError as exc:
        return str(exc), exc.position[0]
    except (ValueError, LookupError):
        return None, None
    return None, None
