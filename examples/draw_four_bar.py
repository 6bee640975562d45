"""Pictures of a four-bar linkage: the default drawing, Mech-style graphics, a coupler
curve, an overlay of configurations, instant centres, a GIF, plots and the HTML viewer.

The coupler is a body here (a triangle with a coupler point P), so its coupler curve is
the locus of P. Files are written to the current directory (``draw_four_bar_*``).

Run: ``python examples/draw_four_bar.py``
"""

import numpy as np

import mechsys as ms
from mechsys import T, draw

a, b, c, d = 1.0, 4.0, 3.0, 4.0  # crank, coupler, rocker, ground: a Grashof crank-rocker

m = ms.Model2D()
g = m.ground
crank = m.add_body("crank", points={"A": (a, 0)}, guess=((0, 0), 0))
coupler = m.add_body("coupler", points={"A": (0, 0), "B": (b, 0), "P": (1.5, 1.2)},
                     guess=((a, 0), 0.9))
rocker = m.add_body("rocker", points={"B": (c, 0)}, guess=((d, 0), 1.8))
m.add(ms.Revolute2(g.point((0, 0)), crank.point(0)))
m.add(ms.Revolute2(crank.point("A"), coupler.point("A")))
m.add(ms.Revolute2(coupler.point("B"), rocker.point("B")))
m.add(ms.Revolute2(g.point((d, 0)), rocker.point(0)))
m.add(ms.RotationLock1(crank, 2 * np.pi * T), name="drive")
sol = m.solve(np.linspace(0, 1, 73))

# 1. the default picture (bodies through their points, pins, ground pivots)
fig = draw.snapshot(sol, index=6, title="four-bar: default drawing")
fig.savefig("draw_four_bar_default.png", dpi=80)

# 2. Mech-style graphics attached to the model, plus the coupler curve and an arrow
P = coupler.point("P")
draw.attach(m,
            draw.Bar(crank, (0, "A"), width=0.2),
            draw.Facet(coupler, ["A", "B", "P"], alpha=0.6),
            draw.Bar(rocker, (0, "B"), width=0.2),
            draw.GroundPivot((0, 0)), draw.GroundPivot((d, 0)),
            draw.LocusPlot(P, label="coupler curve"),
            draw.Arrow(P, m.velocity(P), scale="auto"),
            draw.PointLabel(coupler, ["P"]))
fig = draw.snapshot(sol, t=0.3, title="four-bar at t = 0.3 s")
fig.savefig("draw_four_bar_graphics.png", dpi=80)

# 3. several configurations; the coupler's instant centre
draw.overlay(sol, frames=6).savefig("draw_four_bar_overlay.png", dpi=80)
fig = draw.snapshot(sol, graphics=[draw.InstantCenter(coupler, to=["A", "B"])], index=10)
fig.savefig("draw_four_bar_instant_centre.png", dpi=80)

# 4. an animation at half speed (a short, small one), and the interactive viewer
gif = draw.animate(sol, "draw_four_bar.gif", rate=0.5, fps=12, dpi=50)
html = draw.viewer(sol, "draw_four_bar.html", title="four-bar linkage")

# 5. plots of outputs: time histories against the crank angle, and a phase plot. The model
# declares no unit system (any consistent one works); read it as metres and seconds, and say
# so in the labels of the outputs whose unit mechsys cannot know (angles are radians)
fig = draw.plot(sol, {"rocker angle": "rocker.th",
                      "coupler point P [m]": m.location(P),
                      "|v_P| [m/s]": lambda s: np.linalg.norm(s.velocity(P), axis=1)},
                x="crank.th", xlabel="crank angle")
fig.savefig("draw_four_bar_plots.png", dpi=80)
draw.phase_plot(sol, "rocker.th", m.omega(rocker), xlabel="rocker angle",
                ylabel="rocker angular velocity [rad/s]").savefig("draw_four_bar_phase.png", dpi=80)

print(f"wrote {gif}, {html} and draw_four_bar_*.png")
