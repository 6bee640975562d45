r"""Matplotlib renderers of evaluated pictures (:class:`Frames`): 2D axes for planar models,
3D axes for spatial ones. Imported only when a picture is drawn.

Each item becomes one artist created at the first frame and updated in place for the next
ones (``set_xy``, ``set_data``, ``set_verts``), so an animation frame costs no new artists.
3D faces are shaded by a fixed light (Lambert, two-sided) from normals computed per frame
by Newell's method.
"""

from __future__ import annotations

import numpy as np

from ._eval import Item
from ._scene import Frames

LIGHT = np.array([0.25, -0.75, 0.85]) / np.linalg.norm([0.25, -0.75, 0.85])


def _to_rgba(c, alpha=1.0):
    from matplotlib.colors import to_rgba

    r, g, b, a = to_rgba(c)
    return (r, g, b, a * alpha)


def _darker(c, f=0.55, alpha=1.0):
    r, g, b, a = _to_rgba(c, alpha)
    return (r * f, g * f, b * f, a)


def _finite(a) -> bool:
    return bool(a.size) and bool(np.all(np.isfinite(a)))


def poly_colors(it: Item, alpha_scale=1.0):
    """``(facecolor, edgecolor, linewidth)`` of a filled (or wire) item."""
    st = it.style
    color = st.get("color", "#777777")
    alpha = float(st.get("alpha", 1.0)) * alpha_scale
    faces = st.get("faces", True)
    ec = st.get("edgecolor")
    if faces:
        fc = _to_rgba(color, alpha)
        if ec is None:
            ec = _darker(color, alpha=alpha)
        elif ec != "none":
            ec = _to_rgba(ec, alpha)
        lw = float(st.get("linewidth", 1.0))
    else:
        fc = "none"
        ec = _to_rgba(color if ec in (None, "none") else ec, alpha)
        lw = float(st.get("linewidth", 1.2))
    return fc, ec, lw


def pad_faces(faces) -> np.ndarray:
    """Faces as an ``(F, kmax)`` index array, short faces padded with their last vertex
    (which adds nothing to Newell normals or to a drawn polygon)."""
    k = max(len(f) for f in faces)
    return np.array([list(f) + [f[-1]] * (k - len(f)) for f in faces], dtype=int)


def newell(P: np.ndarray) -> np.ndarray:
    """Unit normals of polygons ``P (F, k, 3)``."""
    n = np.cross(P, np.roll(P, -1, axis=1)).sum(axis=1)
    L = np.linalg.norm(n, axis=1, keepdims=True)
    return n / np.where(L > 0, L, 1.0)


def shade(rgba, normals: np.ndarray, light=LIGHT) -> np.ndarray:
    lam = 0.38 + 0.62 * np.abs(normals @ light)
    c = np.asarray(rgba, dtype=float)
    out = np.empty((len(normals), 4))
    out[:, :3] = np.clip(c[:3][None, :] * lam[:, None], 0, 1)
    out[:, 3] = c[3]
    return out


