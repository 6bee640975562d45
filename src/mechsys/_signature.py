"""The signature a class shows: that of its ``__init__``.

Constraints, loads and drawing primitives keep their constructor arguments for model files
(``mechsys.io``) through a ``__new__(cls, *args, **kwargs)`` on their base class. Sphinx's
autodoc reads a class's signature from a user-defined ``__new__`` before ``__init__``, so every
one of them showed ``(*args, **kwargs)`` in the API reference. Both autodoc and
:func:`inspect.signature` take a class's ``__signature__`` first; this descriptor makes it the
``__init__`` signature of the class it is read from (read when asked, so that a class
decorator that replaces ``__init__`` afterwards, as in ``constraints/_gears.py``, is seen).
"""

from __future__ import annotations

import inspect


class InitSignature:
    """Class attribute ``__signature__ = InitSignature()``: ``inspect.signature(cls)`` is
    ``cls.__init__``'s signature without ``self``."""

    def __get__(self, obj, cls=None) -> inspect.Signature:
        if obj is not None:                 # an instance is not a callable with a signature
            raise AttributeError("__signature__")
        sig = inspect.signature(cls.__init__)
        params = list(sig.parameters.values())[1:]
        return sig.replace(parameters=params)
