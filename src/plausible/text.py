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
  files of ``convert`` and ``export``).
"""

from __future__ import annotations

import math
import os

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


def html_table(caption: str, header, rows) -> str:
    """An HTML ``<table>`` (every cell escaped) with a caption, for notebooks.

    >>> html_table("m", ["k", "v"], [["n", 20]])
    '<table><caption>m</caption><tr><th>k</th><th>v</th></tr><tr><td>n</td><td>20</td></tr></table>'
    """
    from html import escape

    head = "".join(f"<th>{escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><caption>{escape(str(caption))}</caption><tr>{head}</tr>{body}</table>"


def write_atomic(path, text: str | bytes) -> None:
    """Write ``text`` (or ``bytes``) to ``path`` whole or not at all: into a temporary file beside it,
    then renamed over it (``os.replace``, atomic on POSIX and Windows).  An error or an
    interrupt (Ctrl-C) while writing removes the temporary file and leaves ``path`` as it
    was (absent, or its old content): never a half-written file."""
    path = os.fspath(path)
    head, name = os.path.split(path)
    tmp = os.path.join(head, f".{name}.{os.getpid()}.tmp")
    try:
        with (open(tmp, "wb") if isinstance(text, bytes) else open(tmp, "w", encoding="utf-8")) as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


__all__ = ["fmt", "html_table", "jsonable", "shorten", "write_atomic"]
