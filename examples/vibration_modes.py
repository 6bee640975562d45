"""Vibration modes of a double pendulum with a torsion spring and damper at its elbow.

Two links hang from a pin; a rotational spring k and damper c join them at the elbow. About
the hanging equilibrium the linearised equations are ``M q'' + C q' + K q = 0`` with
(point masses m1, m2 at the link ends, angles q = (th1, th2) from the vertical)::

    M = [[(m1 + m2) l1^2, m2 l1 l2], [m2 l1 l2, m2 l2^2]]
    K = [[(m1 + m2) g l1 + k, -k], [-k, m2 g l2 + k]]
    C = [[c, -c], [-c, c]]

``m.vibration`` finds the frequencies, damping ratios and mode shapes from the model itself;
the script compares them with the eigenvalues of these matrices and writes an animation of
the second mode.

Run: ``python examples/vibration_modes.py``
"""

import numpy as np
import scipy.linalg as sla

import mechsys as ms

m1, m2, l1, l2, g, k, c = 1.3, 0.7, 1.1, 0.8, 9.81, 4.0, 0.3

m = ms.Model2D()
upper = m.add_body("upper", points={"tip": (l1, 0)}, mass=m1, centroid=(l1, 0), inertia=0,
                   guess=((0, 0), -1.5))
lower = m.add_body("lower", mass=m2, centroid=(l2, 0), inertia=0, guess=((0.1, -1.1), -1.5))
m.add(ms.Revolute2(m.ground.point((0, 0)), upper.point(0)), name="shoulder")
m.add(ms.Revolute2(upper.point("tip"), lower.point(0)), name="elbow")
m.add_load(ms.Gravity((0, -1), g))
m.add_load(ms.TorsionSpring(upper, lower, k))
m.add_load(ms.TorsionDamper(upper, lower, c))

eq = m.free(solution="static").solve()
modes = m.vibration(at=eq)
print(modes)

# the same eigenvalues from the textbook matrices
M = np.array([[(m1 + m2) * l1**2, m2 * l1 * l2], [m2 * l1 * l2, m2 * l2**2]])
K = np.array([[(m1 + m2) * g * l1 + k, -k], [-k, m2 * g * l2 + k]])
C = np.array([[c, -c], [-c, c]])
A = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
s = sla.eigvals(A)
s = s[s.imag > 0]
s = s[np.argsort(np.abs(s))]
print("closed form |s|:", np.abs(s), " zeta:", -s.real / np.abs(s))
assert np.allclose(modes.omega, np.abs(s), rtol=1e-9)
assert np.allclose(modes.damping_ratio, -s.real / np.abs(s), rtol=1e-9)

# mode 2: the links swing against each other
shape = modes.shape(1, ["upper.th", "lower.th"])
print("mode 2 angles (complex):", np.round(shape, 4))
path = modes.animate(1, "vibration_mode2.gif", amplitude=0.3, frames=10, dpi=60)
print("wrote", path)
