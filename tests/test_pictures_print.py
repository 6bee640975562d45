"""Pictures fit to print (issue 38.5): plot axes carry units (time and position coordinates in
the model's declared units, planar angles in rad; nothing invented where the unit is not known);
the animation player works offline (no Font Awesome from a CDN)."""

import numpy as np
import pytest

from mechsys import models
from mechsys.draw import phase_plot, plot


def _solution(units: dict | None):
    m = models.slider_crank()
    if units:
        m.set_units(**units)
    return m.solve(np.linspace(0, 1, 9))


def _labels(fig):
    return [a.get_ylabel() for a in fig.axes], fig.axes[-1].get_xlabel()


def test_axes_show_the_declared_units(monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt

    sol = _solution({"length": "mm", "time": "s"})
    names = list(sol.names)
    x_name = next(n for n in names if n.startswith("piston.") and n.endswith(".x"))
    fig = plot(sol, {"crank angle": "crank.th", "piston": x_name})
    ylabels, xlabel = _labels(fig)
    assert ylabels == ["crank angle [rad]", "piston [mm]"]
    assert xlabel == "t [s]"
    fig2 = phase_plot(sol, "crank.th", x_name)
    assert fig2.axes[0].get_xlabel() == "crank.th [rad]"
    assert fig2.axes[0].get_ylabel() == f"{x_name} [mm]"
    # an expression or callable has no known unit: its label is kept as given
    fig3 = plot(sol, {"speed": lambda s: s.coordinate(x_name, 1)}, x="crank.th",
                xlabel="crank")
    assert _labels(fig3) == (["speed"], "crank [rad]")
    plt.close("all")


def test_no_unit_is_invented_without_declared_units(monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt

    sol = _solution(None)
    x_name = next(n for n in sol.names if n.startswith("piston.") and n.endswith(".x"))
    ylabels, xlabel = _labels(plot(sol, {"crank angle": "crank.th", "piston": x_name}))
    assert ylabels == ["crank angle [rad]", "piston"]       # an angle is in rad regardless
    assert xlabel == "t"
    plt.close("all")


def test_rates_of_coordinates_carry_their_units(monkeypatch):
    """A velocity symbol (``m.omega(body)`` of a planar body, a coordinate's ``_d``) is the
    coordinate's unit per time unit; a label given to phase_plot keeps that unit."""
    monkeypatch.setenv("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt

    sol = _solution({"length": "mm", "time": "s"})
    m = sol.model
    piston_x = m.body("piston").q[0]
    fig = phase_plot(sol, "crank.th", m.omega(m.body("rod")), ylabel="rod rate")
    assert (fig.axes[0].get_xlabel(), fig.axes[0].get_ylabel()) == ("crank.th [rad]",
                                                                    "rod rate [rad/s]")
    speed = m.time_derivative(piston_x)            # the velocity symbol of piston.x
    assert plot(sol, {"piston speed": speed}).axes[0].get_ylabel() == "piston speed [mm/s]"
    plt.close("all")


def test_snapshot_axes_and_time_carry_the_declared_units(monkeypatch):
    """A drawing's axes are positions in the model's length unit and its time stamp in the
    time unit, when the model declares them; bare names otherwise (nothing invented)."""
    monkeypatch.setenv("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt

    from mechsys.draw import snapshot

    for units, x, stamp in (({"length": "mm", "time": "s"}, "x [mm]", "t = 0.500 s"),
                            (None, "x", "t = 0.500")):
        fig = snapshot(_solution(units), index=4)
        ax = fig.axes[0]
        assert (ax.get_xlabel(), ax.get_ylabel()) == (x, x.replace("x", "y"))
        assert stamp in [t.get_text() for t in ax.texts]
    plt.close("all")


def test_animation_player_needs_no_network(monkeypatch):
    """matplotlib's player loads Font Awesome from a CDN for its buttons (blank offline):
    the player mechsys writes has no remote link and shows its buttons as text."""
    import re

    monkeypatch.setenv("MPLBACKEND", "Agg")
    import mechsys as ms

    sol = _solution(None)
    anim = ms.draw.animate(sol, frames=3)
    html = anim.to_jshtml()
    anim.close()
    assert "font-awesome" not in html and 'class="fa ' not in html
    assert not re.search(r'<(?:link|script)[^>]+(?:href|src)="(?:https?:)?//', html)
    assert "\u25b6" in html and "\u23f8" in html                   # play and pause buttons
    assert html.count("<button") >= 9


def test_3d_tick_labels_do_not_overlap(monkeypatch):
    """A 3D snapshot of the Cardan joint had 16 pairs of overlapping tick labels (11 labels
    on each axis, whatever its drawn length): none now, on any axis."""
    import itertools

    monkeypatch.setenv("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt

    m = models.cardan_joint()
    sol = m.solve(np.linspace(0, 1, 5))
    fig = __import__("mechsys").draw.snapshot(sol)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        boxes = [t.get_window_extent(renderer) for t in axis.get_ticklabels()
                 if t.get_visible() and t.get_text()]
        assert 2 <= len(boxes) <= 6
        assert not [1 for a, b in itertools.combinations(boxes, 2) if a.overlaps(b)]
    plt.close("all")


def test_mode_animation_is_titled(monkeypatch):
    """A vibration mode's animation says which mode and at what frequency (it was
    untitled): the title's frequency is the mode's own, f = omega / (2 pi)."""
    import re

    monkeypatch.setenv("MPLBACKEND", "Agg")
    import mechsys as ms

    m = ms.Model2D()
    k, mass = 40.0, 2.0
    b = m.add_body("block", mass=mass, inertia=1.0, guess=((1, 0), 0))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), b.axis((0, 0), (1, 0))))
    m.add_load(ms.Spring(m.ground.point((0, 0)), b.point(0), stiffness=k, free_length=1.0))
    modes = m.vibration(at=m.guess())
    anim = modes.animate(0, frames=3)
    title = anim.figure.axes[0].get_title()
    anim.close()
    hz = float(re.fullmatch(r"mode 0: (\S+) Hz", title).group(1))
    assert hz == pytest.approx(np.sqrt(k / mass) / (2 * np.pi), rel=1e-3)


def test_tall_mechanism_picture_is_cropped(monkeypatch):
    """A hanging double pendulum is eight times taller than wide: its figure was 6.4 in wide
    around axes of a quarter of that (mostly white); the figure now hugs the axes."""
    monkeypatch.setenv("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt

    import mechsys as ms

    m = ms.Model2D()
    a = m.add_body("a", points={"tip": (1.0, 0)}, guess=((0, 0), -np.pi / 2 + 0.05))
    b = m.add_body("b", points={"tip": (1.0, 0)}, guess=((0.05, -1.0), -np.pi / 2 + 0.1))
    m.add(ms.Revolute2(m.ground.point((0, 0)), a.point(0)))
    m.add(ms.Revolute2(a.point("tip"), b.point(0)))
    m.add(ms.RotationLock1(a, -np.pi / 2 + 0.05))
    m.add(ms.RotationLock1(b, -np.pi / 2 + 0.1))
    fig = ms.draw.snapshot(m.solve(0.0))
    fig.canvas.draw()
    ax = fig.axes[0]
    box = ax.get_window_extent()
    width_px = fig.get_figwidth() * fig.dpi
    assert box.width / width_px > 0.45, (box.width, width_px)      # was about 0.2
    assert fig.get_figheight() >= 7.9
    plt.close("all")
