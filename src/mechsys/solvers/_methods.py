"""The integration methods of ``simulate``: one registry (decision 0038).

As SciPy's ``solve_ivp`` keeps its ``METHODS`` table, this module names each method once:
its family, the spellings it answers to, the options it takes, whether it has a dense
output (events and output times between steps need one), the SciPy stepper class of its
Python path and its compiled loop. Everything else reads it: the option check
(``_integrators.integration_options``), the dispatch (``_integrators.integrate``), the
compiled stepper's plan (``_jit_free.FreeStepper``) and the event-driven runs
(``analyses/_free_switch``). A method added here without a compiled loop runs in Python and
says so (``compiled=None``); a method cannot be known to one part and missing in another.

The contract every method meets (what ``integrate`` relies on): it advances :math:`y' = f(t, y)`
from ``t0`` toward ``t1`` by accepted steps, each followed by the projection onto the
constraints when ``constraint_correction`` is on; it reports the accepted steps' times and
states, the evaluations of ``f``, the rejected steps; it stops cleanly on KeyboardInterrupt
(the steps so far); its compiled loop, where it has one, takes the regular steps of the same
run and hands the others to the Python path without a restart.
"""

from __future__ import annotations

from dataclasses import dataclass

from .._errors import choice

#: the options of every family (Mech's accuracy option max_error works with every method)
_COMMON = ("max_error", "starting_step_size", "constraint_correction")


@dataclass(frozen=True)
class Method:
    """One integration method.

    ``name``: the canonical name (``IntegrationOptions.method``); ``family``:
    ``"runge_kutta"`` (SciPy's stepper with error control, our tableau in the compiled loop)
    or ``"adams"`` (Mech's multistep integrator); ``aliases``: other spellings; ``options``:
    the ``simulate`` options it takes; ``dense_output``: a continuous extension within each
    step (events are located on it); ``scipy``: the class in ``scipy.integrate`` of its Python
    path (Runge-Kutta); ``compiled``: its loop in ``_jit_free_loop`` (``"runge_kutta"`` with
    the tableau ``tableau`` of ``_tableaus``, or ``"adams"``), None when it has none;
    ``order``: the order of the propagated solution (Runge-Kutta); ``implicit``: an implicit
    Runge-Kutta method for stiff models (SciPy's ``Radau``: each step solves its stage
    equations by Newton's method with a finite-difference Jacobian of the derivative; no
    compiled loop)."""

    name: str
    family: str
    options: tuple
    dense_output: bool
    compiled: str | None
    aliases: tuple = ()
    scipy: str | None = None
    tableau: str | None = None
    order: int | None = None
    implicit: bool = False

    @property
    def runge_kutta(self) -> bool:
        return self.family == "runge_kutta"


_RK_OPTIONS = ("rtol", "atol", "max_step") + _COMMON
_ADAMS_OPTIONS = ("fit_degree", "step_size") + _COMMON

METHODS: dict[str, Method] = {m.name: m for m in (
    Method("dop853", "runge_kutta", _RK_OPTIONS, True, "runge_kutta", scipy="DOP853",
           tableau="DOP853_TABLEAU", order=8),
    Method("rk45", "runge_kutta", _RK_OPTIONS, True, "runge_kutta", scipy="RK45",
           tableau="RK45_TABLEAU", order=5),
    # stiff models (stiff springs and dampers, penalty contacts): Radau IIA of order 5,
    # L-stable, on the same index-1 equations (accelerations from the augmented system) and
    # the same projection after each step; decision 0051
    Method("radau", "runge_kutta", _RK_OPTIONS, True, None, scipy="Radau", order=5,
           implicit=True),
    # Mech's SolveFree integrator, three modes of when the corrector is applied
    Method("automatic", "adams", _ADAMS_OPTIONS, False, "adams", aliases=("adams",)),
    Method("predictor", "adams", _ADAMS_OPTIONS, False, "adams"),
    Method("corrector", "adams", _ADAMS_OPTIONS, False, "adams"),
)}

#: every spelling ``simulate(method=...)`` accepts, in the order error messages list them
NAMES = tuple(n for m in METHODS.values() for n in (m.name,) + m.aliases)
_BY_NAME = {n: m for m in METHODS.values() for n in (m.name,) + m.aliases}


def family_names(family: str) -> tuple:
    """The accepted spellings of the methods of ``family``."""
    return tuple(n for n in NAMES if _BY_NAME[n].family == family)


def get(name) -> Method:
    """The method called ``name`` (any case, any alias); :class:`ModelError` listing the
    methods otherwise."""
    m = _BY_NAME.get(name.lower()) if isinstance(name, str) else None
    if m is None:  # an OptionError naming the methods and the closest one
        choice(name, NAMES, "simulate: method")
    return m


def find(name) -> Method | None:
    """The method called ``name``, or None (no error: for the compiled stepper's plan)."""
    return _BY_NAME.get(name.lower()) if isinstance(name, str) else None


__all__ = ["METHODS", "NAMES", "Method", "family_names", "find", "get"]
