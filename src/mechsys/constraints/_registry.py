"""Mech name -> constraint class. Drives the generated docs and the conformance suite."""

from __future__ import annotations

from ._base import ConstraintBase

REGISTRY: dict[str, type[ConstraintBase]] = {}


def register(cls: type[ConstraintBase]) -> type[ConstraintBase]:
    """Register a constraint class under its Mech name (class decorator)."""
    REGISTRY[cls.mech_name or cls.__name__] = cls
    return cls


def constraint_types(space: str | None = None) -> dict[str, type[ConstraintBase]]:
    """Registered types, optionally only those usable in ``"planar"`` or ``"spatial"`` models."""
    return {k: v for k, v in REGISTRY.items() if space is None or space in v.spaces}
