r"""Free motion compiled with Numba: DOP853 or RK45 steps, the augmented-system solves and the
projections onto the constraints with no Python between the compiled equations.

:meth:`~mechsys.analyses._free.FreeSystem.simulate` integrates

.. math::  y = (q, \dot q), \qquad \dot y = (\dot q, \ddot q), \qquad
           \begin{bmatrix} M & \Phi_q^T \\ \Phi_q & 0 \end{bmatrix}
           \begin{bmatrix} \ddot q \\ \lambda \end{bmatrix} =
           \begin{bmatrix} Q + Q_v \\ \gamma \end{bmatrix}

with SciPy's DOP853 (or RK45) and projects ``(q, qd)`` onto ``Phi = 0``, :math:`\Phi_q \dot q = -\Phi_t` after
every accepted step. The compiled loop (``_jit_free_loop.runge_kutta``) performs exactly these
steps: SciPy's Runge-Kutta stages, error norm and step-size control (the same coefficients,
from our own tableaus: ``_tableaus``, decision 0038), the augmented system from the compiled
SymEngine kernel solved by the LAPACK ``dgesv`` SciPy calls, the projection's unit-free
minimum-norm Newton corrections, and the method's dense output at requested output times.
Sums over stages are plain loops where SciPy calls BLAS, so the two paths agree to rounding
(about 1e-15 per step), not bit for bit.

The compiled loop takes the regular steps. Where the Python path needs its special
handling (a singular instant: singular augmented matrix, or multipliers large against the
constraint forces; a projection near a singular Jacobian; a step-size failure) it stops at
the last accepted step and the Python stepper continues from that state (the same SciPy
solver object, so nothing restarts) for :data:`PAUSE_STEPS` steps before the compiled loop
resumes. It also returns every :data:`CHUNK_STEPS` steps so that progress is shown and
Ctrl-C is honoured.

The loop can take a run when (whichever tier runs it): Numba installed (the ``fast`` extra); DOP853, RK45 or
one of Mech's Adams methods; a dense augmented system (``n + m <= SPARSE_THRESHOLD``) or the block
path (above it, while its band is narrow enough: :data:`BLOCK_WORK`; every body's mass
block regular, :data:`BLOCK_PIVOT`, or made so by the rows on that body alone: Euler
parameters, decision 0032), or above it the augmented matrix's pattern by the compiled
sparse LU (``"sparse"``: trees of many branches, whose pattern is not banded and whose
block band exceeds :data:`BLOCK_BAND`, with the Python path's pattern and LU; systems the
block path cannot take, with the banded pattern's sparse twin; its projections through the
Python path's pattern of :math:`\begin{bmatrix} I & J^T \\ \hat J & 0 \end{bmatrix}`); every kernel
SymEngine LLVM code (CSE kernels included: their repeated outputs are expanded in the
loop) or a kernel's Python function behind a ``ctypes`` callback (the SymPy backend's:
:func:`~._jit_runtime.python_entry`; an error inside it is NaN to the loop, which hands the
step over, and the Python path raises it; an interrupt is raised when the loop returns:
decision 0084). Loads that depend on the multipliers (friction) or accelerations
(added mass) take ``free_acceleration``'s Newton in the loop (``"newton"``, decision 0028).
Generalized coordinates with the recursive dynamics (decision 0018) run in the same loops:
the joint kernels, the articulated-body recursion (a tree of Gen joints, no constraint
equation) or the composite-body mass matrix in the augmented system, at any size. Loading
Numba and the cached machine code costs about 0.7 s CPU once per process.
``sol.extra["compiled_steps"]`` tells how many steps ran compiled and
``sol.extra["compiled_solver"]`` how (``"augmented"``, ``"block"``, ``"sparse"``,
``"recursive"``, ``"recursive+augmented"``, ``"path"``, ``"newton"``).

While a missing loop is compiled in the background (``MECHSYS_COMPILE`` unset, decision
0064) the Runge-Kutta loop, the derivative and a path's accelerations run their own code
interpreted (:mod:`._jit_interp`, decisions 0077 and 0082) for systems of up to
:data:`INTERP_WAIT_MAX` unknowns (larger ones take the Python path meanwhile, decision 0083),
each call bounded by about :data:`INTERP_SECONDS` of interpreted work (its steps scaled to
the measured cost of a step), and the compiled loop takes the next call once its compile is
done: the same numbers bit for bit from the first step (``sol.extra["interpreted_steps"]``
counts those steps). Mech's Adams integrator keeps the Python path meanwhile (its
interpreted steps cost too much for the cold start's budget: decisions 0077, 0082).

When it runs (``MECHSYS_JIT``): ``0`` never compiled: the same loops run interpreted, every
step (decision 0082; the Python path takes only the hand-overs at singular instants, as
with the compiled loop, and the systems the loop cannot take at all: kernels without C
entry points that say no sizes, Numba missing); ``1`` or unset: compiled whenever possible.

Velocity constraints :math:`A(q, t) \dot q + b(q, t) = 0` (rolling; decisions 0053, 0062)
run in the same loops (kind ``ROLLING``, reported as ``"augmented"``, :meth:`FreeStepper._plan_rows`)
up to ``SPARSE_THRESHOLD`` holonomic unknowns: the dense augmented system bordered by
:math:`A` (the rows' kernel gives :math:`A`, :math:`b`, :math:`\rho`) and solved as the
Python path's ``nonholonomic_acceleration``, the velocity projection onto
:math:`[\Phi_q; A] \dot q = [-\Phi_t; -b]`, the multipliers :math:`(\lambda, \mu)`.
No zone guard (the Python path with velocity rows passes no singular instant either).

Nonholonomic paths (:class:`~mechsys.analyses._path.PathSystem`, Mech's ``SolvePath``) run
in the same loops (:meth:`FreeStepper.plan_path`, decision 0027): the state is ``q``, its
derivative the velocities of the holonomic and velocity constraints (Newton on ``qd`` with
:math:`\begin{bmatrix} \Phi_q \\ \psi_{\dot q} \end{bmatrix}`: one step when the velocity constraints are
linear in the velocities),
the projection onto the positions only. Above ``SMALL_LU`` coordinates the velocity system
goes through the Python path's fixed pattern and the same compiled sparse LU, and the
projection through :math:`\begin{bmatrix} I & J^T \\ \hat J & 0 \end{bmatrix}`
(``_patterns.projection_pattern``).
"""

from __future__ import annotations

import time

import numpy as np

from . import _jit_runtime, _methods, _tableaus
from ._jit_cache import notice
from ._jit_runtime import SMALL as SMALL_LU
from ._jit_runtime import SPARSE as SPARSE_BW
from ._jit_runtime import GenTree, kernel_entry
from ._linalg import FixedPattern, _sparse_lu, pattern_slots
from ._patterns import free_newton_pattern, projection_pattern
from ._tolerances import SPARSE_THRESHOLD, Singular

#: above ``SPARSE_THRESHOLD`` unknowns the block path runs while its banded Cholesky's work
#: ``m bw^2`` is at most this (else the Python path). Systems whose augmented matrix is not
#: banded (``FixedPattern.banded``: trees of many branches) take the sparse kind before that
#: (radial engines, 3 s: 14 cylinders, ``m bw^2`` = 0.56e6, block path 90 ms, sparse 25 ms;
#: decision 0031)
BLOCK_WORK = 1e6

#: augmented systems with more unknowns take the block path when the mass matrix allows it
SMALL = 24

#: a system whose pattern is not banded for the Python path's LU (above ``SPARSE_THRESHOLD``)
#: still takes the block path when the band of ``J M^-1 J^T`` in its row order is at most
#: this (spatial chains: 6, whatever their length), else the sparse kind (trees of many
#: branches: a star's hub couples every branch)
BLOCK_BAND = 8

#: the block path needs each body's mass block positive definite: the smallest pivot of
#: its unit-diagonal form's Cholesky factor, squared, above this (a slender rod pinned at
#: its end: 0.25; an Euler-parameter block, singular: ~1e-16)
BLOCK_PIVOT = 1e-8

#: Python steps after a handover before the compiled loop resumes
PAUSE_STEPS = 8
#: compiled steps per call at most (progress and Ctrl-C are handled between calls)
CHUNK_STEPS = 2000
#: ... and about this many seconds of work at most: a large system's steps take
#: milliseconds (16 ms for the 1024-link chain), and 2000 of them would leave the progress
#: bar still and Ctrl-C unanswered for half a minute. A stepper's first call takes
#: ``CHUNK_STEPS * 12 // (n + m + k)`` steps (at least :data:`CALL_MIN_STEPS`; all of them
#: up to 12 unknowns), the later ones the steps that fit in this time at the rate the last
#: call measured; the small systems' calls keep their 2000 steps (a few milliseconds)
CALL_SECONDS = 0.25
CALL_MIN_STEPS = 16
#: Mech's Adams steps cost about a tenth of a DOP853 step: their runs return every ten times
#: as many steps (the Python between two runs was a tenth of the double pendulum's time),
#: up to about 16 MB of state rows a run
ADAMS_CHUNK_VALUES = 2_000_000
#: the methods with a compiled loop: those of the registry (``_methods``) that name one
METHODS = tuple(name for name, m in _methods.METHODS.items() if m.compiled is not None)

