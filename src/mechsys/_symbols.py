"""Time and naming of symbols. ``T`` is the time symbol used in drivers."""

from __future__ import annotations

import sympy as sp

#: The time symbol. Use it in any scalar argument to make a driver, e.g. ``2*pi*T``.
T = sp.Symbol("T")


def coord_symbol(name: str) -> sp.Symbol:
    return sp.Symbol(name)


def velocity_symbol(name: str) -> sp.Symbol:
    return sp.Symbol(name + "_d")


def acceleration_symbol(name: str) -> sp.Symbol:
    return sp.Symbol(name + "_dd")
