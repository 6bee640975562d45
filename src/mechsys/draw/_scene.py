r"""Scenes: a model plus its graphics, evaluated over the frames of a solution.

Graphics live here, not on the model: ``Scene(model, [primitives])``, or attach them to a
model once with :func:`attach` (a weak registry keyed by the model, so the model itself
stays free of drawing state) and every picture of that model uses them. A model with no
graphics is drawn by :class:`~mechsys.draw.Skeleton` (its bodies' points and joints).

Evaluation (:meth:`Scene.evaluate`) gives a :class:`Frames`: renderer-independent items in
global coordinates over the frames, a characteristic size and the bounds of the picture.
Renderers (matplotlib 2D/3D, the HTML viewer) only read a ``Frames``.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import sympy as sp

from .._errors import MechError, ModelError
from ._default import Skeleton
from ._eval import Evaluator, Item, Pose, as_solution, subsolution
from ._primitives import Primitive

_REGISTRY: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def attach(model, *primitives: Primitive) -> None:
    """Attach graphics primitives to a model (used by every picture of it)."""
    for p in primitives:
        if not isinstance(p, Primitive):
            raise ModelError(f"attach: expected graphics primitives (Bar, Arrow, ...), got {p!r}")
    _REGISTRY.setdefault(model, []).extend(primitives)


def attached(model) -> list[Primitive]:
    """The graphics attached to a model."""
    return list(_REGISTRY.get(model, []))


def detach(model) -> None:
    """Remove all graphics attached to a model."""
    _REGISTRY.pop(model, None)


@dataclass(eq=False)
class Frames:
    """An evaluated picture: ``items`` over ``len(t)`` frames of a model of dimension
    ``dim``; ``size`` a characteristic length, ``bounds`` ``(2, dim)`` min/max over all
    frames, ``poses`` the body poses used by rigid items."""

    model: object
    dim: int
    t: np.ndarray
    items: list[Item]
    size: float
    bounds: np.ndarray
    poses: list[Pose] = field(default_factory=list)
    label: str = "t"

    def __len__(self) -> int:
        return len(self.t)

    def time_text(self, k: int) -> str:
        """``"t = 0.250"``, with the model's time unit when it declares one (``"t = 0.250 s"``)."""
        from ..results._tables import unit_text

        unit = unit_text((0, 0, 1), getattr(self.model, "units", None)) if self.label == "t" else None
        return f"{self.label} = {self.t[k]:.3f}" + (f" {unit}" if unit else "")