#: the position of the mode (``blocks``) among each loop's arguments (``FreeStepper._call``)
_MODE_AT = {"loop": 14, "adams": 14, "derivative": 13}
#: CPU seconds of each loop's compile from empty caches for the augmented kind (the double
#: pendulum's 51 s to the first result, ``benchmarks/cold_start.py``, shared as
#: ``benchmarks/compile_profile.py`` found it; decision 0044), for the notice. Adams: not
#: measured apart from the derivative it shares with the Runge-Kutta runs
_COMPILE_SECONDS = {"loop": 35, "adams": None, "derivative": 15}

#: while a loop is compiled in the background (decision 0064), and always with
#: ``MECHSYS_JIT=0``, its own code runs interpreted (:mod:`._jit_interp`, decisions 0077,
#: 0082; while compiling, up to :data:`INTERP_WAIT_MAX` unknowns): each call of the
#: stepping loops takes the steps that fit in about this
#: many seconds of interpreted work (measured on the stepper's own calls), so that the
#: compiled loop, once compiled, takes over within that long
INTERP_SECONDS = 0.3
#: while a loop is compiled in the background, the interpreted loop is the first tier of
#: systems of up to this many unknowns ``n + m`` (and velocity rows); larger ones take the
#: Python path meanwhile (decision 0083: an 8-link chain's first 10 s run, 40 unknowns, took
#: 17.8 s of CPU interpreted against 3.65 s on the Python path). ``MECHSYS_JIT=0`` interprets
#: at any size
INTERP_WAIT_MAX = 12
#: interpreted steps of a stepper's first call of a loop for a system of up to 12 unknowns
#: (about 0.1 s of interpreted work each on the double pendulum), fewer in proportion
#: above (``INTERP_STEPS[name] * 12 // (n + m + k)``, at least one); the later calls take
#: the number that fits in :data:`INTERP_SECONDS` at the measured rate
INTERP_STEPS = {"loop": 32, "adams": 128}
#: the loops that run interpreted while they are compiled in the background. Not Mech's
#: Adams integrator: interpreted, its steps cost about 2.7 x the Python path's (0.85 ms a
#: step of the double pendulum against 0.3 ms), and the cold start's 10 s Adams run took
#: 6.0 s of CPU to its first result (the target: 5 s; decisions 0077, 0082), so its Python
#: driver keeps the steps while it is compiled (the same step code, interpreted, with the
#: Python derivative: decision 0088). With ``MECHSYS_JIT=0`` every loop runs
#: interpreted, Adams too (nothing is compiled then)
INTERP_LOOPS = frozenset({"loop", "derivative", "path_acc"})


