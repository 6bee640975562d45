r"""A small, safe XML reader for robot description files (URDF, MJCF) from strangers.

Safety (decision 0040): the file must be a regular file of at most :data:`MAX_XML_BYTES`;
a document type declaration (``<!DOCTYPE``) or an entity declaration (``<!ENTITY``) is
refused *before* parsing, and the Expat parser refuses them again while parsing (no entity
expansion, no external entities, no "billion laughs"); nesting deeper than
:data:`MAX_DEPTH` and more than :data:`MAX_ELEMENTS` elements are refused. Every element
keeps the line it starts on and its file (``Element.source``: an MJCF ``<include>``
brings elements of other files), so an error names the file, the element and its line.
"""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from .._errors import ModelError

MAX_XML_BYTES = 20_000_000
MAX_DEPTH = 256
MAX_ELEMENTS = 500_000
#: refused before parsing (lower case; the scan is case-insensitive)
REFUSED = (b"<!doctype", b"<!entity")


@dataclass
class Element:
    """An XML element: tag, attributes, children and the line it starts on."""

    tag: str
    attrib: dict
    line: int
    children: list = field(default_factory=list)
    parent: Element | None = field(default=None, repr=False)
    #: the file the element was read from (an MJCF ``<include>`` brings elements of other files)
    source: str | None = field(default=None, repr=False)

    def find(self, tag: str) -> Element | None:
        for c in self.children:
            if c.tag == tag:
                return c
        return None

    def findall(self, tag: str) -> list[Element]:
        return [c for c in self.children if c.tag == tag]

    def get(self, key: str, default=None):
        return self.attrib.get(key, default)

    def label(self) -> str:
        name = self.attrib.get("name")
        return f"<{self.tag} name={name!r}>" if name is not None else f"<{self.tag}>"


def where(source: str, el: Element | None) -> str:
    """``"file, line n, <tag name='x'>"``: the element's own file when it has one (an element
    brought by an ``<include>`` names the included file), else ``source``."""
    if el is None:
        return source
    return f"{el.source or source}, line {el.line}, {el.label()}"


def read_xml(path) -> tuple[Element, str]:
    """``(root element, source name)`` of the XML file ``path``, read safely (module doc)."""
    p = Path(path)
    source = str(p)
    try:
        st = os.stat(p)
    except OSError as exc:
        raise ModelError(f"{source}: cannot read the file ({exc.strerror})") from None
    if not stat.S_ISREG(st.st_mode):
        raise ModelError(f"{source}: not a regular file; give the path of a .urdf/.xml file")
    if st.st_size > MAX_XML_BYTES:
        raise ModelError(f"{source}: {st.st_size} bytes, more than the limit of {MAX_XML_BYTES} "
                           "for a robot description")
    with open(p, "rb") as f:
        data = f.read(MAX_XML_BYTES + 1)
    if len(data) > MAX_XML_BYTES:
        raise ModelError(f"{source}: more than the limit of {MAX_XML_BYTES} bytes")
    return parse_xml(data, source), source


def parse_xml(data: bytes, source: str = "<string>") -> Element:
    """The root :class:`Element` of ``data``; refuses declarations (module doc)."""
    low = data.lower()
    for token in REFUSED:
        k = low.find(token)
        if k >= 0:
            line = data.count(b"\n", 0, k) + 1
            raise ModelError(f"{source}, line {line}: a {token[2:].decode().upper()} declaration; "
                               "robot description files are read without document type or entity "
                               "declarations (they could expand without bound); remove it")
    parser = expat.ParserCreate()
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    stack: list[Element] = []
    root: list[Element] = []
    count = [0]

    def refuse(*_args):
        raise ModelError(f"{source}, line {parser.CurrentLineNumber}: a document type or entity "
                           "declaration; robot description files are read without them")

    def start(tag, attrs):
        count[0] += 1
        if count[0] > MAX_ELEMENTS or len(stack) >= MAX_DEPTH:
            raise ModelError(f"{source}, line {parser.CurrentLineNumber}: more than "
                               f"{MAX_ELEMENTS} elements or deeper than {MAX_DEPTH} levels")
        el = Element(tag, dict(attrs), parser.CurrentLineNumber, source=source)
        if stack:
            el.parent = stack[-1]
            stack[-1].children.append(el)
        else:
            root.append(el)
        stack.append(el)

    def end(_tag):
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.StartDoctypeDeclHandler = refuse
    parser.EntityDeclHandler = refuse
    parser.ExternalEntityRefHandler = refuse
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise ModelError(f"{source}, line {exc.lineno}: not well-formed XML "
                           f"({expat.ErrorString(exc.code)})") from None
    if not root:
        raise ModelError(f"{source}: no XML element found")
    return root[0]


def floats(source: str, el: Element, key: str, n: int | None, default=None) -> list[float] | None:
    """The attribute ``key`` of ``el`` as ``n`` numbers (whitespace-separated), or
    ``default`` when absent; a bad value names the element and line."""
    text = el.get(key)
    if text is None:
        return default
    try:
        vals = [float(v) for v in text.split()]
    except ValueError:
        raise ModelError(f"{where(source, el)}: attribute {key}={text!r} is not a list of numbers") \
            from None
    if n is not None and len(vals) != n:
        raise ModelError(f"{where(source, el)}: attribute {key}={text!r} needs {n} numbers, "
                           f"has {len(vals)}")
    import math

    if not all(math.isfinite(v) for v in vals):
        raise ModelError(f"{where(source, el)}: attribute {key}={text!r} is not finite")
    return vals
