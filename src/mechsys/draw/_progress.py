"""The progress bar of renders: :class:`mechsys._progress.Progress` (tqdm), kept here under its
old name for the renderers."""

from .._progress import Progress

__all__ = ["Progress"]
