"""The figure registry: :class:`Figure` entries added by :func:`figure`, and the
:class:`Context` a figure function draws into (the face is :mod:`plausible.figures`).

The figure modules (:data:`MODULES`, in report order) import this one and
register their figures; :func:`names` and :func:`get` import them by name on
first use, as :mod:`plausible.registry` imports the models.
"""

from __future__ import annotations

import csv
import json
import math
import importlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ..progress import silent, start
from ..text import jsonable


@dataclass(frozen=True)
class Figure:
    """One registered figure: ``name`` (file-safe), ``title``, ``source`` (paper and
    figure number), ``caption`` (quoted from the paper), ``params`` (keyword
    arguments of ``fn``, shown in the report) and the function."""

    name: str
    title: str
    source: str
    caption: str
    fn: Callable
    params: dict = field(default_factory=dict)
    renders: bool = False
    module: str = ""


FIGURES: dict[str, Figure] = {}


def figure(name: str, title: str, source: str, caption: str, renders: bool = False, **params):
    """Decorator: register ``fn(ctx, **params)`` as figure ``name``."""

    def deco(fn):
        if name in FIGURES and FIGURES[name].fn.__qualname__ != fn.__qualname__:
            raise ValueError(f"figure {name!r} registered twice")
        FIGURES[name] = Figure(name, title, source, caption, fn, dict(params), renders, fn.__module__)
        return fn

    return deco


#: The figure modules in report order (``materials``: issue 16, the published MERL fits).
MODULES = ("paper_as", "paper_neumann", "paper_notes", "checks", "lobes", "materials", "compensation", "conversion")


def _load():
    for m in MODULES:
        importlib.import_module(f"{__package__}.{m}")


def names() -> list[str]:
    _load()
    return list(FIGURES)


def get(name: str) -> Figure:
    _load()
    try:
        return FIGURES[name]
    except KeyError:
        raise ValueError(f"unknown figure {name!r}; figures: {', '.join(FIGURES)}") from None


#: Image size and samples per pixel of the default run, and of the quick (CI) run.
DEFAULT_RESOLUTION, DEFAULT_SPP = 320, 128
QUICK_RESOLUTION, QUICK_SPP = 48, 8
#: Adaptive sampling of a render's isolated hot pixels (:meth:`Context.image`): the samples of
#: a refined window, times the image's, and the rounds of refinement at most.
REFINE, REFINE_ROUNDS = 8, 2
#: Error bound of the albedo curves a figure plots and checks against bounds of 1e-4 or more (energy
#: "<= 1 + 1e-4", "pumping never lowers it: >= -1e-4"): ten times below them, and below the 4 decimals
#: the report prints.  The integrator's default (1e-6) is kept where a figure reads finer differences.
CURVE_TOL = 1e-5
#: Why the isolated-hot-pixel check is not decided in quick mode: at 8 spp a pixel's estimate is the mean of 8
#: samples, and a sharp lobe's or a caustic's rare large sample is the noise of that estimator (as-gold and
#: materials-atlas had 1-3 such pixels in quick mode); the check is one of the converged image (128 spp).
HOT_QUICK = "at 8 samples a pixel that caught one rare large sample (a sharp lobe's, a caustic's) is the " \
            "estimator's noise, not a firefly of the converged image; the count is a check from the default 128 spp"


