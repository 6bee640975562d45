"""Build time at scale (issue 11): the closed-form virtual work of point forces and the
unoptimised compilation of large kernels give the same numbers as the general paths."""

import ctypes
import pickle

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys.compile import _backends
from mechsys.compile._dynamics import _point_force_terms
from mechsys.loads import Gravity


@pytest.mark.parametrize("dim", [2, 3, "2-euler"])
def test_point_force_closed_form_equals_differentiated_virtual_work(dim):
    """``Q_s = (d r_P / d s)^T F`` by SymPy's derivative of the point's location against
    the closed form ``[F, (dA/ds c')^T F]``, at random coordinates (Euler parameters not
    normalised: the identity holds for any values)."""
    euler = dim == "2-euler"            # planar bodies in (x, y, ei, ej) (12.4)
    dim = 2 if euler else dim
    m = ms.Model2D(orientation="euler") if euler else ms.Model2D() if dim == 2 else ms.Model3D()
    a = sp.Symbol("a")
    local = (0.3, -1.2) if dim == 2 else (0.3, -1.2, 0.7)
    b = m.add_body("b", points={"P": (local[0] + a, *local[1:])}, mass=2.0)
    F = sp.Matrix([1.5 * a, -2.0, 0.4][:dim])
    P = b.point("P")
    fast = _point_force_terms(m.space, b, P, F)
    r = P.location()
    slow = [sum(ri.diff(s) * fi for ri, fi in zip(r, F)) for s in b.q]
    rng = np.random.default_rng(dim)
    subs = {s: float(v) for s, v in zip([*b.q, a], rng.normal(size=len(b.q) + 1))}
    got = [float(e.subs(subs)) for e in fast]
    want = [float(e.subs(subs)) for e in slow]
    np.testing.assert_allclose(got, want, rtol=1e-14, atol=1e-14)


def test_point_depending_on_its_own_coordinates_takes_the_general_path():
    m = ms.Model2D()
    b = m.add_body("b", mass=1.0)
    P = ms.Point(b, (b.q[2], 0))        # a local coordinate that moves with the angle
    assert _point_force_terms(m.space, b, P, sp.Matrix([0, -1])) is None


def test_gravity_forces_unchanged_on_a_model():
    """Generalized gravity forces of a pendulum with an offset centroid against the
    potential energy: ``Q = -dV/dq``."""
    m = ms.Model2D()
    b = m.add_body("rod", mass=3.0, centroid=(0.4, 0.1), inertia=0.2)
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point((0, 0))))
    m.add_load(Gravity((0, -1), 9.81))
    dyn = m.compile().dynamics
    V = dyn.potential
    q = m.compile().layout.q_symbols
    subs = dict(zip(q, (0.2, -0.3, 0.7)))
    for s, Qs in zip(q, dyn.Q):
        assert abs(float(Qs.subs(subs)) + float(V.diff(s).subs(subs))) < 1e-13


def test_large_kernels_compile_unoptimised_with_the_same_values(monkeypatch):
    if "symengine" not in _backends.available_backends():
        pytest.skip("SymEngine not installed")
    x, y = sp.symbols("x y")
    exprs = [sp.sin(k * x) * y + sp.cos(y) ** k for k in range(1, 40)]
    opt = _backends.compile_exprs([x, y], exprs, "symengine")
    monkeypatch.setattr(_backends, "LARGE_KERNEL", 10)
    seen = []
    real = _backends._lambdify

    def spy(args, ex, opt_level, cse=False, mode="llvm"):
        seen.append(opt_level)
        return real(args, ex, opt_level, cse, mode)

    monkeypatch.setattr(_backends, "_lambdify", spy)
    big = _backends.compile_exprs([x, y], exprs, "symengine")
    # the distinct sin/cos in a first stage (STAGE_TRIG = 500 > 39 outputs: unstaged here)
    assert seen == [0]
    for v in ([0.3, -1.1], [2.0, 0.5]):
        np.testing.assert_allclose(big(np.array(v)), opt(np.array(v)), rtol=1e-15, atol=0)


