"""The Whipple bicycle benchmark (Meijaard, Papadopoulos, Ruina & Schwab 2007), built from its
four bodies, three hinges and two exact rolling contacts, linearised about upright straight
running and compared with the paper's eigenvalues.

Bodies (benchmark parameters, Table 1 of the paper): rear wheel R, rear frame B with the
rider, front frame H (fork and handlebar), front wheel F. Hinges (``Revolute5``): the rear
hub, the steer axis tilted back by ``lambda = pi/10`` from the vertical, the front hub. Each
wheel rolls on the ground without slipping: ``RollingDisk2`` (the two no-slip rows, velocity
constraints) with its holonomic part ``PlaneToCircle1`` (the rim touches the ground). The
paper's axes are x forward, y right, z down; here x forward, y left, z up (z-up products of
inertia change sign: ``I_xz -> -I_xz``). The angles keep the paper's senses: lean ``phi``
about the forward x axis (to the right), steer ``delta`` about the steer axis pointing down.

``free.linearize`` takes the 7 coordinates of the configuration (x, y, yaw, lean, steer and
the two wheels' rotations, as expressions of the bodies' Euler parameters), drops the
positions that the motion does not depend on (``cyclic=``: x, y, yaw, the wheel angles) and
uses the rates of lean, steer and the rear wheel as the independent velocities
(``speeds=``): the state is ``(phi, delta, phi', delta', theta_R')``. Its eigenvalues at
forward speeds ``v = 0..10 m/s`` are the four of the paper's Table 2 and a zero (the forward
speed itself is neutral). The weave and capsize speeds are found by root-finding the real
part of the weave pair and the capsize eigenvalue on this linearisation.

The paper's linearised equations ``M q'' + v C1 q' + (g K0 + v^2 K2) q = 0`` (eq. 5.4,
``q = (phi, delta)``) follow from ``A``: ``-M^-1 (g K0 + v^2 K2)`` and ``-v M^-1 C1`` are its
lean/steer block; the example prints the largest deviation from the published matrices.

Finally the nonlinear motion (``free.simulate``, the rolling rows held by the compiled stepper)
after a lean-rate kick of 1 mrad/s: it decays at 5 m/s, inside the self-stable range, and
grows at 8 m/s at the capsize eigenvalue's rate; both follow the linear prediction
``expm(A t) x0`` to 1e-6 of the amplitude. The picture shows the eigenvalues against speed
(the paper's figure 3) with Table 2's values, and these motions; ``whipple_bicycle.html``
is an interactive 3D viewer of the bicycle weaving and recovering at 4.6 m/s after a larger
kick (0.5 rad/s).

Run: ``python examples/whipple_bicycle.py``
"""

from __future__ import annotations

import time

import numpy as np
import scipy.linalg as sla
import scipy.optimize as so
import sympy as sp

import mechsys as ms

# -- the benchmark (Meijaard et al. 2007, Table 1; paper axes: x forward, z down) ------------
W, C, LAM, G = 1.02, 0.08, np.pi / 10, 9.81
R_R, M_R, IR = 0.3, 2.0, (0.0603, 0.12, 0.0603)            # (Ixx, Iyy, Izz)
XB, ZB, M_B, IB = 0.3, -0.9, 85.0, (9.2, 11.0, 2.8, 2.4)    # (Ixx, Iyy, Izz, Ixz)
XH, ZH, M_H, IH = 0.9, -0.7, 4.0, (0.05892, 0.06, 0.00708, -0.00756)
R_F, M_F, IF = 0.35, 3.0, (0.1405, 0.28, 0.1405)

