r"""The self-contained interactive HTML viewer.

One HTML file with the frames and a small renderer written here (no third-party code, no
network; see ``docs/decisions/0003-html-viewer.md``): a Canvas-2D painter's-algorithm
renderer with per-face depth sorting and flat Lambert shading, orbit / pan / zoom, a time
slider, a play button and a playback-rate selector.

Data layout (JSON inside a ``<script type="application/json">``; numeric arrays as
base64 little-endian float32 / int32):

* ``poses``: ``N x nbodies x 12`` floats, per frame and body ``r (3)`` then ``A (3x3)``
  row-major (planar models lifted to z = 0);
* ``items``: each with ``kind``, ``body`` (index into the poses, or -1), ``nv`` vertices,
  ``nf`` frames stored (1 static, N moving; rigid items store their local vertices once),
  ``v`` vertices, for meshes ``faces`` (flat indices) and ``fcount`` (vertices per face),
  colours as RGBA 0..1, line width and marker size in CSS pixels, ``layer``.
"""

from __future__ import annotations

import base64
import json

import numpy as np

from ._scene import Frames
from ._viewer_js import VIEWER_CSS, VIEWER_JS

PT = 96 / 72  # CSS pixels per point


def _b64(a, dtype) -> str:
    """Base64 of the array as little-endian ``dtype`` ("<f4" or "<i4")."""
    return base64.b64encode(np.ascontiguousarray(a, dtype=dtype).tobytes()).decode("ascii")


def _lift(a: np.ndarray) -> np.ndarray:
    """Pad planar coordinates (..., 2) to (..., 3) with z = 0."""
    if a.shape[-1] == 3:
        return a
    pad = np.zeros(a.shape[:-1] + (1,))
    return np.concatenate([a, pad], axis=-1)


def _round(c):
    return [round(float(v), 4) for v in c]


def _rgba(c, alpha=1.0):
    from matplotlib.colors import to_rgba

    r, g, b, a = to_rgba(c)
    return [round(r, 4), round(g, 4), round(b, 4), round(a * alpha, 4)]


def viewer_data(fr: Frames, title: str = "mechsys", rate: float = 1.0,
                autoplay: bool = False, size=None) -> dict:
    from ._mpl import poly_colors

    N, dim = len(fr), fr.dim
    # poses of bodies used by rigid moving items
    pose_index: dict[int, int] = {}
    pose_list = []
    for it in fr.items:
        if it.rigid is not None and it.upto is None:
            pose = it.rigid[0]
            if pose.r.shape[0] == N and N > 1 and id(pose) not in pose_index:
                pose_index[id(pose)] = len(pose_list)
                pose_list.append(pose)
    nb = len(pose_list)
    P = np.zeros((N, max(nb, 1), 12), dtype=float)
    for j, pose in enumerate(pose_list):
        r = _lift(pose.r)
        A = np.zeros((N, 3, 3))
        A[:, :dim, :dim] = pose.A
        if dim == 2:
            A[:, 2, 2] = 1.0
        P[:, j, :3] = r
        P[:, j, 3:] = A.reshape(N, 9)
    items = []
    for it in sorted(fr.items, key=lambda i: i.layer):
        st = it.style
        d: dict = {"kind": it.kind, "layer": int(it.layer)}
        if it.rigid is not None and it.upto is None and id(it.rigid[0]) in pose_index:
            d["body"] = pose_index[id(it.rigid[0])]
            verts = _lift(np.asarray(it.rigid[1], dtype=float))[None]
        else:
            d["body"] = -1
            verts = _lift(it.xyz)
        d["nv"], d["nf"] = int(verts.shape[1]), int(verts.shape[0])
        d["v"] = _b64(verts.reshape(-1), "<f4")
        if it.kind in ("mesh", "polygon"):
            faces = it.faces if it.kind == "mesh" else [tuple(range(verts.shape[1]))]
            d["faces"] = _b64(np.concatenate([np.asarray(f, dtype=int) for f in faces]), "<i4")
            d["fcount"] = _b64([len(f) for f in faces], "<i4")
            fc, ec, lw = poly_colors(it)
            d["fill"] = fc != "none"
            d["color"] = _round(fc if d["fill"] else ec)
            explicit = st.get("edgecolor") is not None or dim == 2
            d["edge"] = _round(ec) if (d["fill"] and explicit and ec != "none") else None
            d["lw"] = round(lw * PT, 3)
        else:
            alpha = float(st.get("alpha", 1.0))
            d["color"] = _rgba(st.get("color", "black"), alpha)
            d["lw"] = round(float(st.get("linewidth", 1.5)) * PT, 3)
            d["closed"] = bool(it.closed)
            ls = st.get("linestyle", "-")
            d["dash"] = {"--": [6, 4], ":": [1.5, 3], "-.": [6, 3, 1.5, 3]}.get(ls, [])
            d["ms"] = round(float(st.get("markersize", 6)) * PT, 3)
            d["hollow"] = not st.get("faces", True)
            d["fs"] = round(float(st.get("fontsize", 9)) * PT, 3)
            if it.texts is not None:
                d["texts"] = [str(s) for s in it.texts]
        if it.upto is not None:
            d["upto"] = _b64(np.asarray(it.upto), "<i4")
        items.append(d)
    lo, hi = _lift(fr.bounds[0]), _lift(fr.bounds[1])
    return {
        "version": 1,
        "title": str(title),
        "dim": dim,
        "label": fr.label,
        "times": [float(t) for t in fr.t],
        "rate": float(rate),
        "autoplay": bool(autoplay),
        "size": [int(size[0]), int(size[1])] if size is not None else None,
        "bounds": [[float(v) for v in lo], [float(v) for v in hi]],
        "nbodies": max(nb, 1),
        "poses": _b64(P.reshape(-1), "<f4") if nb else "",
        "items": items,
    }


def viewer_html(fr: Frames, title: str = "mechsys", rate: float = 1.0,
                autoplay: bool = False, size=None) -> str:
    data = viewer_data(fr, title, rate, autoplay, size)
    # no "<", ">" or "&" in the script block, whatever a name holds ("</script>", "<!--"):
    # JSON's own escapes, which JSON.parse reads back as the same characters
    blob = (json.dumps(data, separators=(",", ":")).replace("<", "\\u003c")
            .replace(">", "\\u003e").replace("&", "\\u0026"))
    esc = (str(title).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;"))
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="generator" content="mechsys">
<title>{esc}</title>
<style>{VIEWER_CSS}</style>
</head>
<body>
<canvas id="view"></canvas>
<div id="info"><b id="title"></b> <span id="time"></span></div>
<div id="help">drag: rotate &middot; shift/right drag: pan &middot; wheel: zoom &middot;
double-click: reset &middot; space: play</div>
<div id="err"></div>
<div id="bar">
<button id="play" title="play / pause (space)">&#9654;</button>
<input id="slider" type="range" min="0" max="0" value="0" step="1" aria-label="frame">
<label>speed <select id="rate"></select></label>
<label><input id="ortho" type="checkbox"> ortho</label>
<button id="home" title="reset the view (double-click)">reset view</button>
</div>
<script type="application/json" id="mechsys-data">{blob}</script>
<script>{VIEWER_JS}</script>
</body>
</html>
"""