def _call_size(store: dict, name: str, cap: int, least: int, unknowns: int) -> int:
    r"""The steps of the next call of the stepping loop ``name`` in one tier: the number the
    tier's last call measured (``store``, by :func:`_record_rate`), or on the first call
    ``cap`` scaled to the size, :math:`\max(k_{min}, \lfloor 12\,\mathit{cap} / \max(12,
    n + m + k_v) \rfloor)` (the whole ``cap`` up to 12 unknowns)."""
    k = store.get(name)
    return max(least, cap * 12 // max(12, unknowns)) if k is None else k


def _record_rate(store: dict, name: str, steps: int, spent: float, seconds: float,
                 least: int, most: float = float("inf")) -> None:
    """Store in ``store`` the steps that fit in ``seconds`` at the rate of a call that took
    ``steps`` in ``spent`` seconds, within ``[least, most]``; a call that took no step (a
    hand-over) sets no rate."""
    if steps > 0 and spent > 0:
        store[name] = int(min(max(least, int(seconds * steps / spent)), most))


def _steps_at(name: str) -> int:
    """The position of ``max_steps`` among the arguments of the loop ``_state[name]``."""
    import inspect

    key = "steps_at_" + name
    if _state.get(key) is None:
        _state[key] = list(inspect.signature(_state[name].py_func).parameters).index("max_steps")
    return _state[key]


_state: dict = {"loop": None, "adams": None, "workspace": None, "derivative": None, "coef": None,
                "gesv": None, "path_acc": None}


def _background() -> bool:
    """Whether a missing loop is compiled in the background (``MECHSYS_COMPILE``, decision
    0064)."""
    return _jit_runtime.compile_policy() == "background"


def _coefficients(solver):
    """``(method, A, B, C, E3, E5, D)`` of ``_jit_free_loop.runge_kutta`` for the SciPy
    ``solver`` (DOP853, or RK45: its ``E`` and ``P`` in the places of ``E5`` and ``D``): the
    registry's method of that stepper class (``_methods``) and its tableau, our own
    (``_tableaus``, decision 0038), not SciPy's private modules."""
    import scipy.integrate

    from . import _jit_free_loop

    spec = next(m for m in _methods.METHODS.values()
                if m.compiled == "runge_kutta" and isinstance(solver, getattr(scipy.integrate, m.scipy)))
    key = "coef_" + spec.name
    if _state.get(key) is None:
        tableau = getattr(_tableaus, spec.tableau)
        if len(tableau) == 5:          # one error estimator (RK45): in the place of E5
            A, B, C, E, P = tableau
            tableau = (A, B, C, np.zeros(1), E, P)
        code = getattr(_jit_free_loop, spec.scipy)     # the loop's code of the method
        _state[key] = (code,) + tuple(np.ascontiguousarray(a, dtype=float) for a in tableau)
    return _state[key]


def _lapack() -> np.ndarray:
    """Addresses of dgetrf, dgecon, dgetrs (as the sweep), dgesv, dgbtrf and dgbtrs."""
    if _state["gesv"] is None:
        from scipy.linalg import cython_lapack

        gesv = _jit_runtime.capsule_address(cython_lapack.__pyx_capi__["dgesv"])
        _state["gesv"] = np.concatenate((_jit_runtime.lapack(), [gesv],
                                         _jit_runtime.band_lapack())).astype(np.int64)
    return _state["gesv"]


class _Blocks:
    """The block path's structure (``_jit_free_loop._accel_blocks``): the mass matrix is
    block-diagonal, one block per body (model variables: one each), positive definite at the
    start or made so by the Jacobian's rows on that block alone (Euler parameters: the
    normalisation row; decision 0032); the Jacobian's rows couple through common blocks,
    so ``S = J M^-1 J^T`` and the projection's ``J^ J^T`` are banded with ``bandwidth``
    (the largest distance of two rows that share a block).

    ``arrays``: ``bstart`` (blocks + 1) first coordinate of each block; ``boff`` (blocks + 1)
    offsets of the blocks in the packed ``M`` store; ``rptr`` (m + 1), ``rblk`` the blocks
    each row touches, the rows in the structure's order: the system's, or (``rptr`` then
    (2 m + 1,)) the order ``rptr[m + 1:]`` that narrows the band (:func:`_row_order`);
    ``roff`` (len(rblk) + 1) offsets of the (row, block) segments;
    ``jpos`` (nnz,) segment position of each Jacobian value; ``bsize`` (blocks,); ``mpos``
    (M nonzeros + A,) packed position of each mass-matrix value, then the ``A`` rows of
    ``J`` that regularise singular blocks (Euler parameters; ``_jit_free_loop._regularise``);
    ``segs`` (segments, 3): the row, the segment offset and the block of every (row, block)
    segment, ordered by block and then row: each block couples every pair of its rows
    (``_jit_free_loop._gram``). (The list of every coupled pair of rows, five integers per
    three products, was six times the Jacobian's segments: at N = 1024 it alone outgrew the
    core's cache between two evaluations.)"""

    def __init__(self, arrays, bandwidth):
        self.arrays, self.bandwidth = arrays, int(bandwidth)

    @staticmethod
    def none():
        z = np.zeros(1, dtype=np.int64)
        return (z, z, z, z, z, z, z, z, np.zeros((1, 3), dtype=np.int64))

    @classmethod
    def of(cls, system, p, start):
        """The structure, or None when the mass matrix is not block-diagonal by bodies or a
        block is neither regular at the start (:func:`_regular`) nor made so by the rows on
        it alone (then the augmented system is solved whole)."""
        got = _block_structure(system)
        if got is None:
            return None
        (bstart, boff, rptr, rblk, roff, jpos, bsize, mpos, segs), bw, rows_blocks, order = got
        n, m = system.n, system.m
        t0, q0 = start
        dyn = system.dynamics
        # the mass matrix in the loop's packed block store (not dense n x n: 75 MB for a
        # 1024-link chain at every run's plan), summed as the dense matrix would be
        vals = dyn.f_terms(dyn.pack(t0, q0, np.zeros(n), np.zeros(m), p, np.zeros(n)))
        Mst = np.zeros(boff[-1])
        np.add.at(Mst, mpos, vals[:len(mpos)])
        J, own = None, []
        for b in _irregular(Mst, boff, bsize):
            # a singular block (Euler parameters): regularised by the rows on it alone, as
            # the loop does it (_jit_free_loop._regularise)
            a, z = bstart[b], bsize[b]
            B = Mst[boff[b]:boff[b] + z * z].reshape(z, z).copy()
            rows = [i for i, r in enumerate(rows_blocks) if r == [b]]
            if J is None:
                J = system.jacobian(t0, q0, p)
            if not rows or not all(_regularise(B, J[i if order is None else order[i], a:a + z])
                                   for i in rows) or not _regular(B):
                return None
            own += rows
        mpos = np.concatenate((mpos, np.array(own, dtype=np.int64)))
        return cls((bstart, boff, rptr, rblk, roff, jpos, bsize, mpos, segs), bw)


def _block_structure(system):
    """The block path's arrays that depend only on the system (``_Blocks``' layout, ``mpos``
    without regularising rows), its bandwidth, the rows' blocks in the structure's order and
    that order (None: the system's); None when the mass matrix is not block-diagonal by
    bodies, or above ``SPARSE_THRESHOLD`` unknowns when ``m bw^2`` exceeds ``BLOCK_WORK``.
    Made once per system (a 256-link chain: 10 ms) and ``BLOCK_WORK``."""
    key, got = system.__dict__.get("_jit_block_structure", (None, None))
    if key == BLOCK_WORK:
        return got
    got = _make_block_structure(system)
    system.__dict__["_jit_block_structure"] = (BLOCK_WORK, got)
    return got


def _make_block_structure(system):
    """:func:`_block_structure`, made."""
    n, m = system.n, system.m
    spans = sorted((sl.start, sl.stop) for sl in system.layout.body_slices.values())
    bstart, j = [], 0
    for a, b in spans + [(n, n)]:
        while j < a:                  # model variables between bodies: one block each
            bstart.append(j)
            j += 1
        if a < n:
            bstart.append(a)
            j = b
    bstart.append(n)
    bstart = np.array(bstart, dtype=np.int64)
    bsize = np.diff(bstart)
    block_of = np.repeat(np.arange(len(bsize)), bsize)
    dyn = system.dynamics
    Mr, Mc = np.asarray(dyn.M_rows, dtype=np.int64), np.asarray(dyn.M_cols, dtype=np.int64)
    if np.any(block_of[Mr] != block_of[Mc]):
        return None
    boff = np.concatenate(([0], np.cumsum(bsize**2))).astype(np.int64)
    b = block_of[Mr]
    mpos = (boff[b] + (Mr - bstart[b]) * bsize[b] + (Mc - bstart[b])).astype(np.int64)
    jr = np.asarray(system.jac_rows, dtype=np.int64)
    jc = np.asarray(system.jac_cols, dtype=np.int64)
    on_row: list = [set() for _ in range(m)]
    for i, c in zip(jr.tolist(), block_of[jc].tolist()):
        on_row[i].add(c)
    blocks_of_row = [sorted(r) for r in on_row]
    # the rows in the structure's order (``order[r]``: the system's row at place r)
    order = _row_order(blocks_of_row, len(bsize)) if m <= n and n + m > SPARSE_THRESHOLD \
        else None
    place = np.arange(m, dtype=np.int64)
    if order is not None:
        place[order] = np.arange(m)
    rows_blocks = blocks_of_row if order is None else [blocks_of_row[i] for i in order]
    rptr = np.concatenate(([0], np.cumsum([len(r) for r in rows_blocks]))).astype(np.int64)
    rblk = np.array([b for r in rows_blocks for b in r], dtype=np.int64)
    roff = np.concatenate(([0], np.cumsum(bsize[rblk]))).astype(np.int64)
    where = {(i, b): roff[rptr[i] + k] for i, r in enumerate(rows_blocks)
             for k, b in enumerate(r)}
    jpos = np.array([where[(i, block_of[c])] + c - bstart[block_of[c]]
                     for i, c in zip(place[jr].tolist(), jc.tolist())], dtype=np.int64)
    bw = _bandwidth(rows_blocks)
    if n + m > SPARSE_THRESHOLD and m * bw**2 > BLOCK_WORK:
        # (never the block path: its couplings grow with the band's square; a star's hub)
        return None
    if order is not None:
        # (the loop reads the order after rptr's m + 1 entries: rptr.size > m + 1)
        rptr = np.concatenate((rptr, order)).astype(np.int64)
    # the segments by block, then row: each block couples its rows (the band of J W, J^ J^T)
    segs = sorted((b, i, int(roff[rptr[i] + k])) for i, r in enumerate(rows_blocks)
                  for k, b in enumerate(r))
    segs = np.array([(i, o, b) for b, i, o in segs], dtype=np.int64).reshape(-1, 3)
    return ((bstart, boff, rptr, rblk, roff, jpos, bsize, mpos, segs), bw, rows_blocks, order)


def _irregular(Mst, boff, bsize) -> list:
    """The blocks of the mass matrix that are not regular (:func:`_regular`), from its packed
    block store ``Mst`` (block ``b``: ``Mst[boff[b]:boff[b + 1]]``, row-major ``z x z``),
    tested a stack of blocks of one size at a time."""
    bad = []
    for z in np.unique(bsize):
        which = np.flatnonzero(bsize == z)
        idx = boff[which][:, None] + np.arange(z * z)
        bad += which[~_pivots_ok(Mst[idx].reshape(-1, z, z))].tolist()
    return sorted(bad)


def _pivots_ok(B) -> np.ndarray:
    """(k,) bool for a stack ``B`` (k, z, z) of blocks: :func:`_regular`'s test of each."""
    d = np.diagonal(B, axis1=1, axis2=2)
    ok = (d > 0).all(axis=1)
    w = 1.0 / np.sqrt(np.where(d > 0, d, 1.0))
    try:
        L = np.linalg.cholesky(B * w[:, :, None] * w[:, None, :])
    except np.linalg.LinAlgError:
        # (one block of the stack is not positive definite: each on its own)
        if len(B) == 1:
            return np.zeros(1, dtype=bool)
        return np.concatenate([_pivots_ok(b[None]) for b in B])
    return ok & (np.diagonal(L, axis1=1, axis2=2).min(axis=1) ** 2 > BLOCK_PIVOT)


def _bandwidth(rows_blocks) -> int:
    """The largest distance of two rows that share a block (the band of ``J M^-1 J^T``)."""
    touching: dict = {}
    for i, r in enumerate(rows_blocks):
        for b in r:
            lo, hi = touching.get(b, (i, i))
            touching[b] = (min(lo, i), max(hi, i))
    return max((hi - lo for lo, hi in touching.values()), default=0)


def _row_order(rows_blocks, nblk):
    """A reverse Cuthill-McKee order of the rows (rows adjacent when they share a block)
    when the rows' own band is wider than ``2 BLOCK_BAND`` and the order at least halves it
    (``order[r]``: the row at place ``r``), else None: the rows keep their order. Asked only
    above ``SPARSE_THRESHOLD`` unknowns, where the band decides whether the block path runs
    at all. A spatial model lists each body's Euler-parameter normalisation after every
    joint, and the n-four-bar its loops' equations by kind, which makes the band as wide as
    the model (24 rods: 72; 40 loops: 161; 6 and 5 in this order). Smaller systems and
    narrow bands keep their order, and so their numbers: near a singular instant the block
    path's hand-over test (the spread of the Cholesky diagonal) depends on the order."""
    import scipy.sparse as sps
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    m = len(rows_blocks)
    natural = _bandwidth(rows_blocks)
    if m < 3 or natural <= 2 * BLOCK_BAND:
        return None
    rows = [i for i, r in enumerate(rows_blocks) for _ in r]
    cols = [b for r in rows_blocks for b in r]
    inc = sps.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(m, max(nblk, 1)))
    order = reverse_cuthill_mckee((inc @ inc.T).tocsr(), symmetric_mode=True).astype(np.int64)
    if 2 * _bandwidth([rows_blocks[i] for i in order]) > natural:
        return None
    return order


def _regular(B) -> bool:
    """A mass block the block path can invert: positive diagonal and its unit-diagonal form
    ``D^-1/2 B D^-1/2`` (free of the units of the coordinates) positive definite with
    Cholesky pivots above ``sqrt(BLOCK_PIVOT)``. A block singular in exact arithmetic (Euler
    parameters: ``M e = 0``) can pass a plain Cholesky with a pivot at the rounding level,
    and its inverse is then noise."""
    return bool(_pivots_ok(np.asarray(B)[None])[0])


def _regularise(B, j) -> bool:
    """``B += w j^T j`` in place, ``w = 1 / sum_t j_t^2 / B_tt`` (the term has unit size in
    the unit-diagonal form); nothing for a row that is zero on the block. False: a diagonal
    entry is not positive (a massless body: the loop would hand over). The Python twin of
    ``_jit_free_loop._regularise``, for the test at the start."""
    diag = np.diag(B)
    if not (diag > 0).all():
        return False
    d = float(np.sum(j * j / diag))
    if d > 0:
        B += np.outer(j / d, j)
    return True


_NO_EXPAND = np.zeros(0, dtype=np.int64)


def _constraint_entries(system, *kernels) -> list:
    """:func:`~._jit_runtime.kernel_entry` of each of the constraint kernels ``kernels``, or
    rows of zeros (never called) when the system has no constraint equation."""
    if system.m:
        return [kernel_entry(k) for k in kernels]
    return [((0, 0, 0, 0, 0), _NO_EXPAND)] * len(kernels)


_WORKSPACES: dict = {}   # (system id, structure) -> (system, its last stepper (weak), workspace)


