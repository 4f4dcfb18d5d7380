"""Values as text and as JSON: the one home of the small formatters.

* :func:`fmt` -- a parameter value (number, colour, choice, nested model) as
  text; the model ``repr`` (also the pumped-up table cache key), the command
  line's tables, fit summaries and the figures report use it with their own
  number format and separators.
* :func:`shorten` -- a value's text cut for an error message;
* :func:`html_table` -- a small HTML table, the ``_repr_html_`` of models,
  reports and results in a notebook.
* :func:`jsonable` -- plain JSON data from results holding NumPy arrays and
  scalars (non-finite numbers become the strings ``"inf"``, ``"nan"``, which
  strict JSON readers accept).
* :func:`write_atomic` -- a text file written whole or not at all (the output
  files of ``convert`` and ``export``); :func:`write_all_atomic` several, all or
  none; :func:`replacing` the same for any writer (an image's ``savefig``).
"""

from __future__ import annotations

import math
import os
from contextlib import contextmanager

import numpy as np


def fmt(v, spec: str = "g", *, sep: str = ", ", brackets: bool = True, other=str,
        sequences: tuple = (np.ndarray,)) -> str:
    """``v`` as text: floats with the format ``spec``; an instance of ``sequences``
    (default: NumPy arrays) element by element, joined by ``sep`` (inside
    ``[...]`` if ``brackets``); anything else with ``other`` (``str`` or ``repr``).

    >>> fmt(np.array([0.5, 1.0]))
    '[0.5, 1]'
    >>> fmt((0.5, 1.0), sep=",", brackets=False, sequences=(tuple,))
    '0.5,1'
    >>> fmt("max", other=repr)
    "'max'"
    """
    if isinstance(v, sequences):
        items = v.ravel().tolist() if isinstance(v, np.ndarray) else list(v)
        body = sep.join(f"{x:{spec}}" if isinstance(x, float) else str(x) for x in items)
        return f"[{body}]" if brackets else body
    return f"{v:{spec}}" if isinstance(v, float) else other(v)


def jsonable(x):
    """``x`` with NumPy arrays and scalars turned into lists and Python numbers,
    recursively through dicts, lists and tuples; non-finite floats as strings; a
    model (e.g. pumped-up's base) as its spec string (:meth:`plausible.bxdf.BxDF.spec`)."""
    if isinstance(x, dict):
        return {k: jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else str(v)
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    if hasattr(x, "spec") and hasattr(x, "eval"):       # a nested model (pumped-up's base)
        return x.spec()
    return x


def shorten(text: str, n: int = 60) -> str:
    """``text`` cut to ``n`` characters, the last three ``...`` (for error messages).

    >>> shorten("x" * 70)[-5:], len(shorten("x" * 70))
    ('xx...', 60)
    """
    return text if len(text) <= n else text[:n - 3] + "..."


def _abbreviates(word: str, option: str) -> bool:
    """Whether ``word`` abbreviates ``option`` segment by segment (segments split
    at ``/``): each segment of ``word`` is a prefix of the option's segment, or
    the initials of its hyphen-separated words (``as`` for
    ``ashikhmin-shirley``, ``ngan2005/as`` for ``ngan2005/ashikhmin-shirley``)."""
    ws, os_ = word.lower().split("/"), option.lower().split("/")
    if len(ws) != len(os_) or not word:
        return False
    for w, o in zip(ws, os_):
        parts = [x for x in o.split("-") if x]
        initials = "".join(x[0] for x in parts)
        if not (o.startswith(w) or (len(w) > 1 and initials.startswith(w))):
            return False
    return True


def closest(word: str, options, n: int = 5, cutoff: float = 0.5) -> list:
    """Up to ``n`` of ``options`` a user who typed ``word`` may have meant: those
    ``word`` abbreviates (prefix or initials, :func:`_abbreviates`) first, then
    :func:`difflib.get_close_matches` at ``cutoff``."""
    import difflib

    options = [str(o) for o in options]
    short = [o for o in options if o != word and _abbreviates(str(word), o)]
    close = difflib.get_close_matches(str(word), options, n=n, cutoff=cutoff)
    return list(dict.fromkeys(short + close))[:n]


def html_table(caption: str, header, rows) -> str:
    """An HTML ``<table>`` (every cell escaped) with a caption, for notebooks.

    >>> html_table("m", ["k", "v"], [["n", 20]])
    '<table><caption>m</caption><tr><th>k</th><th>v</th></tr><tr><td>n</td><td>20</td></tr></table>'
    """
    from html import escape

    head = "".join(f"<th>{escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><caption>{escape(str(caption))}</caption><tr>{head}</tr>{body}</table>"


def _temporary(path) -> str:
    """The temporary file beside ``path`` that :func:`replacing` writes first."""
    head, name = os.path.split(os.fspath(path))
    return os.path.join(head, f".{name}.{os.getpid()}.tmp")


@contextmanager
def replacing(*paths):
    """Write files whole or not at all: yields one temporary path beside each of
    ``paths`` (the same extension, for writers that choose a format by it, such as
    matplotlib's ``savefig``); when the block ends without an error every temporary
    file is renamed over its path (``os.replace``, atomic on POSIX and Windows).  An
    error or an interrupt (Ctrl-C) inside the block, a full disk for one of them,
    removes every temporary file and leaves every path as it was (absent, or its
    old content): never a half-written file, and never one file of a set without
    the others (``check --materials --out``'s table and CSV)."""
    tmps = [_temporary(p) + os.path.splitext(os.fspath(p))[1] for p in paths]
    try:
        yield tmps
        for t, p in zip(tmps, paths):
            os.replace(t, os.fspath(p))
    except BaseException as e:
        for t in tmps:
            try:
                os.unlink(t)
            except OSError:
                pass
        if isinstance(e, OSError) and paths and (e.filename is None or e.filename in tmps):
            # the error names the file the user asked for, not our temporary one (a write
            # that fails on a full disk names none)
            at = tmps.index(e.filename) if e.filename in tmps else 0
            raise OSError(e.errno, e.strerror or str(e), os.fspath(paths[at])) from e
        raise


def write_atomic(path, text: str | bytes) -> None:
    """Write ``text`` (or ``bytes``) to ``path`` whole or not at all (:func:`replacing`)."""
    write_all_atomic({path: text})


def write_all_atomic(files: dict) -> None:
    """Write every ``{path: text}`` of ``files`` or none of them (:func:`replacing`):
    all temporary files are written before the first is renamed."""
    with replacing(*files) as tmps:
        for t, text in zip(tmps, files.values()):
            try:
                with (open(t, "wb") if isinstance(text, bytes) else open(t, "w", encoding="utf-8")) as f:
                    f.write(text)
            except OSError as e:    # a full disk names no file: this one (replacing names its path)
                if e.filename is None:
                    raise OSError(e.errno, e.strerror or str(e), t) from e
                raise


__all__ = ["fmt", "html_table", "jsonable", "replacing", "shorten", "write_all_atomic", "write_atomic"]