#: Table 2 of the paper: the eigenvalues at v = 0, 1, ..., 10 m/s (weave pair, capsize,
#: castering; at v = 0 the two real pairs of the inverted pendulum)
TABLE2 = {
    0: (5.53094371765393, 3.13164324790656, -3.13164324790656, -5.53094371765393),
    1: (3.52696170990070 + 0.80774027519930j, 3.52696170990070 - 0.80774027519930j,
        -3.13423125066578, -7.11008014637442),
    2: (2.68234517512745 + 1.68066296590675j, 2.68234517512745 - 1.68066296590675j,
        -3.07158645641514, -8.67387984831735),
    3: (1.70675605663975 + 2.31582447384325j, 1.70675605663975 - 2.31582447384325j,
        -2.63366137253667, -10.35101467245920),
    4: (0.41325331521125 + 3.07910818603206j, 0.41325331521125 - 3.07910818603206j,
        -1.42944427361326, -12.15861426576447),
    5: (-0.77534188219585 + 4.46486771378823j, -0.77534188219585 - 4.46486771378823j,
        -0.32286642900409, -14.07838969279822),
    6: (-1.52644486584142 + 5.87673060598709j, -1.52644486584142 - 5.87673060598709j,
        -0.00406690076970, -16.08537123098030),
    7: (-2.13875644258362 + 7.19525913329805j, -2.13875644258362 - 7.19525913329805j,
        0.10268170574766, -18.15788466125260),
    8: (-2.69348683581097 + 8.46037971396931j, -2.69348683581097 - 8.46037971396931j,
        0.14327879765713, -20.27940894394570),
    9: (-3.21675402252485 + 9.69377351531791j, -3.21675402252485 - 9.69377351531791j,
        0.15790184030917, -22.43788559040860),
    10: (-3.72016840437287 + 10.90681139476287j, -3.72016840437287 - 10.90681139476287j,
         0.16105338653172, -24.62459635017404),
}
#: the paper's weave and capsize speeds (section 5)
WEAVE, CAPSIZE = 4.29238253634111, 6.02426201538837
#: eq. 5.4 of the paper: M q'' + v C1 q' + (g K0 + v^2 K2) q = 0, q = (lean, steer)
M_PAPER = np.array([[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]])
C1_PAPER = np.array([[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]])
K0_PAPER = np.array([[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]])
K2_PAPER = np.array([[0.0, 76.59734589573222], [0.0, 2.65431523794604]])


def _inertia(ixx, iyy, izz, ixz=0.0, s=1.0):
    """The paper's inertia matrix (z down) in z-up axes (y and z reversed: I_xz changes
    sign), times ``s`` (the square of the length unit's factor)."""
    return [[ixx * s, 0, -ixz * s], [0, iyy * s, 0], [-ixz * s, 0, izz * s]]


def _relative_angle(body1, body2, axis):
    r"""The rotation angle of ``body2`` relative to ``body1`` about ``axis`` (a unit vector in
    body 1's axes, a hinge): from the relative Euler parameters
    :math:`e_{12} = \bar e_1 \otimes e_2 = (\cos\frac\theta2, \sin\frac\theta2\, u)`,
    :math:`\theta = 2\,\mathrm{atan2}(u \cdot e_{12,v}, e_{12,0})` (bilinear arguments:
    their derivatives stay small)."""
    a0, *av = body1.q[3:7]
    b0, *bv = body2.q[3:7]
    av, bv = sp.Matrix(av), sp.Matrix(bv)
    r0 = a0 * b0 + av.dot(bv)
    rv = a0 * bv - b0 * av - av.cross(bv)
    return 2 * sp.atan2(rv.dot(sp.Matrix(axis)), r0)