def _workspace(stepper, system):
    """The loops' work arrays for ``stepper``: those of the last stepper of the same system
    and structure once that one is gone (its run is over: nothing else holds them), else new
    ones. Allocating them costs about 50 µs, a sixth of a short simulation's overhead."""
    import weakref

    key = (id(system), stepper.mode, stepper.p.size, stepper.kp.tobytes(), stepper.kk,
           stepper.jr.size, stepper.bw, tuple(a.tobytes() for a in stepper.blk_i[0]),
           stepper.n, stepper.m, tuple(a.tobytes() for a in stepper.blk_i[3]))
    got = _WORKSPACES.get(key)
    if got is not None and got[0] is system and got[1]() is None and stepper.mode < 2:
        ws = got[2]
    else:
        ws = _state["workspace"](stepper.kp, stepper.n, stepper.m, stepper.p.size, stepper.kk,
                                 stepper.jr.size, stepper.mode, stepper.blk_i, stepper.bw)
    if len(_WORKSPACES) >= 32 and key not in _WORKSPACES:
        _WORKSPACES.clear()
    _WORKSPACES[key] = (system, weakref.ref(stepper), ws)
    return ws


def _projection_part(system):
    r"""The projection's structure for :func:`_two_structures`: ``(FixedPattern, head, pos,
    kperm, dpos)`` of :math:`\begin{bmatrix} I & J^T \\ \hat J & 0 \end{bmatrix}`
    (``_patterns.projection_pattern``, the Python path's; kernel values the Jacobian's, each
    twice, the identity at ``dpos``), or None when the Jacobian has a repeated entry (the row
    scales are taken entry by entry)."""
    n, m = system.n, system.m
    jr = np.asarray(system.jac_rows, dtype=np.int64)
    jc = np.asarray(system.jac_cols, dtype=np.int64)
    nnz = jr.size
    if np.unique(jr * max(n, 1) + jc).size != nnz:
        return None
    pat, slots = projection_pattern(system)
    inv = system._csc_structure()[0]
    at = pat._pos[np.concatenate((slots[:n], slots[n + inv], slots[n + nnz + inv]))]
    return (pat, [n + m, 2 * nnz, pat.s_indices.size, 0, nnz, 0, 0], at[n:],
            np.concatenate((np.arange(nnz), np.arange(nnz))), at[:n])


def _two_structures(first, second, extra=()):
    """The arrays that never change of ``_jit_free_loop``'s two-matrix structure (see above
    its ``_slu_factor``): ``first``, ``second`` as :func:`_projection_part` returns them,
    ``extra`` the kind's numbers after the offsets."""
    from ._jit_free_loop import SECOND

    pat1, head1, pos1, kperm1, dpos1 = first
    pat2, head2, pos2, kperm2, dpos2 = second
    N = pat1.size
    offsets = [pos1.size, N + 1, pat1.s_indices.size, 2 * N, dpos1.size]
    assert len(head1) + len(head2) == SECOND and pos1.size == kperm1.size
    i64 = lambda a: np.ascontiguousarray(a, dtype=np.int64)   # noqa: E731
    return ((pat1, pat2), np.array(head1 + head2 + offsets + list(extra), dtype=np.int64),
            *(i64(np.concatenate(ab)) for ab in (
                (pos1, pos2), (kperm1, kperm2), (pat1.s_indptr, pat2.s_indptr),
                (pat1.s_indices, pat2.s_indices),
                (pat1.row_perm, pat1.perm, pat2.row_perm, pat2.perm), (dpos1, dpos2))))


def _with_storage(got):
    """``got`` (:func:`_two_structures`) with the factors' capacities as the Python path has
    grown them so far and the sparse LU's integer store (one per stepper)."""
    from ._jit_sparse import IWORK

    (pat1, pat2), info = got[0], got[1].copy()
    info[5:7], info[12:14] = pat1._cap, pat2._cap
    size = max(2 * (p.size + 1) + (IWORK + 1) * p.size + sum(p._cap) for p in (pat1, pat2))
    return (info, *got[2:], np.zeros(size, dtype=np.int64), np.zeros((1, 5), dtype=np.int64))


def _sparse_structure(system, fk, start=None):
    """The structure of ``_jit_free_loop._accel_sparse`` (see there) for a large system's
    augmented matrix by the compiled sparse LU: the projection's matrix first, then the
    augmented one (:func:`_two_structures`); None for a Jacobian with a repeated entry. The
    pattern is the Python path's when that one is not banded (trees of many branches: the
    same LU, the same numbers), else its sparse twin (:func:`_sparse_twin`: a chain the block
    path cannot take; ``start = (t0, q0, p)`` sizes its storage). Made once per pattern; the
    sparse LU's integer storage anew per stepper."""
    pat = fk.pattern
    if pat.banded:
        pat = _sparse_twin(system, fk, start)
    if not hasattr(pat, "s_indptr"):
        return None
    got = getattr(pat, "_jit_free_sparse", None)
    if got is None:
        first = _projection_part(system)
        got = () if first is None else _two_structures(first, (
            pat, [pat.size, len(fk._perm), pat.s_indices.size, fk.k_M, fk.k_J, 0, 0],
            pat._pos, np.asarray(fk._perm, dtype=np.int64), np.zeros(0, dtype=np.int64)))
        pat._jit_free_sparse = got
    return _with_storage(got) if got else None


def _sparse_twin(system, fk, start):
    """The augmented matrix's pattern for the compiled sparse LU (``FixedPattern(...,
    sparse=True)``: minimum-degree ordering) beside the banded one the Python path factorises
    by LAPACK (kept: the Python path's band LU is the faster of the two from Python, and the
    two loops then solve by independent factorisations). Made once per kernel. The Python
    path never factorises it, so it cannot grow its storage when a run outgrows it: one
    factorisation at ``start`` (``(t0, q0, p)``, at rest) sizes it here."""
    pat = fk.pattern
    twin = getattr(pat, "_sparse_twin", None)
    if twin is None:
        twin = FixedPattern(pat.indptr, pat.indices, pat.size, sparse=True)
        pat._sparse_twin = twin
    if start is not None and hasattr(twin, "s_indptr"):
        t0, q0, p = start
        n, m = system.n, system.m
        K, _ = fk(float(t0), np.asarray(q0, dtype=float), np.zeros(n), np.zeros(m), p)
        try:
            twin.factor(K.data)
        except Singular:
            pass                  # (the run hands over where the Python path decides)
    return twin


def _path_sparse_structure(path):
    """The structure of ``_jit_free_loop._path_velocity_sparse`` (see ``PATH_EXTRA`` there)
    for a path above ``SMALL_LU`` coordinates, or None (a Jacobian with a repeated entry).
    Both patterns are the Python path's: the projection's (:func:`_projection_part`) and the
    velocity system's (``PathSystem._pattern``). Made once per path; the sparse LU's
    integer storage anew per stepper."""
    got = path.__dict__.get("_jit_sparse")
    if got is None:
        first = _projection_part(path.system)
        if first is None:
            got = ()
        else:
            rK, cK, patK, slotsK = path._pattern()
            n = path.system.n
            got = _two_structures(first, (
                patK, [n, 0, patK.s_indices.size, 0, 0, 0, 0], patK._pos, slotsK,
                np.concatenate((rK, cK))),
                extra=[len(path.psi), 0, 0, 0, 0, 0, 0, int(path.linear), rK.size,
                       path._b_rows.size])
        path._jit_sparse = got
    return _with_storage(got) if got else None


def _newton_band(system):
    """The structure array of ``_jit_free_loop._newton_accel_band`` (see there): the Newton
    matrix's ``FixedPattern`` (``_patterns.free_newton_pattern``, the Python path's) and where
    each term's values go in it, and for a pattern that is not banded (trees of many
    branches) the compiled sparse LU's integer store; None when such a pattern has no
    compiled LU (the Python path's SuperLU)."""
    from ._jit_free_loop import BAND_HEAD
    from ._jit_sparse import IWORK

    rows, cols, pat = free_newton_pattern(system)
    sparse = not pat.banded
    if sparse and (_sparse_lu() is None or not hasattr(pat, "s_indptr")):
        return None
    dyn = system.dynamics
    n, m = system.n, system.m
    N = n + m

    def slot(r, c):
        return pattern_slots(rows, cols, N, r, c)

    z = np.zeros(0, dtype=np.int64)
    jr, jc = np.asarray(system.jac_rows, dtype=np.int64), np.asarray(system.jac_cols, dtype=np.int64)
    uniq, uid = np.unique(jr * n + jc, return_inverse=True)
    urow, ucol = uniq // n, uniq % n
    sM = slot(dyn.M_rows, dyn.M_cols)
    sA = slot(dyn.dA_rows, dyn.dA_cols) if dyn.depends_on_qdd else z
    sD = slot(dyn.dQ_rows, n + np.asarray(dyn.dQ_cols, dtype=np.int64)) if dyn.depends_on_lambda \
        else z
    diag = np.arange(n)
    present = np.isin(diag * N + diag, cols * N + rows)
    if not present.all():
        return None          # (a coordinate without mass: the projection needs the diagonal)
    k = slot(diag, diag)
    P = rows.size
    if sparse:
        # (the sizes of _jit_linalg.big_sizes; the integer store starts with B's structure)
        capL, capU = pat._cap
        bw, store = [SPARSE_BW, P, capL, capU], P + capL + capU + 3 * N
        SI = np.concatenate([pat.s_indptr, pat.s_indices,
                             np.zeros((IWORK + 3) * N + 2 + capL + capU, dtype=np.int64)])
    else:
        bw, store, SI = [0, 0, 0, 0], pat._ld * N, z
    head = [pat.kl, pat.ku, 0 if sparse else pat._ld, P, uniq.size, sM.size, sA.size, sD.size,
            n, *bw, store]
    assert len(head) == BAND_HEAD
    return np.concatenate([np.array(head), pat._pos, rows, cols, pat.row_perm, pat.perm, sM, sA,
                           sD, uid.ravel(), urow, ucol, slot(n + urow, ucol),
                           slot(ucol, n + urow), k, SI]).astype(np.int64)


