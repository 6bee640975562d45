"""The only place that turns SymPy into numbers: layout, :class:`System`, backends."""

from ._backends import Compiled, available_backends, compile_exprs, default_backend
from ._system import Layout, System, make_layout, time_derivative

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
