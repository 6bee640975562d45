"""``Solution.extra``: a dict whose costly entries are computed when first read.

A compiled sweep leaves the condition estimate of its regular points for later (decision
0023): the estimate takes about a fifth of the loop's time and most scripts never read it.
:class:`Extra` holds such an entry as a function and replaces it by its value the first time
anything reads it (``extra["rcond"]``, ``get``, ``items()``, ``values()``, ``dict(extra)``,
``copy``, printing, pickling), so a reader never sees the difference: the same numbers as if
they had been computed in the sweep.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


class _Deferred:
    """A value still to compute: ``make()`` returns it."""

    __slots__ = ("make",)

    def __init__(self, make: Callable[[], Any]):
        self.make = make


class Extra(dict):
    """A ``dict`` whose entries given in ``deferred`` (``{key: make}``) are computed by
    ``make()`` when first read, then kept.

    Example::

        >>> e = Extra({"a": 1}, deferred={"b": lambda: 2})
        >>> "b" in e, e["b"], dict(e)
        (True, 2, {'a': 1, 'b': 2})
    """

    def __init__(self, data=(), deferred: dict[str, Callable[[], Any]] | None = None):
        super().__init__(data)
        for key, make in (deferred or {}).items():
            super().__setitem__(key, _Deferred(make))

    def __getitem__(self, key):
        value = super().__getitem__(key)
        if isinstance(value, _Deferred):
            value = value.make()
            super().__setitem__(key, value)
        return value

    def _resolve(self) -> None:
        for key in list(super().keys()):
            self[key]

    def get(self, key, default=None):
        return self[key] if key in self else default

    def pop(self, key, *default):
        if key in self:
            self[key]
        return super().pop(key, *default)

    def setdefault(self, key, default=None):
        if key in self:
            return self[key]
        super().__setitem__(key, default)
        return default

    # everything below hands out values (or the dict whole): computed first
    def items(self):
        self._resolve()
        return super().items()

    def values(self):
        self._resolve()
        return super().values()

    def popitem(self):
        self._resolve()
        return super().popitem()

    def copy(self) -> dict:
        self._resolve()
        return dict(super().items())

    def __iter__(self):
        # (overriding it makes dict(e), {**e} and f(**e) go through keys() and __getitem__)
        return super().__iter__()

    def __eq__(self, other):
        self._resolve()
        return super().__eq__(other)

    def __ne__(self, other):
        self._resolve()
        return super().__ne__(other)

    __hash__ = None

    def __repr__(self) -> str:
        self._resolve()
        return super().__repr__()

    def __or__(self, other):
        self._resolve()
        return dict(super().items()) | other

    def __ror__(self, other):
        self._resolve()
        return other | dict(super().items())

    def __reduce__(self):
        self._resolve()
        return (Extra, (dict(super().items()),))


__all__ = ["Extra"]