def build(scale: float = 1.0):
    """The bicycle in lengths of ``1/scale`` metres (``scale = 1000``: millimetres). Returns
    ``(model, coordinates)``: the 7 chart coordinates ``[x, y, yaw, lean, steer, rear wheel,
    front wheel]`` as names or ``(name, expression)`` pairs for ``free.linearize``."""
    s = scale
    m = ms.Model3D()
    # the body origins: the wheel centres (rear frame at the rear hub, front frame at the
    # front hub); upright, every body's axes along the global ones
    rear = m.add_body("rear_wheel", guess=((0, 0, R_R * s), (1, 0, 0, 0)), mass=M_R,
                      inertia=_inertia(*IR, s=s * s))
    frame = m.add_body("rear_frame", guess=((0, 0, R_R * s), (1, 0, 0, 0)), mass=M_B,
                       centroid=(XB * s, 0, (-ZB - R_R) * s), inertia=_inertia(*IB, s=s * s))
    fork = m.add_body("front_frame", guess=((W * s, 0, R_F * s), (1, 0, 0, 0)), mass=M_H,
                      centroid=((XH - W) * s, 0, (-ZH - R_F) * s),
                      inertia=_inertia(*IH, s=s * s))
    front = m.add_body("front_wheel", guess=((W * s, 0, R_F * s), (1, 0, 0, 0)), mass=M_F,
                       inertia=_inertia(*IF, s=s * s))
    y_axis = (0, 1, 0)
    m.add(ms.Revolute5(frame.axis(0, y_axis), rear.axis(0, y_axis)), name="rear hub")
    m.add(ms.Revolute5(fork.axis(0, y_axis), front.axis(0, y_axis)), name="front hub")
    # the steer axis meets the ground the trail c ahead of the front contact, tilted back by
    # lambda; its direction points down (the paper's positive steer turns to the right)
    down = (np.sin(LAM), 0.0, -np.cos(LAM))
    m.add(ms.Revolute5(frame.axis(((W + C) * s, 0, -R_R * s), down),
                       fork.axis((C * s, 0, -R_F * s), down)), name="steer")
    ground = m.ground.axis((0, 0, 0), (0, 0, 1))
    for wheel, r, name in ((rear, R_R, "rear"), (front, R_F, "front")):
        roll = ms.RollingDisk2(ground, wheel.axis(0, y_axis), r * s)
        m.add(roll.holonomic(), name=f"{name} contact")
        m.add(roll, name=f"{name} rolling")
    m.add_load(ms.Gravity((0, 0, -1), G * s))
    # the chart: yaw psi, lean phi, pitch (fixed by the contacts) of the rear frame, whose
    # axle (its y axis) is Rz(psi) Rx(phi) e_y = (-sin psi cos phi, cos psi cos phi, sin phi)
    yb = frame.A[:, 1]
    lean = sp.asin(yb[2])
    yaw = sp.atan2(-yb[0], yb[1])
    steer = _relative_angle(frame, fork, down)
    rear_angle = _relative_angle(frame, rear, y_axis)
    front_angle = _relative_angle(fork, front, y_axis)
    coords = ["rear_wheel.x", "rear_wheel.y", ("yaw", yaw), ("lean", lean), ("steer", steer),
              ("rear", rear_angle), ("front", front_angle)]
    return m, coords


CYCLIC = ["rear_wheel.x", "rear_wheel.y", "yaw", "rear", "front"]
SPEEDS = ["lean", "steer", "rear"]


def upright(v: float, scale: float = 1.0) -> dict:
    """Upright straight running at forward speed ``v`` (m/s; in the model's units times
    ``scale``): every body moves forward at ``v``, the wheels spin at ``v / r``."""
    return {"rear_wheel.x_d": v * scale, "rear_frame.x_d": v * scale,
            "front_frame.x_d": v * scale, "front_wheel.x_d": v * scale,
            ("omega", "rear_wheel"): (0.0, v / R_R, 0.0),
            ("omega", "front_wheel"): (0.0, v / R_F, 0.0)}


def linearize(free, coords, v: float, scale: float = 1.0):
    """``free.linearize`` about upright straight running at ``v``: states
    ``(lean, steer, lean_d, steer_d, rear_d)``."""
    return free.linearize(upright(v, scale), coordinates=coords, cyclic=CYCLIC, speeds=SPEEDS)


