r"""Outputs of a multistage solution evaluated stage by stage (issue 14; decision 0009): a
reaction, Jacobian or power uses the rows of a switch, which differ by stage, so it is
evaluated once per stage combination present and combined point by point."""

from __future__ import annotations

import dataclasses

import numpy as np

from ..compile._stages import stage_system
from ..constraints._switches import velocity_members


def is_staged(out) -> bool:
    """Whether ``out`` is a Solution of a model with stage switches (``extra["stages"]``)."""
    extra = getattr(out, "extra", None)
    return bool(isinstance(extra, dict) and extra.get("stages"))


def stagewise(sol, output):
    """``output(s)`` of a multistage solution, each point with the rows of the stage in effect
    there: ``output`` runs once per stage combination present, on a copy of ``sol`` whose system
    is that combination's and whose switches show that stage's equations; the results are
    combined point by point (arrays along the first axis, tuples element by element)."""
    model = sol.model
    switches = model._switches()
    combos = np.stack([np.asarray(np.atleast_1d(sol.extra["stages"][sw.name])) - 1
                       for sw in switches], axis=1)
    keys = sorted({tuple(int(x) for x in c) for c in combos})
    extra = {k: v for k, v in sol.extra.items() if k != "stages"}
    # the velocity constraints (free motion, decisions 0060 and 0063) are no rows of the
    # stage systems: their multipliers are extra["mu"] (the free motion's _base systems)
    apart = tuple(velocity_members(model))
    out = None
    try:
        for key in keys:
            for sw, k in zip(switches, key):
                sw._view = k
            part = dataclasses.replace(sol, system=stage_system(model, key, apart), extra=extra,
                                       scalar=False)
            val = output(part)
            mask = np.all(combos == np.array(key), axis=1)
            if out is None:
                out = (tuple(np.array(v, dtype=float) for v in val) if isinstance(val, tuple)
                       else np.array(val, dtype=float))
            if isinstance(val, tuple):
                for o, v in zip(out, val):
                    o[mask] = np.asarray(v)[mask]
            else:
                out[mask] = np.asarray(val)[mask]
    finally:
        for sw in switches:
            sw._view = None
    if sol.scalar:
        return tuple(o[0] for o in out) if isinstance(out, tuple) else out[0]
    return out


__all__ = ["is_staged", "stagewise"]