def test_large_unoptimised_kernel_computes_each_sin_cos_once(monkeypatch):
    """Above ``STAGE_TRIG`` outputs an unoptimised kernel computes the distinct ``sin(a)``,
    ``cos(a)`` in a first stage, which also copies the arguments the second stage reads
    (decision 0066): the same values (to rounding) as the optimised one-stage kernel, in
    Python, in batch and through the C entry points the compiled loops call (the second
    stage's at ``x``, reading after the arguments); a ``sin`` of a ``Piecewise`` stays in
    the second stage."""
    if "symengine" not in _backends.available_backends():
        pytest.skip("SymEngine not installed")
    import ctypes

    x, y = sp.symbols("x y")
    pw = sp.Piecewise((x, x < 0.5), (x**2, True))
    exprs = [sp.sin(k * x) * y + sp.cos(y) ** k + sp.sin(x + y) for k in range(1, 40)]
    exprs += [sp.sin(pw) * sp.cos(y)]
    opt = _backends.compile_exprs([x, y], exprs, "symengine")
    assert opt._npieces == 1                             # the Piecewise only
    monkeypatch.setattr(_backends, "LARGE_KERNEL", 10)
    monkeypatch.setattr(_backends, "STAGE_TRIG", 10)
    stages = []
    real = _backends._lambdify

    def spy(args, ex, opt_level, cse=False, mode="llvm"):
        stages.append([str(e) for e in ex])
        return real(args, ex, opt_level, cse, mode)

    monkeypatch.setattr(_backends, "_lambdify", spy)
    big = _backends.compile_exprs([x, y], exprs, "symengine")
    # the first stage: y (the one argument the second stage reads, copied), the Piecewise,
    # sin(k x) for k = 1..39, cos(y), sin(x + y)
    assert big._npieces == 1 + 1 + 39 + 2
    first, second = stages
    assert first[0] == "y" and sum("Piecewise" in e for e in first) == 1 and len(first) == 43
    assert not any(e.startswith("sin(Piecewise") for e in first)
    assert sum("sin(" in e for e in second) == 1        # sin of the Piecewise's value
    for v in ([0.3, -1.1], [2.0, 0.5]):
        want = opt(np.array(v))
        np.testing.assert_allclose(big(np.array(v)), want, rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(big.batch(np.array([v]))[0], want, rtol=1e-14, atol=1e-15)
        # the C entry points as a compiled loop calls them: the first stage writes its values
        # after the arguments, the second reads them there
        address, context, pre, pre_context, npieces = big.c_function()
        proto = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
        xs = np.zeros(2 + npieces)
        xs[:2] = v
        out = np.zeros(len(exprs))
        proto(pre)(xs[2:].ctypes.data, xs.ctypes.data, pre_context)
        proto(address)(out.ctypes.data, xs.ctypes.data, context)
        np.testing.assert_allclose(out, want, rtol=1e-14, atol=1e-15)


def test_lever_arm_of_a_large_sparse_dense_jacobian_equals_the_grouped_maxima():
    """A large, mostly empty dense Jacobian takes the scatter of its nonzero entries
    (decision 0066): the same lever arm as the grouped maxima of every entry, NaN entries
    ignored by both."""
    from mechsys.solvers import _linalg

    rng = np.random.default_rng(3)
    nb, m = 200, 1300                      # 600 columns: (x, y, angle) per body
    J = np.zeros((m, 3 * nb))
    rows = rng.integers(0, m, 4000)
    cols = rng.integers(0, 3 * nb, 4000)
    J[rows, cols] = rng.normal(size=4000) * np.where(cols % 3 == 2, 7.0, 1.0)
    J[5, 7] = np.nan
    trans = np.tile([True, True, False], nb)
    body = np.repeat(np.arange(nb), 3)
    assert J.size > _linalg.LEVER_DENSE_MAX
    dense = _linalg._lever_arm_dense(J, trans, body)
    assert dense > 0
    assert _linalg._lever_arm(J, trans, body) == dense


def test_gathered_first_stage_equals_symengines_to_the_last_bit(monkeypatch):
    """A large kernel whose first stage only copies arguments and takes ``sin``/``cos`` of
    arguments runs the shared gather loop instead of a compiled SymEngine stage (decision
    0079): the same bits as the same two stages with SymEngine's first stage, through Python,
    batch, the C entry points the compiled loops call, and after pickling; a first stage
    holding anything else (``sin`` of a sum) stays SymEngine's."""
    if "symengine" not in _backends.available_backends():
        pytest.skip("SymEngine not installed")

    t, x, y, th = sp.symbols("t x y th")
    exprs = [sp.sin(th) * k + sp.cos(x) * y ** k + x * sp.cos(th) for k in range(1, 30)]
    monkeypatch.setattr(_backends, "LARGE_KERNEL", 10)
    monkeypatch.setattr(_backends, "STAGE_TRIG", 10)
    big = _backends.compile_exprs([t, x, y, th], exprs, "symengine")
    with monkeypatch.context() as mp:   # the same two stages, the first compiled by SymEngine
        mp.setattr(_backends, "_gather_table", lambda *a: None)
        plain = _backends.compile_exprs([t, x, y, th], exprs, "symengine")
    assert plain._pre_backend == "symengine-llvm" and big._pre_backend == "gather"
    # the first stage: x, y copied (th only inside sin/cos), then sin/cos values
    assert big._npieces == 2 + 3
    again = pickle.loads(pickle.dumps(big))
    proto = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
    rng = np.random.default_rng(7)
    for scale in (1.0, 1e3, 1e12):
        v = rng.standard_normal(4) * scale
        want = plain(v)
        for got in (big(v), big.batch(v[None])[0], again(v)):
            assert np.array_equal(got.view(np.int64), want.view(np.int64))
        address, context, pre, pre_context, npieces = big.c_function()
        xs = np.zeros(4 + npieces)
        xs[:4] = v
        out = np.zeros(len(exprs))
        proto(pre)(xs[4:].ctypes.data, xs.ctypes.data, pre_context)
        proto(address)(out.ctypes.data, xs.ctypes.data, context)
        assert np.array_equal(out.view(np.int64), want.view(np.int64))
    mixed = _backends.compile_exprs([t, x, y, th], exprs + [sp.sin(x + th)], "symengine")
    assert mixed._pre_backend == "symengine-llvm"


def test_small_matrices_from_entries_equal_sympys():
    """``_matrix`` (decision 0079) gives what ``sp.Matrix`` gives: equal, of the same
    domain (integers stay an integer matrix), usable as before."""
    from mechsys.geometry._points import _matrix

    x, th = sp.symbols("x th", real=True)
    c, s = sp.cos(th, evaluate=False), sp.sin(th, evaluate=False)
    for flat, shape in (([c, -s, s, c], (2, 2)), ([x, sp.S.Zero], (2, 1)),
                        ([sp.Integer(1), sp.Integer(0)], (2, 1)),
                        ([sp.Rational(1, 2), sp.Float(0.5)], (2, 1)),
                        ([sp.Float(0.0), sp.Float(-0.0), x, sp.S.Zero], (2, 2)),
                        ([sp.S.Zero, sp.S.Zero], (2, 1))):
        a, b = _matrix(*shape, flat), sp.Matrix(*shape, flat)
        assert a == b and type(a) is type(b) and a._rep.domain == b._rep.domain
        # (the same entries stored: a Float zero is kept, SymPy's zero left out)
        assert a._rep.to_sdm() == b._rep.to_sdm()
        assert a.T * a == b.T * b


def test_numbers_and_coordinate_tuples_made_once_are_sympys():
    """A float's SymPy number made once per exact value (decision 0086) is what sympify
    makes (``0.0`` and ``-0.0`` apart); a plain coordinate tuple's column, checked once, is
    the column ``sp.Matrix`` makes, a new copy each time (1 and 1.0 apart); a body's stored
    point comes back as ``Point`` would make it."""
    from mechsys._symbols import number
    from mechsys.geometry._points import Point, _as_matrix

    for v in (0.5, 0.0, -0.0, 1 / 12, 1e300, float("inf")):
        got = number(v)
        assert got is number(v) and sp.srepr(got) == sp.srepr(sp.sympify(v))
    assert number(0.0) is not number(-0.0)
    assert number(3) == 3 and number(sp.Symbol("a")) == sp.Symbol("a")
    for coords in ((1, 0), (1.0, 0), (0.5, -0.0), (0.5, 0.0)):
        a, b = _as_matrix(coords, "p"), _as_matrix(coords, "p")
        want = sp.Matrix([sp.sympify(c) for c in coords])
        assert a is not b and a == want and a._rep.domain == want._rep.domain
        assert [sp.srepr(e) for e in a] == [sp.srepr(e) for e in want]
        a[0] = 7                                       # a copy: the next one is as made
        assert _as_matrix(coords, "p") == want
    with pytest.raises(ms.GeometryError):
        _as_matrix((float("nan"), 0.0), "p")
    with pytest.raises(ms.GeometryError):             # checked again, not remembered
        _as_matrix((float("nan"), 0.0), "p")
    m = ms.Model2D()
    b = m.add_body("b", points={"tip": (1, 0.5)})
    for spec in ("tip", 1, 0):
        p, q = b.point(spec), Point(b, b._points["tip"] if spec != 0 else sp.zeros(2, 1),
                                    label="tip" if spec != 0 else "origin")
        assert (p.body, p.label, p.local) == (q.body, q.label, q.local)
        assert p.local is not b._points.get("tip") and type(p.local) is type(q.local)


def test_gc_paused_nests_and_restores_the_collector():
    """``gc_paused`` (decision 0079) pauses the cyclic collector once for nested uses and
    gives it back as it found it, also when the work raises."""
    import gc

    assert gc.isenabled()
    with _backends.gc_paused():
        with _backends.gc_paused():
            assert not gc.isenabled()
        assert not gc.isenabled()
    assert gc.isenabled()
    with pytest.raises(ValueError), _backends.gc_paused():
        raise ValueError("inside")
    assert gc.isenabled()
    gc.disable()
    try:
        with _backends.gc_paused():
            pass
        assert not gc.isenabled()        # it was off: stays off
    finally:
        gc.enable()


def test_rotation_entry_times_float_is_sympys_product():
    """``_times`` (decision 0079) builds ``cos(th) * w`` directly for a Float ``w``: the same
    expression as SymPy's product (equal, same ``srepr``, same precision of the
    coefficient), and SymPy's product itself for anything else."""
    from mechsys.compile._dynamics import _times

    th = sp.Symbol("th", real=True)
    for f in (sp.cos(th, evaluate=False), sp.sin(th, evaluate=False), -sp.sin(th, evaluate=False),
              sp.cos(2 * th), sp.Symbol("x")):
        for w in (sp.Float(-4.905), sp.Float(0.5) * sp.Float(3.0), sp.Float(1.0), sp.Float(-1.0),
                  sp.Float(0.0), sp.Integer(3), sp.Rational(1, 3), sp.Float("1e-300")):
            want = f * w
            got = _times(f, w)
            assert got == want and sp.srepr(got) == sp.srepr(want)
            if isinstance(want, sp.Mul) and isinstance(want.args[0], sp.Float):
                assert got.args[0]._prec == want.args[0]._prec


def test_rotation_lock_at_a_zero_float_angle_is_the_angle_itself():
    """``RotationLock1(body, 0.0)`` (decision 0079) gives SymPy's ``th - 0 - 0.0``, which is
    ``th`` itself, without building the sum; other angles go through the sum as before."""
    m = ms.Model2D()
    b = m.add_body("b", guess=((0.0, 0.0), 0.0))
    th = b.q[2]
    for angle in (0.0, -0.0, 0, 0.3, sp.Float(0, 30)):
        c = ms.RotationLock1(b, angle)
        (eq,) = c.equations(m.space)
        want = th - 0 - sp.sympify(angle)
        assert eq == want and sp.srepr(eq) == sp.srepr(want)


def test_spans_cut_parts_inside_each_section():
    """Parts of at most ``size`` outputs that never straddle two sections (decision 0080);
    sections that do not add up to the outputs are ignored (one block)."""
    assert _backends._spans(10, [4, 6], 3) == [(0, 3), (3, 4), (4, 7), (7, 10)]
    assert _backends._spans(10, None, 4) == [(0, 4), (4, 8), (8, 10)]
    assert _backends._spans(10, [4, 5], 4) == [(0, 4), (4, 8), (8, 10)]
    assert _backends._spans(6, [0, 6, 0], 6) == [(0, 6)]


def test_second_stage_in_parts_equals_the_whole_to_the_last_bit(monkeypatch, tmp_path):
    """A large gathered second stage compiled in parts, each declaring only the arguments
    it reads (decision 0080), gives the bits of the same stage compiled whole: through
    Python, batch, the C entry points the compiled loops call, and after pickling. The
    first stage computes each ``sin``/``cos`` once and copies it into every part reading
    it; a part reading no argument (constant outputs) still compiles; a part two kernels
    share is compiled once (then loaded from the kernel cache)."""
    if "symengine" not in _backends.available_backends():
        pytest.skip("SymEngine not installed")

    q = sp.symbols("q0:12")
    t = sp.Symbol("t")
    jac = [sp.sin(q[i]) * (i + 1) * 0.5 + q[i + 1] * sp.cos(q[i]) for i in range(11)]
    phi = [q[i] - q[i + 1] + 0.25 * sp.cos(q[i]) for i in range(11)]
    zeros = [sp.S.Zero] * 5
    args = [t, *q]
    monkeypatch.setattr(_backends, "LARGE_KERNEL", 10)
    monkeypatch.setattr(_backends, "STAGE_TRIG", 10)
    monkeypatch.setattr(_backends, "PART_OUTPUTS", 4)
    monkeypatch.setenv("MECHSYS_CACHE", str(tmp_path))      # an empty kernel cache
    stored = []
    real_store = _backends._cache.store
    monkeypatch.setattr(_backends._cache, "store", lambda key, f: (stored.append(key),
                                                                     real_store(key, f)))
    exprs = phi + jac + zeros
    big = _backends.compile_exprs(args, exprs, "symengine", sections=[11, 11, 5])
    assert isinstance(big._f, _backends._Parts) and big._pre_backend == "gather"
    assert [(o, k) for _, _, _, o, k in big._f.parts] == [
        (0, 4), (4, 4), (8, 3), (11, 4), (15, 4), (19, 3), (22, 4), (26, 1)]
    table = big._pre._table[1:]
    # each sin/cos once (11 of each), the rest copies of arguments or of earlier values
    ops = table & 3
    assert int(np.sum(ops == 1)) == 11 and int(np.sum(ops == 2)) == 11
    assert np.any(ops == 3)
    whole, rng = _same_bits_as_whole(monkeypatch, big, args, exprs, seed=80)
    # a kernel with the Jacobian's block first (the same sin/cos, so the same names): its
    # three Jacobian parts are the position kernel's, loaded; its parts of zeros (on q1, the
    # first argument it reads) are compiled, the second of four zeros loaded again
    before = len(stored)
    vel = _backends.compile_exprs(args, jac + zeros + zeros, "symengine", sections=[11, 10])
    assert len(vel._f.parts) == 6 and len(stored) - before == 2
    v = rng.standard_normal(len(args))
    assert np.array_equal(vel(v)[:11].view(np.int64), whole(v)[11:22].view(np.int64))


def test_shapes_name_the_expression_up_to_its_symbols():
    """An output's shape (decision 0086) is its exact graph with symbols numbered by first
    occurrence: renamed symbols keep it; another number (one ulp), a symbol read twice
    instead of two, another function or another order of a product's factors as SymEngine
    keeps them change it."""
    import symengine as se

    x, y, u, v = se.symbols("x y u v")
    sh = _backends._shapes
    (a, sa), (b, sb) = sh([se.RealDouble(2.5) * x + se.sin(y), se.RealDouble(2.5) * u + se.sin(v)])
    assert a == b and (len(sa), len(sb)) == (2, 2) and {*sa, *sb} == {x, y, u, v}
    assert sh([se.RealDouble(2.5 + 2**-51) * x + se.sin(y)])[0][0] != a
    assert sh([se.RealDouble(2.5) * x + se.sin(x)])[0][0] != a
    assert sh([se.RealDouble(2.5) * x + se.cos(y)])[0][0] != a
    assert sh([se.RealDouble(2.5) * x + se.sin(y)])[0][1] == [x, y]   # first occurrence
    assert sh([x + y])[0][0] != sh([x + 1])[0][0]
    assert sh([se.Integer(1)])[0] == ("One:1", [])
    # the short cuts for leaves and nodes of leaves write what the general walk writes
    mixed = [x, se.RealDouble(-0.0), se.RealDouble(0.5) * y, x + y + 1, x * x, se.sin(x),
             se.cos(x + y) * se.RealDouble(2.0) - x, se.Integer(-1) * u, u ** 3, se.Rational(1, 3)]
    assert sh(mixed) == [_backends._shape_walk(e) for e in mixed]


def test_shape_functions_give_the_bits_of_the_whole_stage(monkeypatch, tmp_path):
    """A large gathered second stage whose outputs repeat a few shapes is computed by one
    compiled function per shape and batch size, called for every batch and scattered into
    place (decision 0086): the bits of the same stage compiled whole, through Python, batch,
    the C entry points the compiled loops call, ``_slow`` and after pickling; a second
    kernel of those shapes on other symbols calls the functions compiled for the first."""
    if "symengine" not in _backends.available_backends():
        pytest.skip("SymEngine not installed")

    n = 40
    q = sp.symbols(f"q0:{n + 1}")
    t = sp.Symbol("t")
    exprs = []
    for i in range(n):          # interleaved shapes: the scatter puts them in place
        exprs += [q[i] - q[i + 1] + 0.25 * sp.cos(q[i]), -0.5 * sp.sin(q[i]), sp.S.One,
                  sp.cos(q[i]) * q[i + 1] ** 2]
    exprs += [sp.exp(q[0]) + t, sp.S.Zero]                 # a few of their own shape
    args = [t, *q]
    monkeypatch.setattr(_backends, "LARGE_KERNEL", 10)
    monkeypatch.setattr(_backends, "STAGE_TRIG", 10)
    monkeypatch.setattr(_backends, "PART_OUTPUTS", 50)
    monkeypatch.setattr(_backends, "SHAPE_MIN", 4)
    monkeypatch.setattr(_backends, "SHAPE_BATCHES", (16, 4, 1))
    monkeypatch.setattr(_backends, "_SHAPE_FUNCS", {})
    monkeypatch.setenv("MECHSYS_CACHE", str(tmp_path))      # an empty kernel cache
    compiled = []
    real = _backends._lambdify
    monkeypatch.setattr(_backends, "_lambdify", lambda *a, **k: (compiled.append(a[1]),
                                                                 real(*a, **k))[1])
    big = _backends.compile_exprs(args, exprs, "symengine")
    parts = big._f
    assert isinstance(parts, _backends._Parts) and big._pre_backend == "gather"
    assert parts.scatter is not None and sorted(parts.scatter) == list(range(len(exprs)))
    funcs = {id(f) for f, *_ in parts.parts}
    assert len(funcs) < len(parts.parts)          # batches share their shape's function
    assert big.c_function()[4] == big._pre.nout + len(exprs)   # values, then the scratch
    n_compiled = len(compiled)
    whole, rng = _same_bits_as_whole(monkeypatch, big, args, exprs, seed=86)
    # the same shapes on other symbols: every shape function is the first kernel's
    r = sp.symbols(f"r0:{n + 1}")
    other = [e.xreplace(dict(zip(q, r))) for e in exprs[:4 * n]]
    compiled.clear()
    second = _backends.compile_exprs([t, *r], other, "symengine")
    assert isinstance(second._f, _backends._Parts)
    shared = {id(f) for f, *_ in second._f.parts} & funcs
    assert shared and len(compiled) < n_compiled
    v = rng.standard_normal(len(args))
    assert np.array_equal(second(v).view(np.int64), whole(v)[:4 * n].view(np.int64))


def test_fingerprint_is_exact_and_iterative():
    """The kernel cache's key of expressions (decision 0080): a change in the last bit of a
    number, the order of the outputs or of a product's factors as SymEngine keeps them gives
    another key; equal lists the same; a deep expression needs no recursion."""
    import symengine as se

    x, y = se.symbols("x y")
    fp = _backends._fingerprint
    assert fp([x + se.RealDouble(0.1) * y]) != fp([x + se.RealDouble(0.1 + 2**-56) * y])
    assert fp([x + y, x]) != fp([x, x + y])
    assert fp([x * y + 2, se.sin(x)]) == fp([x * y + 2, se.sin(x)])
    assert fp([x + 1]) != fp([x + se.RealDouble(1.0)])
    deep = x
    for k in range(3000):
        deep = se.sin(deep) + k
    assert len(fp([deep])) == 64


def test_function_atoms_is_sympys_atoms_once():
    """The SymPy atoms the checks before a compile look for, found once per expression:
    equal to SymPy's ``atoms`` of those types, remembered."""
    from mechsys.compile._derive import symengine_safe

    x = sp.Symbol("x")
    e = sp.sin(x) + x**2 + sp.Max(x, 1) + sp.floor(x) * sp.I
    want = e.atoms(sp.Pow, sp.Function, sp.Max, sp.Min, type(sp.I), type(sp.zoo))
    assert _backends.function_atoms(e) == want
    assert _backends.function_atoms(e) is _backends.function_atoms(e)
    assert symengine_safe([sp.sin(x) + sp.floor(x)]) and not symengine_safe([sp.Mod(x, 2)])
    assert _backends._plainly_real(sp.sin(x) + sp.Max(x, 1))
    assert not _backends._plainly_real(sp.sqrt(-1) * x)


def test_free_symbols_is_sympys_once():
    """An expression's free symbols, found once per expression (decision 0080): SymPy's,
    remembered; expressions SymPy tells apart (a Float and an Integer exponent) kept apart."""
    from mechsys._symbols import T, free_symbols

    x = sp.Symbol("x")
    e = T * x + sp.cos(x) ** 2
    assert free_symbols(e) == e.free_symbols and free_symbols(e) is free_symbols(e)
    assert free_symbols(sp.floor(2.0 * x)) == {x} and free_symbols(sp.Integer(3)) == set()


def _same_bits_as_whole(monkeypatch, big, args, exprs, seed: int):
    """``big`` (a kernel compiled in parts) gives the bits of the same kernel compiled whole
    through every path: its call, batch, pickled copy and Python stages, and its C entry
    points as the compiled loops call them (first stage, then second), at random arguments
    of three scales. Returns ``(whole kernel, the random generator after the draws)``."""
    with monkeypatch.context() as mp:                     # the same stages, the second whole
        mp.setattr(_backends, "PART_OUTPUTS", 10**6)
        whole = _backends.compile_exprs(args, exprs, "symengine")
    assert not isinstance(whole._f, _backends._Parts)
    again = pickle.loads(pickle.dumps(big))
    proto = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
    rng = np.random.default_rng(seed)
    for scale in (1.0, 1e3, 1e9):
        v = rng.standard_normal(len(args)) * scale
        want = whole(v)
        for got in (big(v), big.batch(np.array([v, v]))[1], again(v), big._slow(v)):
            assert np.array_equal(got.view(np.int64), want.view(np.int64))
        for k in (big, again):
            address, context, pre, pre_context, npieces = k.c_function()
            xs = np.zeros(len(args) + npieces)
            xs[:len(args)] = v
            out = np.zeros(len(exprs))
            proto(pre)(xs[len(args):].ctypes.data, xs.ctypes.data, pre_context)
            proto(address)(out.ctypes.data, xs.ctypes.data, context)
            assert np.array_equal(out.view(np.int64), want.view(np.int64))
    return whole, rng
