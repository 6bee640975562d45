r"""The compiled System of a stage combination of a model with switches (Mech chapter 5;
docs/decisions/0009-multistage.md): the model's equations with each switch's rows replaced by
those of its stage, optionally without dropped constraints or stages (free motion). Cached on
the model per version. Used by the multistage sweep (``analyses/_multistage.py``), free motion
through stage changes (``analyses/_free_switch.py``) and stage-by-stage outputs
(``results/_stagewise.py``)."""

from __future__ import annotations

from ._options import process_equation
from ._system import System, make_layout


def _cache(model) -> dict:
    c = model.__dict__.get("_stage_cache")
    if c is None or c[0] != model._version:
        c = model.__dict__["_stage_cache"] = (model._version, {})
    return c[1]


def stage_system(model, stages, dropped=()) -> System:
    """The System of the stage combination ``stages`` (0-based stage index per switch, in
    model order; ``None``: every switch at its first stage), compiled once per model version.

    ``dropped`` (free motion): constraints whose rows are left out (of the model, or inside
    a stage of a switch: the velocity constraints free motion holds as rows of their own,
    decision 0063), and ``(switch, stage)`` pairs (0-based stage): in that stage the switch
    contributes only the rows holding its variables (``v - v_held``), so the motion it
    constrained elsewhere is free there."""
    switches = model._switches()
    stages = tuple(stages) if stages is not None else (0,) * len(switches)
    plain = [c for c in dropped if not isinstance(c, tuple)]
    staged = {(id(c[0]), c[1]) for c in dropped if isinstance(c, tuple)}
    key = (stages, tuple(sorted(map(id, plain))), tuple(sorted(staged)))
    if not dropped:
        key = stages
    cache = _cache(model)
    if key in cache:
        return cache[key]
    chosen = dict(zip(map(id, switches), zip(switches, stages)))
    eqs0, owners0, index0 = model._all_equations()
    eqs, owners, index, done = [], [], [], set()
    for e, o, i in zip(eqs0, owners0, index0):
        if any(o is c for c in plain):
            continue
        if id(o) in chosen:
            if id(o) not in done:
                done.add(id(o))
                k = chosen[id(o)][1]
                rows = (o.stage_equations(model.space, k, plain) if (id(o), k) not in staged
                        else [v.symbol - o.held_symbol(v.symbol) for v in o.new_variables()])
                # m.set_compile_options(process=...) reaches the switched rows too
                rows = [process_equation(model._compile_opts, e, o.label()) for e in rows]
                gen = model._gen_substitution()  # slave bodies (Gen joints): their poses
                rows = [e.xreplace(gen) for e in rows] if gen else rows
                eqs += rows
                owners += [o] * len(rows)
                index += list(range(len(rows)))
            continue
        eqs.append(e)
        owners.append(o)
        index.append(i)
    held = [s for sw in switches for s in sw.held_symbols()]
    model._check_symbols([e for e in eqs if not e.free_symbols & set(held)], owners)
    layout = make_layout(model._bodies[1:], model._variables, list(model._params) + held, owners,
                         index)
    system = System(model.space, layout, eqs, model._p(), model.guess(), backend=model._backend,
                    version=model._version, model=model, loads=list(model._loads))
    # the stage each switch's rows come from (None: only its held rows), for the branch
    # guard of the angle drivers inside the stages (compile/_branches.py, decision 0033)
    system.switch_stages = {id(sw): None if (id(sw), k) in staged else k
                            for sw, k in zip(switches, stages)}
    cache[key] = system
    return system


__all__ = ["stage_system"]
