"""The papers' figures, reproduced: a registry of small figure functions.

Each figure is a function ``fn(ctx, **params)`` registered with :func:`figure`:
parameters in, images / plotted data / measured numbers out through the
:class:`Context` (``ctx.image``, ``ctx.plot``, ``ctx.table``, ``ctx.measure``).
:func:`plausible.figures.report.run` calls them with a progress bar, caches
them by a hash of their inputs and writes ``index.html``.

    >>> import plausible.figures as F
    >>> F.run("out", only=["as-furnace"], quick=True)   # doctest: +SKIP
"""

from __future__ import annotations

from .core import (DEFAULT_RESOLUTION, DEFAULT_SPP, FIGURES, QUICK_RESOLUTION, QUICK_SPP, Context, Figure, figure,
                   get, names)


def run(out, **kw):
    """Make the figures into ``out`` (see :func:`plausible.figures.report.run`)."""
    from .report import run as _run

    return _run(out, **kw)


__all__ = ["Context", "FIGURES", "Figure", "figure", "get", "names", "run"]