# ----------------------------------------------------------------------------------------
# 2D
# ----------------------------------------------------------------------------------------
class Artists2D:
    """The artists of a planar picture on one axes; ``update(k)`` moves them to frame k."""

    def __init__(self, ax, fr: Frames, k: int = 0, alpha: float = 1.0, moving_only=False):
        from matplotlib.collections import PolyCollection
        from matplotlib.patches import Polygon

        self.ax, self.fr = ax, fr
        self.entries = []
        for it in sorted(fr.items, key=lambda i: i.layer):
            if moving_only and it.static and it.upto is None:
                continue
            st = it.style
            z = 2 + 0.1 * it.layer
            a = it.at(k)
            alpha_it = float(st.get("alpha", 1.0)) * alpha
            if it.kind == "polygon":
                fc, ec, lw = poly_colors(it, alpha)
                art = Polygon(a if _finite(a) else np.zeros((3, 2)), closed=True, facecolor=fc,
                              edgecolor=ec, linewidth=lw, zorder=z,
                              linestyle=st.get("linestyle", "-"), label=st.get("label"))
                art.set_visible(_finite(a))
                ax.add_patch(art)
            elif it.kind == "mesh":
                fc, ec, lw = poly_colors(it, alpha)
                fidx = pad_faces(it.faces)
                art = PolyCollection(list(a[fidx]), facecolors=fc, edgecolors=ec, linewidths=lw,
                                     zorder=z)
                ax.add_collection(art)
                art._mechsys_faces = fidx
            elif it.kind in ("line", "points"):
                kw = dict(color=_to_rgba(st.get("color", "k"), alpha_it), zorder=z,
                          label=st.get("label"))
                if it.kind == "line":
                    kw.update(linewidth=float(st.get("linewidth", 1.5)),
                              linestyle=st.get("linestyle", "-"))
                else:
                    ms = float(st.get("markersize", 6))
                    kw.update(linestyle="none", marker=st.get("marker", "o"), markersize=ms,
                              markerfacecolor=kw["color"] if st.get("faces", True) else "none",
                              markeredgewidth=1.5)
                (art,) = ax.plot(a[:, 0], a[:, 1], **kw)
            elif it.kind == "text":
                art = [ax.text(p[0], p[1], _plain(s), color=st.get("color", "black"),
                               fontsize=st.get("fontsize", 9), zorder=z, clip_on=True,
                               alpha=alpha_it, ha="left", va="bottom")
                       for p, s in zip(a, it.texts or [])]
            else:  # pragma: no cover
                continue
            self.entries.append((it, art))

    def update(self, k: int) -> list:
        changed = []
        for it, art in self.entries:
            if it.static and it.upto is None:
                continue
            a = it.at(k)
            if it.kind == "polygon":
                ok = _finite(a)
                art.set_visible(ok)
                if ok:
                    art.set_xy(a)
            elif it.kind == "mesh":
                art.set_verts(list(a[art._mechsys_faces]))
            elif it.kind in ("line", "points"):
                art.set_data(a[:, 0], a[:, 1])
            elif it.kind == "text":
                for p, t in zip(a, art):
                    t.set_position((p[0], p[1]))
                    t.set_visible(bool(np.all(np.isfinite(p))))
                changed.extend(art)
                continue
            changed.append(art)
        return changed


def setup_2d(ax, fr: Frames, grid=True, margin=0.05):
    lo, hi = fr.bounds
    span = hi - lo
    pad = margin * max(float(span.max()), 0.1 * fr.size)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal", adjustable="box")
    ax.set_axisbelow(True)
    if grid:
        ax.grid(True, alpha=0.25)
    ax.set_xlabel(_axis_label(fr, "x"))
    ax.set_ylabel(_axis_label(fr, "y"))


def _axis_label(fr: Frames, name: str) -> str:
    """``"x [mm]"`` in the model's declared length unit; the bare name when none is declared
    (a unit is never invented: the model may be in any consistent system)."""
    from ..results._tables import LENGTH, unit_text

    unit = unit_text(LENGTH, getattr(fr.model, "units", None))
    return f"{name} [{unit}]" if unit else name


def _figsize_2d(fr: Frames, width=6.4):
    lo, hi = fr.bounds
    span = np.maximum(hi - lo, 1e-9)
    ratio = float(span[1] / span[0])
    tall = width * ratio * 0.92 + 0.9
    height = float(np.clip(tall, 2.6, 8.0))
    if tall > 8.0:
        # a tall mechanism (a hanging pendulum): the equal-aspect axes are narrower than the
        # figure, which was mostly white; narrow the figure to them (1.3 in for the y labels)
        width = float(np.clip((height - 0.9) / (ratio * 0.92) + 1.3, 2.6, width))
    return (width, height)