class Context:
    """What a figure function writes through.  ``res(scale)`` and ``spp(scale)``
    give the image size / sample count for this run (``--resolution``, ``--spp``,
    quick mode); the figure scales them for its own layout.  ``progress``: a
    :mod:`plausible.progress` factory, announced by :meth:`steps`."""

    def __init__(self, out: Path, *, resolution=None, spp=None, quick=False, progress=None):
        self.out = Path(out)
        self.out.mkdir(parents=True, exist_ok=True)
        self.quick = quick
        self.base_res = resolution or (QUICK_RESOLUTION if quick else DEFAULT_RESOLUTION)
        self.base_spp = spp or (QUICK_SPP if quick else DEFAULT_SPP)
        self._progress = progress
        self._tick = silent(0)      # until steps() announces a total
        self._total = self._done = 0
        self.items: list[dict] = []      # images, plots, data files, in order
        self.measurements: list[dict] = []
        self.notes: list[str] = []

    # -- sizes ------------------------------------------------------------------
    def res(self, scale: float = 1.0, minimum: int = 8) -> int:
        return max(minimum, int(round(self.base_res * scale / 2)) * 2)

    def spp(self, scale: float = 1.0) -> int:
        return max(1, int(round(self.base_spp * scale)))

    # -- progress ---------------------------------------------------------------
    def steps(self, total: int):
        """Declare how many ``tick()`` calls this figure will make."""
        self._tick = start(self._progress, total)
        self._total, self._done = total, 0

    def tick(self, n: int = 1):
        """One step (or ``n``) of those declared by :meth:`steps` done."""
        self._done += n
        self._tick(n)

    def finish(self):
        """Count the steps the figure declared but did not tick (the runner calls it)."""
        if self._done < self._total:
            self.tick(self._total - self._done)

    # -- outputs ----------------------------------------------------------------
    def image(self, name: str, img, exposure: float = 1.0, caption: str = "", refine=None) -> np.ndarray:
        """A render: ``name.exr`` (linear) and ``name.png`` (sRGB), and a check that it
        has no isolated hot pixel (:func:`plausible.figures.scenes.hot_pixels`: luminance
        above 4 x its 3x3 median + 0.5; a reference image has none).

        ``refine(y0, x0, h, w)``, if given, renders the window ``[y0, y0 + h) x [x0, x0 +
        w)`` of the same scene with another seed and :data:`REFINE` times the samples:
        samples where they are needed.  Each isolated hot pixel's 7 x 7 neighbourhood is
        rendered so and averaged with what the pixels had, weighted by sample count (the
        mean of every sample taken there), for at most :data:`REFINE_ROUNDS` rounds; the
        image written and checked is the refined one, and the check counts by the
        definition alone.  (A noisy estimate just over the threshold settles below it; a
        feature of the converged image stays hot and fails the check.)  Returns the image
        written."""
        from .scenes import HOT_FACTOR, HOT_OFFSET, count_hot_pixels, hot_pixels, write_image

        img = np.array(img, dtype=np.float64)
        weight = np.ones(img.shape[:2])             # samples per pixel, in units of the first pass's
        refined = set()
        for _ in range(REFINE_ROUNDS if refine is not None else 0):
            iso = hot_pixels(img)
            if not iso.any():
                break
            h, w = iso.shape
            for y, x in zip(*np.nonzero(iso)):
                y0, x0 = max(0, min(y - 3, h - 7)), max(0, min(x - 3, w - 7))
                win = np.s_[y0:y0 + min(7, h), x0:x0 + min(7, w)]
                crop = np.asarray(refine(int(y0), int(x0), min(7, h), min(7, w)), dtype=np.float64)
                wk = weight[win][..., None]
                img[win] = (img[win] * wk + crop * REFINE) / (wk + REFINE)
                weight[win] += REFINE
                refined.add((int(y), int(x)))
        write_image(self.out / name, img, exposure)
        self.items.append(dict(kind="image", png=f"{name}.png", exr=f"{name}.exr", caption=caption))
        hot, n = count_hot_pixels(img, isolated=False), count_hot_pixels(img)
        note = f"{hot} pixels pass the luminance test alone"
        if hot > n:
            note += f", {hot - n} of them with 2 or more neighbours as bright (the corners of a bright area, " \
                    "not isolated)"
        if refined:
            note += f"; {len(refined)} isolated hot pixel(s) of the first pass had their 7 x 7 neighbourhood " \
                    f"rendered again with {REFINE}x the samples (another seed) and averaged with it by sample " \
                    "count (samples where they are needed); counted after that"
        self.measure(f"{name}: isolated hot pixels (luminance > {HOT_FACTOR:g} x its 3x3 median + {HOT_OFFSET:g}, "
                     "at most one neighbour as bright)", n, at_most=0, note=note, quick=HOT_QUICK)
        return img

    def plot(self, name: str, fig, caption: str = ""):
        """A matplotlib figure -> ``name.png``."""
        fig.savefig(self.out / f"{name}.png", dpi=110)
        import matplotlib.pyplot as plt

        plt.close(fig)
        self.items.append(dict(kind="plot", png=f"{name}.png", caption=caption))

    def table(self, name: str, columns: dict, caption: str = ""):
        """Plotted data as ``name.csv``: ``columns`` maps header -> 1-D array."""
        keys = list(columns)
        arr = np.column_stack([np.asarray(columns[k], dtype=np.float64).ravel() for k in keys])
        # the csv module quotes a header holding a comma ("eq. 21 as printed, (N.V)(N.L)"): a plain
        # ",".join gave such a file more header fields than data fields
        with open(self.out / f"{name}.csv", "w", newline="") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(keys)
            w.writerows([f"{x:.8g}" for x in row] for row in arr)
        self.items.append(dict(kind="data", file=f"{name}.csv", caption=caption))

    def json(self, name: str, obj, caption: str = ""):
        (self.out / f"{name}.json").write_text(json.dumps(jsonable(obj), indent=1, default=str))
        self.items.append(dict(kind="data", file=f"{name}.json", caption=caption))

    def file(self, name: str, caption: str = ""):
        """Register a file the figure wrote itself into ``ctx.out``."""
        self.items.append(dict(kind="data", file=name, caption=caption))

    def measure(self, quantity: str, measured, expected=None, tol=None, note: str = "", at_most=None,
                at_least=None, quick: str = ""):
        """A number measured on the figure.  It is a check when given

        * ``expected`` and ``tol``: ``ok = |measured - expected| <= tol``;
        * ``at_most`` and/or ``at_least``: ``ok = at_least <= measured <= at_most``;
        * a boolean ``measured`` with a boolean ``expected``: ``ok = measured == expected``
          (shown as yes / no).

        Every value stored is a number (or a boolean); the report writes the bounds
        as ``<= x`` / ``>= x`` in its "expected" column.

        ``quick``: why the check cannot be decided at the quick mode's quality (the CI
        mode's 48 px, 8 spp).  In quick mode such a check is then not measured: the
        number is kept with its bound, without a verdict (``unmeasured`` holds the
        reason, and the report says "not measured at this quality")."""
        m = self._measure(quantity, measured, expected, tol, note, at_most, at_least)
        if quick and self.quick and "ok" in m:
            del m["ok"]
            m["unmeasured"] = f"not measured at this quality (quick mode: {self.base_res} px, {self.base_spp} " \
                              f"spp): {quick}"
        return m

    def _measure(self, quantity, measured, expected, tol, note, at_most, at_least):
        if isinstance(measured, (bool, np.bool_)) or isinstance(expected, (bool, np.bool_)):
            if not isinstance(expected, (bool, np.bool_, type(None))):
                raise ValueError(f"measure({quantity!r}): a boolean is compared with a boolean, got {expected!r}")
            m = dict(quantity=quantity, measured=bool(measured), expected=None if expected is None
                     else bool(expected), tol=None, note=note)
            if expected is not None:
                m["ok"] = bool(measured) == bool(expected)
            self.measurements.append(m)
            return m
        for k, v in (("expected", expected), ("tol", tol), ("at_most", at_most), ("at_least", at_least)):
            if v is not None and not isinstance(v, (int, float, np.integer, np.floating)):
                raise ValueError(f"measure({quantity!r}): '{k}' must be a number, got {v!r}")
        m = dict(quantity=quantity, measured=_num(measured), expected=_num(expected), tol=_num(tol), note=note)
        if expected is not None and tol is not None:
            m["ok"] = bool(abs(float(measured) - float(expected)) <= float(tol))
        if at_most is not None or at_least is not None:
            m.update(at_most=_num(at_most), at_least=_num(at_least))
            x = float(measured)
            m["ok"] = bool((at_most is None or x <= float(at_most)) and (at_least is None or x >= float(at_least)))
        self.measurements.append(m)
        return m

    def note(self, text: str):
        self.notes.append(text)


def _num(x):
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else str(x)


__all__ = ["CURVE_TOL", "Context", "FIGURES", "Figure", "MODULES", "figure", "get", "names"]