class StepDense:
    """The dense output of one compiled Runge-Kutta step from ``t_old`` to ``t``: ``FD``
    (8, N2) as ``_jit_free_loop.runge_kutta`` leaves it (the coefficients ``F``, the state
    at the start in row 7), the polynomials the loop evaluates at output times (SciPy's
    ``Dop853DenseOutput``; ``RkDenseOutput``), to rounding. With ``x = (s - t_old) / h``:

    * DOP853: ``y(s) = y_old + ((((((F_6 x + F_5) (1-x) + F_4) x + F_3) (1-x) + F_2) x
      + F_1) (1-x) + F_0) x``;
    * RK45: ``y(s) = y_old + h (Q_0 x + Q_1 x^2 + Q_2 x^3 + Q_3 x^4)``.

    Example: ``dense = StepDense(0.0, 0.1, FD, DOP853); y_mid = dense(0.05)``."""

    def __init__(self, t_old: float, t: float, FD: np.ndarray, method: int):
        from ._jit_free_loop import RK45 as RK45_CODE

        self.t_old, self.t, self.h = t_old, t, t - t_old
        self.F, self.y_old = FD[:7].copy(), FD[7].copy()
        self.rk45 = method == RK45_CODE

    def __call__(self, s: float) -> np.ndarray:
        # the nested forms expanded into one weight per row, applied in one product
        x = (s - self.t_old) / self.h
        if self.rk45:
            w = np.array([x, x * x, x ** 3, x ** 4]) * self.h
            return w @ self.F[:4] + self.y_old
        u = 1.0 - x
        w = np.array([x, x * u, x * x * u, (x * u) ** 2, x ** 3 * u * u, (x * u) ** 3,
                      x ** 4 * u ** 3])
        return w @ self.F + self.y_old


def _holding(stepper, *kernels):
    """``stepper``, holding the kernels whose entry points it calls (``stepper.kernels``): a
    kernel without LLVM code is called through a :mod:`ctypes` callback
    (:func:`~._jit_runtime.python_entry`, decision 0084) that lives as long as its kernel, so
    the addresses in ``stepper.kp`` and its structure stay valid while the stepper lives."""
    stepper.kernels = tuple(k for k in kernels if k is not None)
    return stepper


def _loops_at_hand() -> bool:
    """Whether the loops' code can run, compiled or interpreted: Numba importable and the
    loops' module imported. Its import checks Numba's on-disk cache first (``_jit_cache``);
    with ``MECHSYS_JIT=0`` (nothing compiled, the loops interpreted: decision 0082) a cache
    refused as unsafe (:class:`~mechsys.CacheError`, whose message offers ``MECHSYS_JIT=0``
    as the way around it) leaves the run to the Python path instead of raising."""
    off = _jit_runtime.mode() == "off"     # (a misspelled MECHSYS_JIT raises here)
    if not _jit_runtime.available():
        return False
    if off:
        from .._errors import CacheError

        try:
            from . import _jit_free_loop  # noqa: F401
        except CacheError:
            return False
    return True


