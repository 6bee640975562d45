"""Model files: a declarative JSON format that is safe to read from strangers (no ``eval``, no
pickle; expressions read by the restricted grammar of :mod:`mechsys.io._expr`)."""

from ._expr import parse as parse_expression
from ._expr import to_text as expression_text
from ._files import load, model_from_dict, model_to_dict, save
from ._mjcf import from_mjcf
from ._urdf import ImportReport, from_urdf

__all__ = ["ImportReport", "expression_text", "from_mjcf", "from_urdf", "load", "model_from_dict",
           "model_to_dict", "parse_expression", "save"]