def bicycle_eigenvalues(lin) -> tuple[np.ndarray, complex]:
    """The four eigenvalues of the lean and steer motion (descending real part, then
    imaginary part, as Table 2) and the fifth: the neutral forward speed, told apart by its
    eigenvector (the rear wheel's rate alone; the capsize eigenvalue nears zero too)."""
    vals, vecs = sla.eig(np.asarray(lin.A))
    j = int(np.argmax(np.abs(vecs[-1]) / np.linalg.norm(vecs, axis=0)))
    rest = np.delete(vals, j)
    return rest[np.lexsort((-rest.imag, -rest.real))], complex(vals[j])


def lean_steer_matrices(lin):
    """``(-M^-1 K(v), -M^-1 C(v))``: the lean/steer block of ``A``."""
    A = np.asarray(lin.A)
    return A[2:4, 0:2], A[2:4, 2:4]


def table(free, coords, scale: float = 1.0):
    """``{v: (eigenvalues (4,), neutral, largest relative error)}`` for v = 0..10."""
    out = {}
    for v, published in TABLE2.items():
        s, zero = bicycle_eigenvalues(linearize(free, coords, float(v), scale))
        ref = np.array(published, dtype=complex)
        ref = ref[np.lexsort((-ref.imag, -ref.real))]
        out[v] = (s, zero, float(np.max(np.abs(s - ref) / np.abs(ref))))
    return out


def weave_and_capsize(free, coords):
    """The weave speed (the weave pair's real part crosses zero) and the capsize speed (the
    capsize eigenvalue crosses zero), by Brent's method on the linearisation."""
    def weave(v):
        s, _ = bicycle_eigenvalues(linearize(free, coords, v))
        return s[np.abs(s.imag) > 0].real.max()

    def capsize(v):
        s, _ = bicycle_eigenvalues(linearize(free, coords, v))
        real = s[s.imag == 0].real
        return real[np.argmin(np.abs(real))]

    return (so.brentq(weave, 4.0, 5.0, xtol=1e-12), so.brentq(capsize, 5.5, 6.5, xtol=1e-12))


def kick_response(free, coords, v: float, t: np.ndarray, kick: float = 1e-3):
    """The nonlinear motion (``free.simulate``, the compiled stepper holding the rolling rows)
    after a lean-rate kick ``kick`` (rad/s) of upright running at ``v``, and the linear
    prediction ``x(t) = expm(A t) x0`` from the same start: ``(lean, lean_linear)``. The
    start gives the rear frame's and rear wheel's angular velocities (the lean rate and the
    wheel's spin ``v / r_R``); the other velocities follow the constraints."""
    lin = linearize(free, coords, v)
    sol = free.simulate(t, initial_condition={("omega", "rear_frame"): (kick, 0.0, 0.0),
                                              ("omega", "rear_wheel"): (kick, v / R_R, 0.0)},
                        rtol=1e-8, atol=1e-11)
    i = free.system.layout.index("rear_frame.e0")
    e0, e1, e2, e3 = sol.q[:, i:i + 4].T
    lean = np.arcsin(2 * (e2 * e3 + e0 * e1))      # the rear frame's y axis, z component
    # the linear state at the start: lean, steer, their rates, the wheel's rate change
    wB, wH, wR = (sol.omega(b)[0] for b in ("rear_frame", "front_frame", "rear_wheel"))
    down = np.array([np.sin(LAM), 0.0, -np.cos(LAM)])
    x0 = np.array([lean[0], 0.0, wB[0], (wH - wB) @ down, (wR - wB)[1] - v / R_R])
    A = np.asarray(lin.A)
    linear = np.array([(sla.expm(A * tk) @ x0)[0] for tk in t])
    return lean, linear