class Scene:
    """A model and its graphics.

    ``graphics``: primitives drawn in addition to those attached to the model.
    ``default``: draw the :class:`Skeleton` (bodies and joints): ``"auto"`` (only when no
    graphics are given or attached), ``True`` or ``False``.
    """

    def __init__(self, model, graphics=None, default="auto"):
        if not hasattr(model, "bodies") or not hasattr(model, "space"):
            raise ModelError(f"Scene needs a Model, got {model!r}")
        if default not in ("auto", True, False):
            raise ModelError("Scene: default must be 'auto', True or False")
        self.model = model
        self.graphics: list[Primitive] = []
        self.default = default
        if graphics is not None:
            self.add(*(graphics if isinstance(graphics, (list, tuple)) else [graphics]))

    def add(self, *primitives: Primitive) -> Scene:
        for p in primitives:
            if not isinstance(p, Primitive):
                raise ModelError(f"Scene.add: expected graphics primitives, got {p!r}")
        self.graphics.extend(primitives)
        return self

    def primitives(self) -> list[Primitive]:
        own = attached(self.model) + self.graphics
        if self.default is True or (self.default == "auto" and not own):
            return [Skeleton()] + own
        return own

    # -- evaluation -----------------------------------------------------------------------
    def evaluate(self, solution=None, frames=None) -> Frames:
        """Evaluate all graphics at the given frames of ``solution`` (default: the model's
        last solution, or its initial guess). ``frames``: ``None`` (all time points), an
        index, a list of indices, or a :class:`Solution` already restricted to the frames
        (``solution`` then gives the full motion, for loci and guides)."""
        full = as_solution(solution if solution is not None else
                           (self.model.last_solution or self.model))
        if full.model is not self.model:
            raise ModelError("this solution belongs to another model than the scene's")
        if frames is None:
            sub = full
        elif hasattr(frames, "eval"):
            sub = as_solution(frames)
        else:
            idx = np.atleast_1d(np.asarray(frames, dtype=int))
            n = len(full.t)
            if idx.size == 0 or idx.min() < -n or idx.max() >= n:
                raise ModelError(f"frame indices must lie in 0..{n - 1}")
            sub = subsolution(full, idx % n)
        ev = Evaluator(self.model, sub, full)
        ev.later(lambda: _set_size(ev))
        finishers = [p._prepare(ev) for p in self.primitives()]
        ev.run()
        items: list[Item] = []
        for f in finishers:
            items.extend(f())
        bounds = _bounds(items, ev.dim, ev.size)
        label = "t"
        return Frames(self.model, ev.dim, np.asarray(sub.t, dtype=float), items, ev.size, bounds,
                      ev.poses, label)

    # -- renderers ------------------------------------------------------------------------
    def snapshot(self, solution=None, index=0, t=None, ax=None, **kw):
        """A matplotlib figure of one configuration: frame ``index`` of the solution, or
        time ``t`` (interpolated). 3D models get a 3D axes. Keywords: ``figsize``, ``dpi``,
        ``title``, ``show_time``, ``grid``, ``view=(elev, azim)`` (3D)."""
        sol = as_solution(solution if solution is not None else
                          (self.model.last_solution or self.model))
        if t is not None:
            frames = _at_time(sol, t)
        else:
            frames = [index]
        fr = self.evaluate(sol, frames)
        from . import _mpl

        return _mpl.snapshot(fr, ax=ax, **kw)

    def overlay(self, solution=None, frames=6, ax=None, **kw):
        """Several configurations in one picture, earlier ones fainter: ``frames`` an
        int (that many, evenly spread over the solution) or a list of indices."""
        sol = as_solution(solution if solution is not None else
                          (self.model.last_solution or self.model))
        if isinstance(frames, (int, np.integer)):
            idx = np.unique(np.linspace(0, len(sol.t) - 1, int(frames)).round().astype(int))
        else:
            idx = np.asarray(frames, dtype=int)
        fr = self.evaluate(sol, idx)
        from . import _mpl

        return _mpl.overlay(fr, ax=ax, **kw)

    def animate(self, solution=None, path=None, fps=None, rate=1.0, frames=None, dpi=None,
                progress=None, **kw):
        """Animate a solution. Returns an :class:`~mechsys.draw.Animation` (which shows
        itself in Jupyter), or, with ``path``, saves it (``.gif`` always; ``.mp4`` when
        ffmpeg is present; ``.html`` a self-contained JavaScript player) and returns the
        path.

        Timing: ``rate`` is the playback speed (1 = real time, 0.5 = slow motion);
        ``fps`` resamples the motion at that many frames per second of playback;
        ``frames`` asks for exactly that many frames. By default the solution's own time
        points are the frames (thinned when they would play faster than 50 per second).
        ``progress``: print a progress bar to stderr (default: only for long renders on a
        terminal).
        """
        sol = as_solution(solution if solution is not None else
                          (self.model.last_solution or self.model))
        sub, interval = timeline(sol, fps=fps, rate=rate, frames=frames)
        fr = self.evaluate(sol, sub)
        from . import _mpl
        from ._animate import Animation

        fig, update = _mpl.animation_figure(fr, dpi=dpi, **kw)
        anim = Animation(fig, update, len(fr), interval, fr.t, dpi=dpi)
        if path is None:
            return anim
        out = anim.save(path, progress=progress)
        anim.close()
        return out

    def viewer(self, solution=None, path=None, fps=None, rate=1.0, frames=None, title=None,
               autoplay=False, size=None):
        """A self-contained interactive HTML viewer (orbit, zoom, time slider, play button;
        no network needed). Returns the HTML text, or writes it to ``path`` and returns the
        path. ``rate``: initial playback speed (1 = real time); ``frames``/``fps``: resample
        the motion (default: the solution's points, at most 600); ``size=(w, h)``: a fixed
        canvas size in CSS pixels (default: the whole window; also ``file.html#size=WxH``).
        """
        sol = as_solution(solution if solution is not None else
                          (self.model.last_solution or self.model))
        if frames is None and fps is None:
            frames = min(len(sol.t), 600) if len(sol.t) > 600 else None
        sub, _ = timeline(sol, fps=fps, rate=rate, frames=frames, max_fps=None)
        fr = self.evaluate(sol, sub)
        from ._html import viewer_html

        html = viewer_html(fr, title=title or "mechsys", rate=rate, autoplay=autoplay, size=size)
        if path is None:
            from ._jupyter import ViewerHTML

            return ViewerHTML(html, size=size)      # a str that shows itself in Jupyter
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(html, encoding="utf-8")
        return p

    def __repr__(self) -> str:
        return f"<Scene of {self.model!r}: {len(self.primitives())} primitive(s)>"