# ----------------------------------------------------------------------------------------
# 3D
# ----------------------------------------------------------------------------------------
class Artists3D:
    """The artists of a spatial picture on 3D axes; ``update(k)`` moves them to frame k."""

    def __init__(self, ax, fr: Frames, k: int = 0, alpha: float = 1.0, moving_only=False):
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        self.ax, self.fr = ax, fr
        self.entries = []
        for it in sorted(fr.items, key=lambda i: i.layer):
            if moving_only and it.static and it.upto is None:
                continue
            st = it.style
            a = it.at(k)
            alpha_it = float(st.get("alpha", 1.0)) * alpha
            if it.kind in ("mesh", "polygon"):
                faces = it.faces if it.kind == "mesh" else [tuple(range(len(a)))]
                fidx = pad_faces(faces)
                fc, ec, lw = poly_colors(it, alpha)
                P = a[fidx]
                if fc != "none":
                    colors = shade(fc, newell(P))
                    ec = "none" if st.get("edgecolor") is None else ec
                    lw = 0.3 if ec == "none" else lw
                else:
                    colors = "none"
                art = Poly3DCollection(list(P), facecolors=colors, edgecolors=ec, linewidths=lw)
                ax.add_collection3d(art)
                self.entries.append((it, (art, fidx, fc)))
            elif it.kind in ("line", "points"):
                kw = dict(color=_to_rgba(st.get("color", "k"), alpha_it), label=st.get("label"))
                if it.kind == "line":
                    kw.update(linewidth=float(st.get("linewidth", 1.5)),
                              linestyle=st.get("linestyle", "-"))
                else:
                    kw.update(linestyle="none", marker=st.get("marker", "o"),
                              markersize=float(st.get("markersize", 6)))
                (art,) = ax.plot(a[:, 0], a[:, 1], a[:, 2], **kw)
                self.entries.append((it, art))
            elif it.kind == "text":
                arts = [ax.text(p[0], p[1], p[2], _plain(s), color=st.get("color", "black"),
                                fontsize=st.get("fontsize", 9), alpha=alpha_it)
                        for p, s in zip(a, it.texts or [])]
                self.entries.append((it, arts))

    def update(self, k: int) -> list:
        changed = []
        for it, art in self.entries:
            if it.static and it.upto is None:
                continue
            a = it.at(k)
            if it.kind in ("mesh", "polygon"):
                coll, fidx, fc = art
                P = a[fidx]
                coll.set_verts(list(P))
                if fc != "none":
                    coll.set_facecolor(shade(fc, newell(P)))
                changed.append(coll)
            elif it.kind in ("line", "points"):
                art.set_data_3d(a[:, 0], a[:, 1], a[:, 2])
                changed.append(art)
            elif it.kind == "text":
                for p, t in zip(a, art):
                    t.set_position_3d(p)
                changed.extend(art)
        return changed


def setup_3d(ax, fr: Frames, view=None, grid=True):
    lo, hi = fr.bounds
    c = (lo + hi) / 2
    half = np.maximum((hi - lo) / 2, 0.3 * float(np.max(hi - lo)) / 2)
    half = np.maximum(half * 1.05, 1e-9)
    ax.set_xlim(c[0] - half[0], c[0] + half[0])
    ax.set_ylim(c[1] - half[1], c[1] + half[1])
    ax.set_zlim(c[2] - half[2], c[2] + half[2])
    ax.set_box_aspect(tuple(half / half.max()))
    # legible ticks: matplotlib puts up to 11 labels on each 3D axis whatever its drawn
    # length, and they overlap on short or foreshortened axes; a few per axis, in
    # proportion to its length in the box, at a smaller size
    from matplotlib.ticker import MaxNLocator

    for axis, frac in zip((ax.xaxis, ax.yaxis, ax.zaxis), half / half.max(), strict=True):
        axis.set_major_locator(MaxNLocator(nbins=max(2, int(round(4 * frac))), steps=[1, 2, 2.5, 5, 10]))
    ax.tick_params(labelsize=7, pad=0)
    ax.set_xlabel(_axis_label(fr, "x"))
    ax.set_ylabel(_axis_label(fr, "y"))
    ax.set_zlabel(_axis_label(fr, "z"))
    ax.grid(grid)
    elev, azim = view if view is not None else (25, -60)
    ax.view_init(elev=elev, azim=azim)


