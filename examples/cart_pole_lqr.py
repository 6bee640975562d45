"""An inverted pendulum on a cart: linearise to state space, design an LQR controller and
close the loop on the nonlinear model.

A cart (mass M) on a horizontal rail carries a pole (mass m, centroid at l from the pin,
inertia I about the centroid) pinned on it; a horizontal force F pushes the cart. About the
upright position (th = angle from the vertical) the textbook linearisation is::

    (M + m) x'' - m l th'' = F,      (I + m l^2) th'' - m l x'' - m g l th = 0

``free.linearize`` gives the same ``A`` and ``B`` from the model itself (the force magnitude
is the parameter ``F``, the input). The script checks them against the closed form, tests
controllability, computes the LQR gain with SciPy's Riccati solver, adds the feedback
``F = -K x`` to the model as a load written with the coordinates and velocities, and
simulates the nonlinear closed loop from a 0.25 rad tilt: the pole is caught and the cart
returns to the origin. Without the controller the linear model's tilt grows as
``cosh(s t)`` (``scipy.signal.lsim`` of ``lin.to_scipy()``).

Run: ``python examples/cart_pole_lqr.py``
"""

import matplotlib.pyplot as plt
import numpy as np
import scipy.linalg as sla
import scipy.signal as ss

import mechsys as ms

Mc, mp, l, I, g = 1.0, 0.3, 0.5, 0.01, 9.81

m = ms.Model2D()
F = m.parameter("F", 0.0)
cart = m.add_body("cart", mass=Mc, inertia=0.05, guess=((0, 0), 0))
pole = m.add_body("pole", points={"tip": (2 * l, 0)}, mass=mp, centroid=(l, 0), inertia=I,
                  guess=((0, 0), np.pi / 2))
m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), cart.axis((0, 0), (1, 0))), name="rail")
m.add(ms.Revolute2(cart.point(0), pole.point(0)), name="pin")
m.add_load(ms.Gravity((0, -1), g))
m.add_load(ms.Force(cart.point(0), (1, 0), F), name="push")

free = m.free()
lin = free.linearize(coordinates=["cart.x", "pole.th"], inputs=["F"],
                     outputs=["cart.x", "pole.th"])
print(lin)

# the textbook matrices (th measured from the upright; pole.th = pi/2 + th)
J = I + mp * l**2
p = (Mc + mp) * J - (mp * l) ** 2
A = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [0, (mp * l) ** 2 * g / p, 0, 0],
              [0, (Mc + mp) * mp * g * l / p, 0, 0]])
B = np.array([[0], [0], [J / p], [mp * l / p]])
assert np.allclose(lin.A, A, rtol=1e-12, atol=1e-12) and np.allclose(lin.B, B, rtol=1e-12)
print("A, B match the closed form; controllable:", lin.controllable)

# LQR: minimise the integral of x^T Qw x + u^T Rw u
Qw, Rw = np.diag([10.0, 50.0, 1.0, 1.0]), np.array([[0.5]])
X = sla.solve_continuous_are(lin.A, lin.B, Qw, Rw)
K = np.linalg.solve(Rw, lin.B.T @ X)[0]
closed = np.linalg.eigvals(lin.A - lin.B @ K[None, :])
print("LQR gain K =", np.round(K, 3))
print("closed-loop eigenvalues:", np.round(np.sort_complex(closed), 3))
assert np.all(closed.real < 0)

# the nonlinear model with F = -K (x, th - pi/2, x', th') added as a load written with the
# coordinates and their velocities
start = {"pole.th": np.pi / 2 + 0.25}
rates = m.velocity_symbols()
x, th = cart.q[0], pole.q[2]
state = [x, th - np.pi / 2, rates[x], rates[th]]
m.add_load(ms.Force(cart.point(0), (1, 0), -sum(k * s for k, s in zip(K, state))),
           name="lqr")
sol = m.free().simulate(np.linspace(0, 4, 201), initial_condition=start)

fig, ax = plt.subplots(1, 2, figsize=(9, 3.2))
ax[0].plot(sol.t, sol["pole.th"] - np.pi / 2, label="pole angle [rad]")
ax[0].plot(sol.t, sol["cart.x"], label="cart position [m]")
ax[0].set_xlabel("t [s]")
ax[0].set_title("LQR on the nonlinear model")
ax[0].legend()
# without control the linear model's tilt grows as cosh(s t), s = sqrt(A[3, 1])
tf = np.linspace(0, 0.8, 41)
_, y_open, _ = ss.lsim(lin.to_scipy(), U=np.zeros(len(tf)), T=tf, X0=[0, 0.25, 0, 0])
ax[1].plot(tf, y_open[:, 1])
ax[1].set_xlabel("t [s]")
ax[1].set_ylabel("pole angle [rad]")
ax[1].set_title("without control (linear model): it falls")
fig.tight_layout()
fig.savefig("cart_pole_lqr.png", dpi=80)
print(f"final tilt {sol['pole.th'][-1] - np.pi / 2:.2e} rad, cart at {sol['cart.x'][-1]:.2e} m")
assert abs(sol["pole.th"][-1] - np.pi / 2) < 1e-2 and abs(sol["cart.x"][-1]) < 5e-2
assert np.allclose(y_open[:, 1], 0.25 * np.cosh(np.sqrt(A[3, 1]) * tf), rtol=1e-6)
