"""``solvers._jit_borrow.borrow``: the same data without reference counting (decision 0021),
and the free-motion loops' workspace that relies on it."""

import numpy as np
import pytest

nb = pytest.importorskip("numba")

from mechsys.solvers._jit_borrow import borrow  # noqa: E402


@nb.njit(cache=False)
def _through(a, pair):
    """Borrow, write through the borrowed copies, read a strided view of one."""
    a2, (b2, k, c2) = borrow((a, pair))
    a2[0] = 7.0
    b2[1, 1] = -3.0
    for i in range(c2.size):
        c2[i] += 1
    return a2[::2].sum() + b2[:, 1].sum() + k + c2.sum(), a2.shape[0], b2.strides[0]


@nb.njit(cache=False)
def _sum(ws, n, lend):
    """The same loop over ``ws``, counted (``lend`` False) or borrowed."""
    if lend:
        ws = borrow(ws)
    s = 0.0
    for i in range(n):
        s += _leaf(ws, i)
    return s


@nb.njit(cache=False)
def _leaf(ws, i):
    a, (b, c) = ws
    if i < 0:
        return -1.0
    return a[i % a.size] + b[0, i % b.shape[1]] * c[i % c.size]


def test_borrowed_arrays_are_the_same_data():
    a = np.arange(6.0)
    b = np.zeros((3, 4))
    c = np.ones(2, dtype=np.int64)
    total, size, stride = _through(a, (b, 5, c))
    # writes through the borrowed copies land in the caller's arrays
    assert a[0] == 7.0 and b[1, 1] == -3.0 and np.array_equal(c, [2, 2])
    assert total == (7.0 + 2.0 + 4.0) + (-3.0) + 5 + 4
    assert size == 6 and stride == b.strides[0]


def test_borrowed_loop_gives_the_counted_loops_numbers():
    rng = np.random.default_rng(1)
    ws = (rng.normal(size=7), (rng.normal(size=(2, 5)), rng.normal(size=3)))
    assert _sum(ws, 1000, True) == _sum(ws, 1000, False)


def test_borrow_refuses_what_it_cannot_strip():
    @nb.njit(cache=False)
    def f(x):
        return borrow(x)

    with pytest.raises(nb.core.errors.TypingError):
        f([np.zeros(2)])                     # a reflected list: would need counting


def _three_links():
    """The free 3-link pendulum chain the workspace tests run, and the two compiled methods
    with their options."""
    from mechsys import models

    m = models.pendulum_chain(3, 9.81)
    m.solve(0.0)
    return m.free(drop=["lock0", "lock1", "lock2"]), (("dop853", {"rtol": 1e-9, "atol": 1e-11}),
                                                      ("adams", {"max_error": 1e-6}))


def test_free_stepper_workspace_carries_no_state_between_chunks(monkeypatch):
    """A stepper allocates its work arrays once and the loops borrow them for every chunk
    of steps: a run cut into chunks of 7 steps is bit-identical to a run in one chunk."""
    from mechsys.solvers import _jit_free

    free, methods = _three_links()
    for method, opts in methods:
        whole = free.simulate((0.0, 1.0), method=method, **opts)
        assert whole.extra["compiled_steps"] > 3 * 7
        with monkeypatch.context() as mp:
            mp.setattr(_jit_free, "CHUNK_STEPS", 7)
            cut = free.simulate((0.0, 1.0), method=method, **opts)
        assert cut.extra["compiled_steps"] == whole.extra["compiled_steps"]
        for a, b in ((whole.q, cut.q), (whole.qd, cut.qd), (whole.lam, cut.lam)):
            assert np.array_equal(a, b)


def test_a_reused_workspace_carries_nothing_from_the_last_run():
    """Steppers of the same system take over the last one's work arrays once its run is
    over (``_jit_free._workspace``): a run after another with other initial conditions and
    options is bit-identical to the same run first, and a stepper still alive keeps its own."""
    import gc

    from mechsys.solvers import _jit_free

    free, methods = _three_links()
    for method, opts in methods:
        first = free.simulate((0.0, 0.5), method=method, **opts)
        other = free.simulate((0.0, 0.3), method="dop853", rtol=1e-5, atol=1e-7,
                              initial_condition={"l0.th": 0.4, "l1.th": -0.2, "l2.th": 0.1})
        assert not np.array_equal(other.q[-1], first.q[-1])
        gc.collect()
        again = free.simulate((0.0, 0.5), method=method, **opts)
        assert again.extra["compiled_steps"] == first.extra["compiled_steps"] > 0
        for a, b in ((first.q, again.q), (first.qd, again.qd), (first.lam, again.lam)):
            assert np.array_equal(a, b)
    s = free.system
    steppers = []
    orig = _jit_free.FreeStepper.__init__

    def keep(self, *a, **k):
        orig(self, *a, **k)
        steppers.append(self)

    _jit_free.FreeStepper.__init__ = keep
    try:
        free.simulate((0.0, 0.1))
        free.simulate((0.0, 0.1))
    finally:
        _jit_free.FreeStepper.__init__ = orig
    assert steppers[0].ws is not steppers[1].ws       # the first still lives: not shared
    assert s is free.system


def test_a_finished_run_frees_its_stepper_without_the_garbage_collector():
    """SciPy's solver objects live in reference cycles; the stepper must not be kept alive
    by them (the derivative SciPy calls holds it weakly), or the next run cannot reuse its
    work arrays until a garbage collection: with the collector off, the second run's
    stepper has the first one's workspace."""
    import gc
    import weakref

    from mechsys.solvers import _jit_free

    free, _ = _three_links()
    free.simulate((0.0, 0.1))
    made = []
    orig = _jit_free.FreeStepper.__init__

    def note(self, *a, **k):
        orig(self, *a, **k)
        made.append((weakref.ref(self), self.ws))

    was = gc.isenabled()
    gc.disable()
    _jit_free.FreeStepper.__init__ = note
    try:
        free.simulate((0.0, 0.1))
        assert made[0][0]() is None                  # gone when the run returned
        free.simulate((0.0, 0.1), rtol=1e-6, atol=1e-8)
    finally:
        _jit_free.FreeStepper.__init__ = orig
        if was:
            gc.enable()
    assert len(made) == 2 and made[1][1] is made[0][1]
