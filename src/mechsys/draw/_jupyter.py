r"""The HTML viewer inline in Jupyter.

:func:`mechsys.draw.viewer` without a path returns a :class:`ViewerHTML`: the viewer's
self-contained HTML page as a ``str`` (so it can still be written, compared or served), which
a notebook shows inline, in an ``<iframe srcdoc=...>``. The frame keeps the viewer's
element ids, style and key bindings apart from the notebook's and from other viewers in the
same notebook; nothing is fetched from the network. Example::

    ms.draw.viewer(sol)                       # last expression of a cell: shown inline
    ms.draw.viewer(sol, size=(480, 320))      # a fixed canvas size, and a frame to fit

(animations show themselves as a JavaScript player: :class:`mechsys.draw.Animation`.)
"""

from __future__ import annotations

import html

DEFAULT_HEIGHT = 440      # CSS pixels of the inline frame when the viewer fills its window
_BAR = 60                 # room for the time slider and buttons under a fixed-size canvas


class ViewerHTML(str):
    """The HTML text of a viewer page that displays itself inline in Jupyter."""

    size: tuple[int, int] | None = None

    def __new__(cls, text: str, size=None):
        obj = super().__new__(cls, text)
        obj.size = (int(size[0]), int(size[1])) if size is not None else None
        return obj

    def iframe(self, height: int | None = None) -> str:
        """An ``<iframe>`` element holding the page (``srcdoc``, HTML-escaped)."""
        if height is None:
            height = self.size[1] + _BAR if self.size else DEFAULT_HEIGHT
        width = f"{self.size[0] + 20}px" if self.size else "100%"
        doc = html.escape(str(self), quote=True)
        return (f'<iframe class="mechsys-viewer" srcdoc="{doc}" title="mechsys viewer" '
                f'style="width: {width}; height: {int(height)}px; border: 1px solid #ccc;" '
                'sandbox="allow-scripts"></iframe>')

    def _repr_html_(self) -> str:
        return self.iframe()

    def __repr__(self) -> str:
        # the plain-text display (terminals, a notebook's text/plain): not 40 kB of HTML
        return (f"<ViewerHTML: {len(self)} characters of HTML; shown inline in Jupyter, "
                "or write it to a .html file>")