# ----------------------------------------------------------------------------------------
def _set_size(ev: Evaluator) -> None:
    """Characteristic length: the diagonal of the box holding every body's origin and named
    points over the whole solution."""
    model = ev.model
    pts = []
    for b in model.bodies:
        pts.append(b.point(0))
        for name in b.points:
            pts.append(b.point(name))
    exprs = []
    for p in pts:
        loc = p.location()
        exprs.extend(loc)
    vals = np.asarray(ev.full.eval(sp.Matrix(exprs)), dtype=float).reshape(-1, ev.dim)
    vals = vals[np.all(np.isfinite(vals), axis=1)]
    size = float(np.linalg.norm(np.ptp(vals, axis=0))) if len(vals) else 0.0
    ev.size = size if size > 1e-12 else 1.0


def _bounds(items: list[Item], dim: int, size: float) -> np.ndarray:
    lo = np.full(dim, np.inf)
    hi = np.full(dim, -np.inf)
    for it in items:
        if not it.fit:
            continue
        a = it.xyz.reshape(-1, dim)
        a = a[np.all(np.isfinite(a), axis=1)]
        if a.size:
            lo = np.minimum(lo, a.min(axis=0))
            hi = np.maximum(hi, a.max(axis=0))
    if not np.all(np.isfinite(lo)):
        lo, hi = -np.full(dim, size / 2), np.full(dim, size / 2)
    for it in items:  # far points (instant centres near infinity) stay off the picture
        if it.fit:
            continue
        a = it.xyz.reshape(-1, dim)
        near = np.all(np.isfinite(a), axis=1) & np.all((a > lo - size) & (a < hi + size), axis=1)
        if near.any():
            lo = np.minimum(lo, a[near].min(axis=0))
            hi = np.maximum(hi, a[near].max(axis=0))
    return np.array([lo, hi])


def _at_time(sol, t):
    k = np.flatnonzero(np.isclose(sol.t, t, rtol=0, atol=1e-12))
    if k.size:
        return [int(k[0])]
    if len(sol.t) < 2:
        raise MechError(f"no frame at t = {t}: the solution has one time point")
    return sol.interpolate(np.atleast_1d(float(t)))


def timeline(sol, fps=None, rate=1.0, frames=None, max_fps=50.0):
    """The frames of an animation and the playback interval between them (seconds).

    Returns ``(frames, interval)``: frame indices into ``sol``, or an interpolated
    Solution when the requested times are not solution points.
    """
    t = np.asarray(sol.t, dtype=float)
    if rate is None or not rate > 0:
        raise ModelError(f"rate must be positive (1 = real time), got {rate!r}")
    N = len(t)
    D = float(t[-1] - t[0]) if N > 1 else 0.0
    if N == 1 or D <= 0:
        return np.zeros(1, dtype=int), 0.1
    if frames is not None or fps is not None:
        if frames is not None:
            n = int(frames)
            if n < 1:
                raise ModelError("frames must be at least 1")
        else:
            if not fps > 0:
                raise ModelError(f"fps must be positive, got {fps!r}")
            n = int(round(D / rate * fps)) + 1
        times = np.linspace(t[0], t[-1], n)
        interval = D / rate / max(n - 1, 1)
        idx = np.searchsorted(t, times)
        idx = np.clip(idx, 0, N - 1)
        if np.allclose(t[idx], times, rtol=0, atol=1e-12 * max(1.0, abs(D))):
            return idx, interval
        return sol.interpolate(times), interval
    dt = D / (N - 1)
    step = 1
    if max_fps is not None and rate / dt > max_fps:
        step = math.ceil(rate / dt / max_fps)
    idx = np.arange(0, N, step)
    return idx, step * dt / rate
