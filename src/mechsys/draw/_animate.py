r"""Animations: frames rendered with matplotlib and written as GIF (Pillow, always
available with matplotlib), MP4 (when ffmpeg is installed) or a JavaScript player
(``to_jshtml``, shown inline in Jupyter).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .._errors import MechError
from ._progress import Progress


def ffmpeg_available() -> bool:
    from matplotlib.animation import FFMpegWriter

    return bool(FFMpegWriter.isAvailable())


class Animation:
    """A rendered-on-demand animation of a solution.

    ``frames`` (count), ``times`` (solution time of each frame), ``interval`` (seconds of
    playback between frames), ``fps``; ``save(path)``, ``to_jshtml()``; displays itself in
    Jupyter. ``figure`` is the matplotlib figure drawn into (``update(k)`` shows frame k).
    """

    def __init__(self, figure, update, frames: int, interval: float, times, dpi=None):
        self.figure = figure
        self.update = update
        self.frames = int(frames)
        self.interval = float(interval)
        self.times = np.asarray(times)
        self.dpi = dpi

    @property
    def fps(self) -> float:
        return 1.0 / self.interval if self.interval > 0 else 10.0

    def save(self, path, fps=None, dpi=None, progress=None) -> Path:
        """Write ``.gif``, ``.mp4`` (needs ffmpeg) or ``.html``; returns the path."""
        import matplotlib.animation as manim

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        suffix = path.suffix.lower()
        fps = float(fps) if fps is not None else self.fps
        dpi = dpi or self.dpi or self.figure.dpi
        if suffix in (".html", ".htm"):
            path.write_text(self.to_jshtml(), encoding="utf-8")
            return path
        if suffix == ".gif":
            writer = manim.PillowWriter(fps=fps)
        elif suffix in (".mp4", ".m4v", ".mov"):
            if not ffmpeg_available():
                raise MechError("saving MP4 needs ffmpeg on the PATH (apt-get install ffmpeg); "
                                "save as .gif or .html instead")
            writer = manim.FFMpegWriter(fps=fps, codec="h264", extra_args=["-pix_fmt", "yuv420p"])
        else:
            raise MechError(f"unknown animation format {suffix!r}; use .gif, .mp4 or .html")
        bar = Progress(self.frames, f"writing {path.name}", progress)
        with writer.saving(self.figure, str(path), dpi):
            for k in range(self.frames):
                self.update(k)
                writer.grab_frame()
                bar.update(k + 1)
        bar.close()
        return path

    def _funcanimation(self):
        import matplotlib.animation as manim

        return manim.FuncAnimation(self.figure, self.update, frames=self.frames,
                                   interval=1000 * self.interval, blit=False, repeat=True)

    def to_jshtml(self, default_mode: str = "loop") -> str:
        """An HTML/JavaScript player of the frames (what Jupyter shows)."""
        import matplotlib as mpl

        anim = self._funcanimation()
        limit = max(float(mpl.rcParams["animation.embed_limit"]), 200.0)
        with mpl.rc_context({"animation.embed_limit": limit}):
            return offline_player(anim.to_jshtml(fps=self.fps, default_mode=default_mode))

    def _repr_html_(self) -> str:
        return self.to_jshtml()

    def close(self) -> None:
        """Release the figure."""
        self.figure.clear()

    def __repr__(self) -> str:
        return (f"<Animation: {self.frames} frames at {self.fps:.3g} fps, "
                f"t = {self.times[0]:g} ... {self.times[-1]:g}>")


# matplotlib's player draws its buttons with Font Awesome icons loaded from a CDN: offline
# (or behind a firewall) the buttons are blank. The same symbols as text need no font file.
_FA_LINK = re.compile(r'<link rel="stylesheet"\s+href="https?://[^"]*font-awesome[^"]*">\s*')
_FA_ICONS = {
    "fa fa-minus": "\u2212", "fa fa-fast-backward": "\u23ee", "fa fa-step-backward": "\u23f4\u2759",
    "fa fa-play fa-flip-horizontal": "\u25c0", "fa fa-pause": "\u23f8", "fa fa-play": "\u25b6",
    "fa fa-step-forward": "\u2759\u23f5", "fa fa-fast-forward": "\u23ed", "fa fa-plus": "+",
}


def offline_player(html: str) -> str:
    """matplotlib's ``to_jshtml`` player without its Font Awesome style sheet (a CDN): each
    icon becomes the Unicode symbol it shows, so the buttons read the same with no network."""
    html = _FA_LINK.sub("", html)

    def icon(m: re.Match) -> str:
        return f'<span aria-hidden="true">{_FA_ICONS.get(m.group(1), "?")}</span>'

    return re.sub(r'<i class="(fa [^"]+)"></i>', icon, html)