def main() -> None:
    t0 = time.perf_counter()
    m, coords = build()
    free = m.free()
    lin = linearize(free, coords, 5.0)
    print(f"{free}; built and first linearised in {time.perf_counter() - t0:.1f} s")
    print(f"states {lin.states}")
    rows = table(free, coords)
    print(f"{'v':>3} {'eigenvalues (mechsys)':>86} {'rel. error':>11}")
    for v, (s, zero, err) in rows.items():
        txt = "  ".join(f"{x.real:+.10f}{x.imag:+.10f}j" if x.imag else f"{x.real:+.10f}"
                        for x in s)
        print(f"{v:>3} {txt:>86} {err:11.1e}   (neutral {abs(zero):.0e})")
    print(f"largest relative error of the eigenvalues: {max(r[2] for r in rows.values()):.1e}")
    vw, vc = weave_and_capsize(free, coords)
    print(f"weave speed   {vw:.10f} m/s (paper {WEAVE:.10f}, error {abs(vw - WEAVE):.1e})")
    print(f"capsize speed {vc:.10f} m/s (paper {CAPSIZE:.10f}, error {abs(vc - CAPSIZE):.1e})")
    # the paper's matrices: -M^-1 K(v) and -M^-1 C(v) at two speeds give M^-1 K0, K2, C1
    Minv = np.linalg.inv(M_PAPER)
    err = 0.0
    for v in (0.0, 3.0):
        K, Cv = lean_steer_matrices(linearize(free, coords, v))
        Kp = -Minv @ (G * K0_PAPER + v * v * K2_PAPER)
        Cp = -Minv @ (v * C1_PAPER)
        err = max(err, np.abs(K - Kp).max() / np.abs(Kp).max(),
                  np.abs(Cv - Cp).max() / max(np.abs(Cp).max(), 1.0))
    print(f"lean/steer block against the paper's M, C1, K0, K2: largest relative error {err:.1e}")
    t1 = time.perf_counter()
    lin5 = linearize(free, coords, 5.0)
    print(f"one linearisation at 5 m/s: {1e3 * (time.perf_counter() - t1):.1f} ms")
    del lin5
    # the nonlinear motion after a small lean-rate kick: decays at 5 m/s (self-stable),
    # grows at 8 m/s (capsize, +0.143 1/s); tests/test_bicycle.py also runs 2 m/s (weave,
    # +2.68 1/s)
    t = np.linspace(0.0, 4.0, 81)
    runs = {}
    for v, span in ((5.0, 4.0), (8.0, 4.0)):
        tv = t[t <= span + 1e-12]
        lean, linear = kick_response(free, coords, v, tv)
        runs[v] = (tv, lean, linear)
        dev = np.abs(lean - linear).max() / np.abs(linear).max()
        q = len(tv) // 4
        print(f"kick at {v:.0f} m/s: lean amplitude {np.abs(lean[q:2 * q]).max():.2e} in the "
              f"second quarter, {np.abs(lean[-q:]).max():.2e} in the last; nonlinear "
              f"against linear {dev:.1e} of the amplitude")
    # at 8 m/s the weave has died out after a second: the lean then grows at the capsize rate
    tv, lean, _ = runs[8.0]
    rate = np.log(lean[-1] / lean[-21]) / (tv[-1] - tv[-21])
    s8, _ = bicycle_eigenvalues(linearize(free, coords, 8.0))
    print(f"growth rate of the lean at 8 m/s over the last second {rate:.5f} 1/s; capsize "
          f"eigenvalue {s8[0].real:.5f} 1/s")
    _figure(free, coords, runs)
    _viewer(m, free)


