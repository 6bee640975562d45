"""Model files: a declarative JSON format that is safe to read from strangers (no ``eval``, no
pickle; expressions read by the restricted grammar of :mod:`mechsys.io._expr`)."""

from ._expr import parse as parse_expression
from ._expr import to_text as expression_text

__all__ = ["expression_text", "parse_expression"]
