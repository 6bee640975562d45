"""The only place that turns SymPy into numbers: layout, :class:`System`, backends."""

from ._backends import Compiled, available_backends, compile_exprs, default_backend
from ._derive import time_derivative
from ._system import Layout, System, make_layout

__all__ = [
    "Compiled",
    "Layout",
    "System",
    "available_backends",
    "compile_exprs",
    "default_backend",
    "make_layout",
    "time_derivative",
]