def _viewer(m, free) -> None:
    """An interactive 3D viewer (HTML: orbit, time slider, play) of the bicycle at 4.6 m/s,
    just above the weave speed, after a lean-rate kick of 0.5 rad/s: it weaves and recovers."""
    from mechsys import draw

    rear, frame, fork, front = (m.body(n) for n in ("rear_wheel", "rear_frame", "front_frame",
                                                      "front_wheel"))
    v = 4.6
    sol = free.simulate(np.linspace(0.0, 6.0, 121),
                        initial_condition={("omega", "rear_frame"): (0.5, 0.0, 0.0),
                                           ("omega", "rear_wheel"): (0.5, v / R_R, 0.0)},
                        rtol=1e-7, atol=1e-9)
    axis = np.array([-np.sin(LAM), 0.0, np.cos(LAM)])            # the steer axis, upwards
    top, low = (np.array([W + C, 0.0, 0.0]) + s * axis for s in (0.95, 0.55))
    seat = np.array([0.25, 0.0, 0.95])

    def on_frame(g):                  # global (upright) -> the rear frame's local point
        return tuple(g - np.array([0.0, 0.0, R_R]))

    def on_fork(g):
        return tuple(g - np.array([W, 0.0, R_F]))

    red, grey, black = "#c0392b", "#7f8c8d", "#333333"
    graphics = [
        draw.Cylinder(rear, (0, -0.02, 0), (0, 0.02, 0), R_R, color=black),
        draw.Cylinder(front, (0, -0.02, 0), (0, 0.02, 0), R_F, color=black),
        *(draw.Cylinder(frame, on_frame(a), on_frame(b), 0.02, color=red)
          for a, b in ((np.array([0.0, 0.0, R_R]), seat), (seat, top),
                       (np.array([0.0, 0.0, R_R]), low), (seat, low))),
        draw.Sphere(frame, (XB, 0.0, -ZB - R_R), 0.12, color="#2e86c1"),   # the rider
        draw.Cylinder(fork, (0, 0, 0), on_fork(top), 0.018, color=grey),
        draw.Cylinder(fork, on_fork(top + [0, -0.25, 0]), on_fork(top + [0, 0.25, 0]), 0.015,
                      color=grey),
    ]
    path = draw.viewer(sol, "whipple_bicycle.html", graphics=graphics,
                       title="Whipple bicycle at 4.6 m/s after a lean kick")
    i = free.system.layout.index("rear_frame.e0")
    e0, e1, e2, e3 = sol.q[:, i:i + 4].T
    lean = np.abs(np.arcsin(2 * (e2 * e3 + e0 * e1)))
    print(f"wrote {path}: at 4.6 m/s the lean peaks at {lean.max():.3f} rad and is "
          f"{lean[-1]:.1e} rad after 6 s")


def _figure(free, coords, runs) -> None:
    """The eigenvalues against speed (the paper's figure 3) with Table 2's points, and the
    lean after a kick, nonlinear against linear."""
    import matplotlib.pyplot as plt

    speeds = np.linspace(0.0, 10.0, 41)
    eig = np.array([bicycle_eigenvalues(linearize(free, coords, v))[0] for v in speeds])
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    ax.plot(speeds, eig.real, "k.", ms=2)
    ax.plot(speeds, np.abs(eig.imag), ".", color="tab:blue", ms=2)
    for v, published in TABLE2.items():
        ref = np.array(published, dtype=complex)
        ax.plot([v] * 4, ref.real, "o", mfc="none", color="tab:red", ms=5)
    ax.axvline(WEAVE, ls=":", color="gray")
    ax.axvline(CAPSIZE, ls=":", color="gray")
    ax.set(xlabel="forward speed v [m/s]", ylabel="eigenvalue [1/s]", ylim=(-10, 10),
           title="real (black), |imaginary| (blue); Table 2 (circles)")
    for v, (tv, lean, linear) in runs.items():
        line, = bx.plot(tv, 1e3 * lean, label=f"{v:.0f} m/s nonlinear")
        bx.plot(tv, 1e3 * linear, "--", color=line.get_color(), label=f"{v:.0f} m/s linear")
    bx.set(xlabel="t [s]", ylabel="lean [mrad]", ylim=(-1, 1),
           title="after a lean-rate kick of 1 mrad/s")
    if runs:
        bx.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig("whipple_bicycle.png", dpi=80)


if __name__ == "__main__":
    main()