class FreeStepper:
    """The compiled stepper of one free-motion run (see the module docstring).

    ``scaling``: the run's :class:`~mechsys.solvers._linalg.Scaling`; ``rows0`` (m,): the
    row scales of the zone guard (at the start of the motion); ``robust``: the run passes
    singular instants (the zone guard applies); ``correction``: project after each step;
    ``t_eval`` (k,) or None: output times."""

    def __init__(self, system, p, scaling, rows0, robust, correction, t_eval, kernels, fk,
                 blocks=None, expand=(_NO_EXPAND,) * 3, gen=None, path=None, newton=None,
                 newton_tol=1e-10, sparse=None, rows=None):
        from ._jit_free_loop import (
            AUGMENTED,
            BLOCK,
            GEN_AUGMENTED,
            GEN_TREE,
            NEWTON,
            PATH,
            PATH_EXTRA,
            ROLLING,
            SPARSE,
        )

        kern, fpos, fvel = kernels
        n, m = system.n, system.m
        N = n + m
        self.n, self.m = n, m
        #: the velocity constraints' rows (``ROLLING``): ``(k, their kernel's row, expansion
        #: map)``; the multipliers are ``(lambda, mu)``, ``nl = m + k`` of them
        kv = 0 if rows is None else int(rows[0])
        self.kv, self.nl = kv, m + kv
        #: the state's size: (q, qd) for free motion, q for a path
        self.ny = n if path is not None else 2 * n
        self.kp = np.array([kern, fpos, fvel], dtype=np.int64)
        self.blocks = blocks
        #: how the compiled loop solves for the accelerations: "block" (Schur complement on
        #: the block-diagonal mass matrix, banded), "augmented" (the whole system, dense),
        #: "recursive" (Gen joints: the articulated-body recursion) or "recursive+augmented"
        #: (Gen joints with constraint equations: the composite-body mass matrix in the
        #: augmented system), "sparse" (the augmented system by the compiled sparse LU of its
        #: fixed pattern: trees whose band is wide)
        if rows is not None:
            self.mode, self.solver = ROLLING, "augmented"
        elif path is not None:
            self.mode, self.solver = PATH, "path"
        elif sparse is not None:
            self.mode, self.solver = SPARSE, "sparse"
        elif newton is not None:
            self.mode, self.solver = NEWTON, "newton"
        elif gen is not None:
            self.mode = GEN_TREE if gen.tree else GEN_AUGMENTED
            self.solver = "recursive" if gen.tree else "recursive+augmented"
        else:
            self.mode = AUGMENTED if blocks is None else BLOCK
            self.solver = "augmented" if blocks is None else "block"
        if path is not None:
            # the path's numbers in the block structure's first array: [k, npar, the
            # holonomic velocity kernel's row] (the loops hand the derivative one kernel row);
            # a large path's sparse structure with them (_path_sparse_structure)
            self.flat_t = self.mp = np.zeros(0, dtype=np.int64)
            k, linear, big = path
            if big is None:
                blk = (np.array([k, len(p), *fvel, int(linear)], dtype=np.int64),
                       *_Blocks.none()[1:])
            else:
                blk = big
                blk[0][PATH_EXTRA + 1] = len(p)
                blk[0][PATH_EXTRA + 2:PATH_EXTRA + 7] = fvel
            self.bw = 0
        elif newton is not None:
            self.flat_t = self.mp = np.zeros(0, dtype=np.int64)
            blk, self.bw = newton, 0
        elif sparse is not None:
            self.flat_t = self.mp = np.zeros(0, dtype=np.int64)
            blk, self.bw = sparse, 0
        elif blocks is None and gen is None:
            flat = np.asarray(fk._flat, dtype=np.int64)
            Nk = N + kv                  # (bordered by the velocity rows: ROLLING)
            self.flat_t = (flat % N) * Nk + flat // N     # K^T in C order = K in Fortran order
            self.mp = np.asarray(fk._map, dtype=np.int64)
            blk, self.bw = _Blocks.none(), 0
        elif blocks is None:
            self.flat_t = self.mp = np.zeros(0, dtype=np.int64)
            blk, self.bw = _Blocks.none(), 0
        else:
            self.flat_t = self.mp = np.zeros(0, dtype=np.int64)
            blk, self.bw = blocks.arrays, blocks.bandwidth
        # the loop's structure argument: (block path, Gen tree, the kernels' output maps)
        if rows is None:
            ri = (np.zeros(7, dtype=np.int64), _NO_EXPAND)
        else:
            ri = (np.array([*rows[1], kv, len(p)], dtype=np.int64), rows[2])
        self.blk_i = (blk, GenTree.none() if gen is None else gen.arrays, tuple(expand), ri)
        if path is not None:
            # the velocity constraints' outputs: [psi, psi_qd (dense, or its nonzeros), rest]
            self.kk = int(2 * path[0] + (path[0] * n if path[2] is None
                                         else path[2][0][PATH_EXTRA + 9]))
        elif newton is not None:
            self.kk = int(newton[0][0]) + 2 * n           # [M values, Q, Qv]
        else:
            self.kk = 0 if gen is not None else int(fk.k_M + fk.k_J)
        self.p = np.ascontiguousarray(p, dtype=float)
        self.jr = system.jac_rows.astype(np.int64)
        self.jc = system.jac_cols.astype(np.int64)
        self.rows0 = np.ascontiguousarray(rows0 if rows0 is not None else np.ones(m), dtype=float)
        self.columns = np.ascontiguousarray(scaling.columns, dtype=float)
        self.offset = float(scaling.offset)
        self.robust = bool(robust)
        self.correction = bool(correction) and m + kv > 0
        self.t_eval = np.zeros(0) if t_eval is None else np.ascontiguousarray(t_eval, dtype=float)
        k = len(self.t_eval)
        self.ET, self.EY = np.zeros(k), np.zeros((k, self.ny))
        self.EQDD, self.ELAM = np.full((k, n), np.nan), np.full((k, self.nl), np.nan)
        #: steps taken by the compiled loop, and by the same loop interpreted (decision 0077)
        self.steps = 0
        self.interpreted_steps = 0
        #: the tier of the last loop call: "compiled", "interpreted" or None (handed over)
        self.tier = None
        #: ``MECHSYS_JIT=0``: the loops never compiled, always interpreted (decision 0082)
        self.interpret_only = _jit_runtime.mode() == "off"
        #: the steps of the next interpreted call of each stepping loop (``_interpret``)
        self._interp_steps: dict = {}
        #: ... and of the next compiled call (:meth:`budget`)
        self._call_steps: dict = {}
        if _state["loop"] is None:
            from ._jit_free_loop import adams, derivative, runge_kutta, workspace

            _state["loop"], _state["adams"], _state["workspace"] = runge_kutta, adams, workspace
            _state["derivative"] = derivative
        #: the loops' machine code specialised on this stepper's mode (``_call``)
        self._entries: dict = {}
        # the loops' work arrays, owned here for every run of this stepper (the loops borrow
        # them: decision 0021)
        self.ws = _workspace(self, system)
        if newton is not None:
            self.ws[14][:] = 1.0              # the first evaluation's multipliers (Python: ones)
            self.ws[16][0][7][0] = newton_tol   # then the column scales (the unit-free test)
            self.ws[16][0][7][1:1 + n] = self.columns

    @classmethod
    def plan(cls, system, method, p, scaling, rows0, robust, correction, t_eval, start,
             newton=None, rows=None):
        r"""The stepper when the compiled loop can run this simulation (``method``: DOP853 or
        one of Mech's Adams methods; ``start``: ``(t0, q0)``), else None.

        ``rows``: the free system's velocity constraints :math:`A \dot q + b = 0`
        (:class:`~mechsys.analyses._nonholonomic.VelocityRows`, decisions 0053, 0062): the
        kind ``ROLLING`` (:meth:`_plan_rows`; also a switched run's stage with velocity rows,
        decision 0084). Kernels without LLVM code (``Model(backend="sympy")``) are called
        through :func:`~._jit_runtime.python_entry` (decision 0084): the stepper holds them
        (:attr:`kernels`) while it lives."""
        spec = _methods.find(method)
        if spec is None or spec.compiled is None or system.n == 0:
            return None
        if not spec.runge_kutta:
            t_eval = None              # Adams output times are interpolated afterwards
        dyn = system.dynamics
        if not _loops_at_hand():
            return None
        if rows is not None:
            return cls._plan_rows(system, rows, p, scaling, correction, t_eval)
        if dyn.depends_on_lambda or dyn.depends_on_qdd:
            return cls._plan_newton(system, p, scaling, correction, t_eval, newton)
        N = system.n + system.m
        blocks = gen = sparse = None
        if getattr(dyn, "recursive", False):
            # generalized coordinates, recursive dynamics (decision 0018): the joint kernels
            # and the kernel of the rest, the recursion in the loop (dense at any size, as
            # the Python path: the mass matrix of a chain in joint coordinates is full)
            fk = None
            entries = [kernel_entry(dyn._main)]
        else:
            # the kernel the Python path uses (sparse above the threshold): compiled once
            fk = dyn.free_kernel(N > SPARSE_THRESHOLD)
            wide = N > SPARSE_THRESHOLD and not fk.pattern.banded
            if N > SMALL:
                # (the band from the structure, made once per system, before the test at
                # the start, made at every plan)
                got = _block_structure(system)
                if got is not None and not (wide and got[1] > BLOCK_BAND):
                    blocks = _Blocks.of(system, p, start)
            if wide and (blocks is None or blocks.bandwidth > BLOCK_BAND):
                # a wide band (a tree of many branches): the Python path's pattern and its
                # sparse LU, in the loop
                blocks = None
                sparse = _sparse_structure(system, fk)
                if sparse is None:
                    return None
            elif N > SPARSE_THRESHOLD and (
                    blocks is None or system.m * blocks.bandwidth**2 > BLOCK_WORK):
                # no block path (a mass block that its own rows do not make regular, or a
                # band too wide for it): the compiled sparse LU of the same pattern in the
                # loop (the Python path keeps LAPACK's band LU)
                blocks = None
                sparse = _sparse_structure(system, fk, (*start, p))
                if sparse is None:
                    return None
            entries = [kernel_entry(fk.f)]
        entries += _constraint_entries(system, system.f_position, system.f_velocity)
        if any(e is None for e in entries):
            return None
        rows = [e[0] for e in entries]
        if fk is None:
            gen = GenTree.of(system, dyn, rows[0])
            if gen is None:
                return None
        return _holding(cls(system, p, scaling, rows0, robust, correction, t_eval, rows, fk,
                            blocks, [e[1] for e in entries], gen, sparse=sparse),
                        dyn._main if fk is None else fk.f, system.f_position,
                        system.f_velocity, *getattr(dyn, "_kernels", ()))

    @classmethod
    def _plan_rows(cls, system, rows, p, scaling, correction, t_eval):
        r"""The stepper of free motion with velocity constraints (kind ``ROLLING``: the
        dense augmented system bordered by the rows ``A``, solved as
        ``analyses._nonholonomic.nonholonomic_acceleration`` solves it; the velocity
        projection onto :math:`[\Phi_q; A] \dot q = [-\Phi_t; -b]` as its
        ``project_velocities``), or None (the Python path, the same answer): loads that
        depend on the multipliers or accelerations, recursive (Gen) dynamics, more than
        ``SPARSE_THRESHOLD`` holonomic unknowns (the sparse free kernel), or a kernel
        without C entry points that none can be made for. The run passes no singular
        instant (``robust`` off, as the Python path with velocity constraints)."""
        dyn = system.dynamics
        n, m = system.n, system.m
        if dyn.depends_on_lambda or dyn.depends_on_qdd or getattr(dyn, "recursive", False) \
                or n + m > SPARSE_THRESHOLD or rows.k == 0 or len(rows.rho_sym) != rows.k:
            return None          # (rho: the rows' kernel holds [A, b, rho], rho derived)
        fk = dyn.free_kernel(False)
        entries = [kernel_entry(fk.f)] + _constraint_entries(system, system.f_position,
                                                            system.f_velocity)
        mine = kernel_entry(rows._f)
        if mine is None or any(e is None for e in entries):
            return None
        return _holding(cls(system, p, scaling, None, False, correction, t_eval,
                            [e[0] for e in entries], fk, expand=[e[1] for e in entries],
                            rows=(rows.k, mine[0], mine[1])),
                        fk.f, system.f_position, system.f_velocity, rows._f)

    @classmethod
    def _plan_newton(cls, system, p, scaling, correction, t_eval, newton):
        """The stepper for loads that depend on the multipliers or accelerations (kind
        ``NEWTON``: ``free_acceleration``'s Newton in the loop), or None: a ``Dynamics``
        (not the recursive one) and kernels with C entry points whose loads' derivatives have
        all their outputs distinct. A first stage of those derivatives (``Piecewise`` values,
        or a large kernel's gathered values: a 128-link chain's ``dQ/dlambda``) gets its room
        in the loop's work array (``workspace``); before, such a run went to the Python
        stepper whole.
        ``newton``: ``free_acceleration``'s keyword options (``tol``, ``max_iterations``).
        Above ``SMALL_LU`` unknowns the Newton matrix goes by the Python path's fixed pattern
        (``_newton_band``): banded (chains) by LAPACK's band LU, else (trees of many
        branches) by the compiled sparse LU; None only where the Python path has no
        compiled LU either (no Numba: SuperLU)."""
        dyn = system.dynamics
        n, m = system.n, system.m
        if getattr(dyn, "recursive", False):
            return None
        band = np.zeros(1, dtype=np.int64)
        if n + m > SMALL_LU:
            band = _newton_band(system)
            if band is None:
                return None
        kw = dict(newton or {})
        tol, maxit = float(kw.get("tol", 1e-10)), int(kw.get("max_iterations", 30))
        main = [kernel_entry(dyn.f_terms)] + _constraint_entries(system, system.f_position,
                                                           system.f_velocity)
        extra = _constraint_entries(system, system.f_position, system.f_gamma)
        z = np.zeros(0, dtype=np.int64)
        for flag, kern in ((dyn.depends_on_lambda, "f_dQ_dlam"), (dyn.depends_on_qdd, "f_dQ_dqdd")):
            extra.append(kernel_entry(getattr(dyn, kern)) if flag else ((0, 0, 0, 0, 0), _NO_EXPAND))
        if any(e is None for e in main + extra) or any(len(e[1]) for e in extra):
            return None
        dr, dc = ((dyn.dQ_rows, dyn.dQ_cols) if dyn.depends_on_lambda else (z, z))
        ar, ac = ((dyn.dA_rows, dyn.dA_cols) if dyn.depends_on_qdd else (z, z))
        info = [len(dyn.M_rows), int(dyn.depends_on_lambda), maxit, len(dr), len(ar), len(p)]
        for e in extra:
            info += list(e[0])
        i64 = lambda a: np.ascontiguousarray(a, dtype=np.int64)   # noqa: E731
        blk = (np.array(info, dtype=np.int64), i64(dyn.M_rows), i64(dyn.M_cols), i64(dr),
               i64(dc), i64(ar), i64(ac), band, np.zeros((1, 5), dtype=np.int64))
        return _holding(cls(system, p, scaling, None, False, correction, t_eval,
                            [e[0] for e in main], None, expand=[e[1] for e in main],
                            newton=blk, newton_tol=tol),
                        dyn.f_terms, system.f_position, system.f_velocity, system.f_gamma,
                        dyn.f_dQ_dlam if dyn.depends_on_lambda else None,
                        dyn.f_dQ_dqdd if dyn.depends_on_qdd else None)

    @classmethod
    def plan_path(cls, path, method, p, scaling, correction, t_eval):
        r"""The stepper of a nonholonomic path (:class:`~mechsys.analyses._path.PathSystem`)
        when the compiled loop can run it, else None: LLVM kernels; up to ``SMALL_LU``
        coordinates the velocity system dense (the written-out LU), above it (where the
        Python path solves it sparse) by the Python path's pattern and the compiled sparse
        LU, the projection through :math:`\begin{bmatrix} I & J^T \\ \hat J & 0 \end{bmatrix}`
        (``_path_sparse_structure``)."""
        system = path.system
        n = system.n
        spec = _methods.find(method)
        if spec is None or spec.compiled is None or n == 0 or not _loops_at_hand():
            return None
        big = None
        if n > SMALL_LU:
            if not path._sparse or _sparse_lu() is None:
                return None
            big = _path_sparse_structure(path)
            if big is None:
                return None
        if not spec.runge_kutta:
            t_eval = None
        entries = [kernel_entry(path._f)] + _constraint_entries(system, system.f_position,
                                                          system.f_velocity)
        if any(e is None for e in entries):
            return None
        return _holding(cls(system, p, scaling, None, False, correction, t_eval,
                            [e[0] for e in entries], None, expand=[e[1] for e in entries],
                            path=(len(path.psi), path.linear, big)),
                        path._f, system.f_position, system.f_velocity)

    def path_accelerations(self, path, times, Q, QD, QDD) -> int:
        """A path's accelerations at the rows of ``times``, ``Q``, ``QD`` into ``QDD`` (N, n)
        in compiled code (``_jit_free_loop.path_accelerations``); returns the first row left
        to the Python path (0 when a kernel has no C entry point)."""
        system = path.system
        sparse = self.blk_i[0][7].size > 1
        # (a large path's Jacobian from the velocity kernel, as its Python path takes it)
        entries = _constraint_entries(
            system, system.f_velocity if sparse else system.f_position, system.f_gamma)
        entries.append(kernel_entry(path._f))
        if any(e is None for e in entries):
            return 0
        if _state.get("path_acc") is None:
            from ._jit_free_loop import path_accelerations

            _state["path_acc"] = path_accelerations
        # (every compile of more than about a second is announced: decision 0044; while it
        # is compiled in the background, decision 0064, the same code interpreted for a
        # small path, decision 0077, else None: the Python path takes every point)
        got = self._call(
            "path_acc", np.array([e[0] for e in entries], dtype=np.int64),
            tuple(e[1] for e in entries), np.ascontiguousarray(times, dtype=float),
            np.ascontiguousarray(Q, dtype=float), np.ascontiguousarray(QD, dtype=float), self.p,
            self.jr, self.jc, len(path.psi), self.blk_i[0], self.ws[16][0], QDD)
        return 0 if got is None else int(got)

    def rate(self, y, row):
        """The state's derivative at ``y`` from a row the loop returned (its ``QDD``):
        ``(qd, qdd)`` for free motion, the velocities themselves for a path."""
        return row if self.ny == self.n else np.concatenate((y[self.n:], row))

    def advance(self, solver, ie: int, max_steps: int | None = None):
        """Compiled steps of the SciPy DOP853 or RK45 ``solver`` from its current state; the
        solver is left at the last accepted step (status ``"finished"`` at the end). Returns ``(status,
        T, Y, H, QDD, LAM, ie)``: the accepted steps' times, states, step sizes, accelerations
        and multipliers (NaN rows: not known), and the next output index."""
        n, m = self.n, self.m
        max_steps = self.budget("loop", CHUNK_STEPS) if max_steps is None else max_steps
        method, A, B, C, E3, E5, D = _coefficients(solver)
        T, H = np.empty(max_steps), np.empty(max_steps)
        Y = np.empty((max_steps, self.ny))
        QDD, LAM = np.empty((max_steps, n)), np.empty((max_steps, self.nl))
        state = np.array([solver.t, solver.h_abs], dtype=float)
        y = np.array(solver.y, dtype=float)
        f = np.array(solver.f, dtype=float)
        atol = np.broadcast_to(np.asarray(solver.atol, dtype=float), (self.ny,)).copy()
        t_prev = solver.t
        got = self._call(
            "loop", self.kp, _lapack(), self.p, self.flat_t, self.mp, self.kk, n, m, self.jr,
            self.jc, self.rows0, self.columns, self.offset, self.robust, self.mode,
            self.blk_i, self.ws, self.correction, 1e-12, 8, method, A, B, C, E3, E5, D,
            float(solver.rtol), atol, float(solver.max_step),
            float(solver.t_bound), float(solver.direction), state, y, f, self.t_eval, int(ie),
            int(max_steps), T, Y, H, QDD, LAM, self.ET, self.EY, self.EQDD, self.ELAM,
            np.zeros((0, self.ny)))
        if got is None:            # (being compiled in the background: hand over at once)
            return 2, T[:0], Y[:0], H[:0], QDD[:0], LAM[:0], int(ie), 0, 0
        status, steps, ie, evals, rejected, projections = got
        solver.nfev += int(evals)
        if steps:
            solver.t_old = float(T[steps - 2]) if steps >= 2 else t_prev
            solver.t, solver.y, solver.f = float(state[0]), y, f
            solver.h_abs = float(state[1])
            solver.h_previous = float(T[steps - 1] - solver.t_old)
            if status == 0:
                solver.status = "finished"
        self._count(steps)
        if self.tier == "interpreted":
            # (a short call: its rows alone are kept, not the chunk-sized arrays)
            T, Y, H, QDD, LAM = (a[:steps].copy() for a in (T, Y, H, QDD, LAM))
        return (int(status), T[:steps], Y[:steps], H[:steps], QDD[:steps], LAM[:steps], int(ie),
                int(rejected), int(projections))


    def step_again(self, solver, t: float, y: np.ndarray, f: np.ndarray, h_abs: float):
        """One compiled step of ``solver``'s method from ``(t, y, f)`` with the step size
        ``h_abs`` of an accepted step of an earlier run (so accepted again, with the same
        numbers), with its dense output: ``(t_new, y_new, StepDense)``, ``y_new`` the
        (projected) state at its end; or None where the loop hands the step over. The
        compiled runs of free motion with events find the step with an event after the run;
        this takes it again for the event's location, instead of a Python step."""
        n, m = self.n, self.m
        method, A, B, C, E3, E5, D = _coefficients(solver)
        T, H = np.empty(1), np.empty(1)
        Y = np.empty((1, self.ny))
        QDD, LAM = np.empty((1, n)), np.empty((1, self.nl))
        FD = np.empty((8, self.ny))
        state = np.array([t, h_abs], dtype=float)
        yy = np.array(y, dtype=float)
        ff = np.array(f, dtype=float)
        atol = np.broadcast_to(np.asarray(solver.atol, dtype=float), (self.ny,)).copy()
        none = np.zeros(0)
        got = self._call(
            "loop", self.kp, _lapack(), self.p, self.flat_t, self.mp, self.kk, n, m, self.jr,
            self.jc, self.rows0, self.columns, self.offset, self.robust, self.mode,
            self.blk_i, self.ws, self.correction, 1e-12, 8, method, A, B, C, E3, E5, D,
            float(solver.rtol), atol, float(solver.max_step),
            float(solver.t_bound), float(solver.direction), state, yy, ff, none, 0, 1,
            T, Y, H, QDD, LAM, none, np.zeros((0, self.ny)), np.zeros((0, n)),
            np.zeros((0, self.nl)), FD)
        if got is None:            # (being compiled in the background)
            return None
        status, steps, _, evals, _, _ = got
        solver.nfev += int(evals)
        if steps != 1:
            return None
        return float(T[0]), Y[0].copy(), StepDense(t, float(T[0]), FD, method)

    def _call(self, name: str, *args):
        """``_state[name](*args)`` (a loop of ``_jit_free_loop``) through its machine code
        specialised on this stepper's mode (``_jit_modes.entry``: the mode argument typed as
        its value, so that only this mode's solvers are compiled; decision 0044), found once
        per stepper. A compile from empty caches is announced first (``_jit_cache.notice``).

        While that machine code is compiled in the background (decision 0064) the same
        loop runs interpreted (:meth:`_interpret`, decisions 0077, 0082) when it is one of
        :data:`INTERP_LOOPS` and the system is small enough (:meth:`interpretable`), a
        bounded amount of work a call so that the caller
        asks again soon: the interpreted function is not kept, and the compiled loop takes
        the first call after its compile is done. With ``MECHSYS_JIT=0`` every loop runs
        interpreted and nothing is compiled. None: neither (the caller hands over to its
        Python path and asks again after its pause). ``self.tier`` tells which ran."""
        fn = self._entries.get(name)
        if fn is None:
            if self.interpret_only:
                got = self._interpret(name, args)
                _jit_runtime.raise_callback_error()
                return got
            from ._jit_modes import entry

            what = {"loop": "the free-motion stepper", "adams": "Mech's Adams integrator",
                    "derivative": "the free-motion derivative",
                    "path_acc": "a path's accelerations"}[name]
            fn = entry(_state[name], args, literal=(_MODE_AT[name],) if name in _MODE_AT else (),
                       say=lambda how: notice(f"{what} ({self.solver})", _COMPILE_SECONDS.get(name),
                                              background=how == "background"))
            if fn is None:
                # being compiled in the background (decision 0064)
                if name not in INTERP_LOOPS or not self.interpretable():
                    self.tier = None
                    return None
                got = self._interpret(name, args)
                _jit_runtime.raise_callback_error()
                return got
            self._entries[name] = fn
        self.tier = "compiled"
        if name not in INTERP_STEPS:
            got = fn(*args)
        else:
            began = time.perf_counter()
            got = fn(*args)
            self._rate(name, int(got[1]), time.perf_counter() - began)
        # (an interrupt a Python kernel's entry point caught: decision 0084)
        _jit_runtime.raise_callback_error()
        return got

    def budget(self, name: str, cap: int) -> int:
        r"""The steps the next compiled call of the stepping loop ``name`` may take, at most
        ``cap``: about :data:`CALL_SECONDS` of work at the rate the last call measured, or on
        the first call :math:`\max(k_{min}, \lfloor 12\,\mathit{cap} / \max(12, n + m +
        k_v) \rfloor)`, so that a call of a large system returns to the caller (progress,
        Ctrl-C) about that often. The chunks change no number: each call resumes the run
        from the state the last one left (``tests/test_free_reach.py``)."""
        return int(min(_call_size(self._call_steps, name, cap, CALL_MIN_STEPS,
                                  self.n + self.nl), cap))

    def _rate(self, name: str, steps: int, spent: float) -> None:
        """Size the next compiled call of ``name`` from this one's ``steps`` in ``spent``
        seconds (:meth:`budget`)."""
        _record_rate(self._call_steps, name, steps, spent, CALL_SECONDS, CALL_MIN_STEPS)

    def interpretable(self) -> bool:
        """Whether the loops run interpreted while their machine code is compiled in the
        background: at most :data:`INTERP_WAIT_MAX` unknowns (coordinates, multipliers and
        velocity rows). Larger systems take the Python path meanwhile, whose step costs 4 to
        19 times less there (decision 0083). ``MECHSYS_JIT=0`` interprets at any size."""
        return self.n + self.nl <= INTERP_WAIT_MAX

    def _interpret(self, name: str, args):
        r"""The loop ``_state[name]`` run interpreted (:mod:`._jit_interp`: its own code,
        the compiled loop's numbers bit for bit). A stepping loop (``loop``, ``adams``)
        takes at most ``k`` steps (its ``max_steps`` argument, made smaller): on the
        stepper's first call of it :data:`INTERP_STEPS` scaled to the size
        (:math:`k_0 = \max(1, \lfloor 12 k_s / \max(12, n + m + k_v) \rfloor)`), then the number
        that fits in :data:`INTERP_SECONDS` at the rate the last call measured,
        :math:`k = \min(\max(1, \lfloor T / (t_{call} / \mathit{steps}) \rfloor), 8 k_s)`, so
        that each call is about that much work at any size (decision 0082) and the caller
        asks for the compiled loop again that often."""

        from ._jit_interp import interpreted

        self.tier = "interpreted"
        fn = interpreted(_state[name])
        if name not in INTERP_STEPS:
            return fn(*args)
        at = _steps_at(name)
        cap = INTERP_STEPS[name]
        args = list(args)
        args[at] = min(int(args[at]),
                       _call_size(self._interp_steps, name, cap, 1, self.n + self.nl))
        began = time.perf_counter()
        got = fn(*args)
        _record_rate(self._interp_steps, name, int(got[1]), time.perf_counter() - began,
                     INTERP_SECONDS, 1, 8 * cap)
        return got

    def _count(self, steps) -> None:
        """Add ``steps`` to the count of the tier that took them."""
        if self.tier == "interpreted":
            self.interpreted_steps += int(steps)
        else:
            self.steps += int(steps)

    def derivative(self, t: float, y: np.ndarray):
        """``(f, lam)``: the derivative ``f = (qd, qdd)`` (2n,) and the multipliers (m,) at
        ``(t, y)`` computed as the compiled loop computes them (about 10 µs from Python
        instead of about 40 µs for the Python path's), or None where the Python path must
        decide (its special handling: the loops hand over there too)."""
        n, m = self.n, self.m
        if self.tier is None and "loop" not in self._entries and "adams" not in self._entries \
                and not self.interpret_only and _background():
            # a speed-up of SciPy's set-up alone (two evaluations a run): compiled only once
            # a loop runs, so that a first run's background compile is the loop's (0064)
            return None
        f, lam = np.empty(self.ny), np.empty(self.nl)
        ok = self._call(
            "derivative", self.kp, _lapack(), self.p, self.flat_t, self.mp, self.kk, n, m,
            self.jr, self.jc, self.rows0, self.columns, self.robust, self.mode, self.blk_i,
            self.ws, float(t),
            np.ascontiguousarray(y, dtype=float), f, lam)
        return (f, lam) if ok else None

    def fun(self, python_fun, switch):
        """``python_fun(t, y) -> f`` answered by :meth:`derivative` while ``switch[0]`` is
        true and it can (SciPy's set-up of the solver: its first derivative and initial
        step). The steps the Python loop takes after a hand-over keep ``python_fun``: its
        zone guard marks the steps with a kink, which the compiled derivative does not.

        The function holds the stepper weakly: SciPy's solver objects live in reference
        cycles (freed by the garbage collector, not when the run ends), and a strong
        reference would keep the stepper alive with them, so that the next run could not
        reuse its work arrays (:func:`_workspace`). The run holds the stepper meanwhile."""
        import weakref

        ref = weakref.ref(self)

        def fun(t, y):
            stepper = ref() if switch[0] else None
            got = stepper.derivative(t, y) if stepper is not None else None
            return python_fun(t, y) if got is None else got[0]

        return fun

    def advance_adams(self, state, y, hist_t, hist_f, recent, options, max_steps=None):
        """Compiled steps of Mech's Adams integrator from the state of
        ``solvers._integrators.integrate_adams`` (see ``_jit_free_loop.adams``): ``state =
        [t, h, history length, recent count, rejected]``, arrays updated in place. Returns
        ``(status, T, Y, H, E, QDD, LAM, evaluations, projections)``."""
        n, m = self.n, self.m
        if max_steps is None:
            max_steps = self.budget("adams", max(CHUNK_STEPS, min(10 * CHUNK_STEPS,
                                                                  ADAMS_CHUNK_VALUES // self.ny)))
        T, H, E = np.empty(max_steps), np.empty(max_steps), np.empty(max_steps)
        Y = np.empty((max_steps, self.ny))
        QDD, LAM = np.empty((max_steps, n)), np.empty((max_steps, self.nl))
        k, (a, b, c), method, fixed, inv_scale, t1 = options
        got = self._call(
            "adams", self.kp, _lapack(), self.p, self.flat_t, self.mp, self.kk, n, m, self.jr,
            self.jc, self.rows0, self.columns, self.offset, self.robust, self.mode,
            self.blk_i, self.ws, self.correction, 1e-12, 8, int(k), float(a), float(b),
            float(c), int(method), bool(fixed), inv_scale,
            float(t1), state, y, hist_t, hist_f, recent, int(max_steps), T, Y, H, E, QDD, LAM)
        if got is None:            # (being compiled in the background: hand over at once)
            return 2, T[:0], Y[:0], H[:0], E[:0], QDD[:0], LAM[:0], 0, 0
        status, steps, evals, projections = got
        self._count(steps)
        if self.tier == "interpreted":
            # (a short call: its rows alone are kept, not the chunk-sized arrays)
            T, Y, H, E, QDD, LAM = (a[:steps].copy() for a in (T, Y, H, E, QDD, LAM))
        return (int(status), T[:steps], Y[:steps], H[:steps], E[:steps], QDD[:steps],
                LAM[:steps], int(evals), int(projections))


__all__ = ["CHUNK_STEPS", "METHODS", "PAUSE_STEPS", "FreeStepper"]