# ----------------------------------------------------------------------------------------
# Entry points
# ----------------------------------------------------------------------------------------
def _axes(fr: Frames, ax, figsize, dpi, pyplot=True):
    if ax is not None:
        return ax.figure, ax
    if figsize is None:
        figsize = _figsize_2d(fr) if fr.dim == 2 else (6.4, 5.6)
    if pyplot:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=figsize, dpi=dpi)
    else:
        from matplotlib.figure import Figure

        fig = Figure(figsize=figsize, dpi=dpi)
    ax = fig.add_subplot(111, projection="3d" if fr.dim == 3 else None)
    return fig, ax


def _artists(ax, fr, k, alpha=1.0, moving_only=False):
    return (Artists2D if fr.dim == 2 else Artists3D)(ax, fr, k, alpha, moving_only)


def _setup(ax, fr, grid, view):
    if fr.dim == 2:
        setup_2d(ax, fr, grid)
    else:
        setup_3d(ax, fr, view, grid)


def _time_label(ax, fr, k):
    if fr.dim == 2:
        return ax.text(0.01, 0.99, fr.time_text(k), transform=ax.transAxes, ha="left",
                       va="top", fontsize=9, zorder=10)
    return ax.text2D(0.01, 0.99, fr.time_text(k), transform=ax.transAxes, ha="left",
                     va="top", fontsize=9)


def _finish(fig, ax, fr, title):
    if title:
        ax.set_title(title)
    if any(it.style.get("label") for it in fr.items):
        ax.legend(loc="best", fontsize=8)
    if fig is not None and hasattr(fig, "tight_layout") and fr.dim == 2:
        fig.tight_layout()


def snapshot(fr: Frames, ax=None, figsize=None, dpi=None, title=None, show_time=True,
             grid=True, view=None, k=0):
    fig, ax = _axes(fr, ax, figsize, dpi)
    _setup(ax, fr, grid, view)
    _artists(ax, fr, k)
    if show_time:
        _time_label(ax, fr, k)
    _finish(fig, ax, fr, title)
    return fig


def overlay(fr: Frames, ax=None, figsize=None, dpi=None, title=None, grid=True, view=None,
            faint=0.2):
    fig, ax = _axes(fr, ax, figsize, dpi)
    _setup(ax, fr, grid, view)
    n = len(fr)
    for k in range(n):
        # min: faint + (1 - faint) * (n-1)/(n-1) can round to 1 + ulp, which matplotlib refuses
        alpha = 1.0 if n == 1 else min(1.0, faint + (1 - faint) * k / (n - 1))
        _artists(ax, fr, k, alpha, moving_only=k < n - 1)
    if title is None:
        title = f"{n} configurations, {fr.label} = {fr.t[0]:.3g} ... {fr.t[-1]:.3g}"
    _finish(fig, ax, fr, title)
    return fig


def animation_figure(fr: Frames, dpi=None, figsize=None, title=None, show_time=True, grid=True,
                     view=None):
    """A figure (not registered with pyplot) and ``update(k)`` for an animation."""
    fig, ax = _axes(fr, None, figsize, dpi or 80, pyplot=False)
    _setup(ax, fr, grid, view)
    arts = _artists(ax, fr, 0)
    label = _time_label(ax, fr, 0) if show_time else None
    _finish(fig, ax, fr, title)

    def update(k: int):
        out = arts.update(k)
        if label is not None:
            label.set_text(fr.time_text(k))
            out.append(label)
        return out

    return fig, update


def _plain(text) -> str:
    """``text`` drawn as written: matplotlib reads ``$...$`` as mathematics (an odd ``$`` in
    a name is an error), so dollars are escaped."""
    return str(text).replace("$", r"\$")
