r"""Pictures of mechanisms: graphics primitives, snapshots, animations, a 3D HTML viewer
and plots of outputs.

Nothing here imports matplotlib until a picture is actually drawn. Quick start::

    import numpy as np
    import mechsys as ms
    from mechsys import models

    m = models.slider_crank()
    sol = m.solve(np.linspace(0, 1, 61))
    ms.draw.snapshot(sol)                          # the model's default picture at t = 0
    ms.draw.animate(sol, "slider_crank.gif")       # GIF (MP4 with ffmpeg, .html player)
    ms.draw.viewer(sol, "slider_crank.html")       # interactive 3D viewer, no network
    ms.draw.plot(sol, {"piston x": m.location(m.body("piston").point(0))[0]})

Graphics with Mech's names are functions of body coordinates evaluated at any state::

    scene = ms.draw.Scene(m, [ms.draw.Bar("crank", (0, "pin"), 0.3),
                              ms.draw.LocusPlot(m.body("rod").point((3, 0)))])
    scene.snapshot(sol, t=0.25); scene.animate(sol, "out.gif", rate=0.5)

or attach them to the model once: ``ms.draw.attach(m, ms.draw.Bar(...))``.
"""

from __future__ import annotations

import numpy as np

from ._animate import Animation, ffmpeg_available
from ._default import Skeleton
from ._eval import STYLE_KEYS, Item
from ._explore import Explorer, explore
from ._jupyter import ViewerHTML
from ._plots import phase_plot, plot
from ._primitives import (
    Arrow,
    Bar,
    Box,
    CamPlot,
    Cylinder,
    Edge,
    Extrude,
    Facet,
    GroundPivot,
    InstantCenter,
    LocalAxes,
    LocusPlot,
    Mesh,
    PitchCircle,
    PointLabel,
    Primitive,
    Revolve,
    Sphere,
    Torus,
    Vertex,
    Wheel,
    body_color,
)
from ._scene import Frames, Scene, attach, attached, detach


def _scene(obj, graphics, default):
    from ._eval import as_solution

    if hasattr(obj, "bodies") and hasattr(obj, "space"):
        return Scene(obj, graphics, default), None
    sol = as_solution(obj)
    return Scene(sol.model, graphics, default), sol


def snapshot(solution, graphics=None, index=0, t=None, default="auto", **kw):
    """A matplotlib figure of one configuration (frame ``index`` or time ``t``) of a
    solution; a Model is drawn at its last solution (at its initial guess before any solve).
    ``graphics``: extra primitives."""
    scene, sol = _scene(solution, graphics, default)
    return scene.snapshot(sol, index=index, t=t, **kw)


def overlay(solution, graphics=None, frames=6, default="auto", **kw):
    """Several configurations of a solution overlaid, earlier ones fainter."""
    scene, sol = _scene(solution, graphics, default)
    return scene.overlay(sol, frames=frames, **kw)


def ReactionArrow(constraint, body, point=None, scale="auto", **style) -> Arrow:
    """An arrow of the force that ``constraint`` applies to ``body`` (from a static,
    kinematic or dynamic solution), drawn ending at ``point`` (default the body origin)
    so it pushes on it. ``scale="auto"`` sizes the largest to a quarter of the picture."""

    def force(sol):
        return np.asarray(sol.reaction(constraint, body)[0])

    return Arrow(point if point is not None else body.point(0), force, scale=scale,
                 anchor="head", **style)


def animate(solution, path=None, graphics=None, default="auto", **kw):
    """Animate a solution: an :class:`Animation`, or with ``path`` (``.gif``, ``.mp4``,
    ``.html``) the written file. See :meth:`Scene.animate` for timing options."""
    scene, sol = _scene(solution, graphics, default)
    return scene.animate(sol, path=path, **kw)


def viewer(solution, path=None, graphics=None, default="auto", **kw):
    """A self-contained interactive HTML viewer of a solution (orbit, zoom, time slider,
    play button); the HTML text, or the written path."""
    scene, sol = _scene(solution, graphics, default)
    return scene.viewer(sol, path=path, **kw)


__all__ = [
    "Explorer",
    "explore",
    "ReactionArrow",
    "STYLE_KEYS",
    "Animation",
    "Arrow",
    "Bar",
    "Box",
    "Cylinder",
    "Edge",
    "Extrude",
    "Facet",
    "Frames",
    "GroundPivot",
    "InstantCenter",
    "Item",
    "LocalAxes",
    "CamPlot",
    "LocusPlot",
    "PitchCircle",
    "PointLabel",
    "Primitive",
    "Revolve",
    "Scene",
    "Skeleton",
    "Sphere",
    "Mesh",
    "Torus",
    "Vertex",
    "ViewerHTML",
    "Wheel",
    "animate",
    "attach",
    "attached",
    "body_color",
    "detach",
    "ffmpeg_available",
    "overlay",
    "phase_plot",
    "plot",
    "snapshot",
    "viewer",
]
