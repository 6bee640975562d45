"""Pictures of models with generalized-coordinate joints: slave bodies are placed by their
substituted poses, and a Gen joint is drawn as the joint it replaces."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import mechsys as ms  # noqa: E402
from mechsys import draw as d  # noqa: E402


def test_slave_bodies_are_drawn_where_the_solution_puts_them():
    m = ms.Model2D()
    a = m.add_body("a", points={"o": (0, 0), "e": (1, 0)}, mass=1, inertia=0.1)
    b = m.add_body("b", points={"o": (0, 0), "e": (0.7, 0)}, mass=1, inertia=0.1)
    m.add(ms.GenRevolute2(a.axis("o"), m.ground.axis((0, 0)), ("t1", 0.3)), name="j1")
    m.add(ms.GenRevolute2(b.axis("o"), a.axis("e"), ("t2", 0.2)), name="j2")
    m.add(ms.Constraint(ms.T - m.compile().layout.q_symbols[0] + 0.3))
    m.add(ms.Constraint(m.compile().layout.q_symbols[1] - 0.2 - 2 * ms.T))
    sol = m.solve(np.linspace(0, 1, 5))
    pts = [a.point("e"), b.point("e")]
    item = d.Scene(m, [d.Vertex(pts)]).evaluate(sol).items[0]
    xyz = np.broadcast_to(item.xyz, (len(sol.t),) + item.xyz.shape[1:])
    for j, p in enumerate(pts):
        np.testing.assert_allclose(xyz[:, j], sol.location(p), atol=1e-12)
    t1, t2 = 0.3 + sol.t, 0.2 + 2 * sol.t
    np.testing.assert_allclose(sol.location(b.point("e"))[:, 0],
                               np.cos(t1) + 0.7 * np.cos(t1 + t2), atol=1e-12)
    bar = d.Scene(m, [d.Bar("b", ("o", "e"), width=0.1)]).evaluate(sol).items[0]
    assert np.ptp(bar.xyz[:, :, 0]) > 0.3  # it moves with the chain
    fig = d.snapshot(sol, default=True, index=2, figsize=(3, 3), dpi=60)
    assert fig.axes
    plt.close(fig)
