"""Force arrows from the reactions of a static solution."""

import numpy as np

import mechsys as ms
from mechsys import models


def test_reaction_arrow_is_the_wrist_pin_force():
    m = models.slider_crank()
    piston = m.body("piston")
    m.add_load(ms.Force(piston.point(0), (1, 0), -100.0))
    sol = m.solve(np.linspace(0.05, 0.45, 5), solution="static")
    arrow = ms.draw.ReactionArrow("wrist pin", piston, piston.point(0), scale=0.01)
    fr = ms.draw.Scene(m, [arrow], default=False).evaluate(sol, [0, 2, 4])
    shaft, head = fr.items
    tail, tip = shaft.xyz[:, 0], head.xyz[:, 0]
    F = np.asarray(sol.reaction("wrist pin", piston)[0])[[0, 2, 4]]
    # the arrow ends at the piston (it pushes on it) and is 0.01 x the force
    np.testing.assert_allclose(tip, sol.location(piston.point(0))[[0, 2, 4]], atol=1e-12)
    np.testing.assert_allclose(tip - tail, 0.01 * F, atol=1e-9)
