"""The cross-model table of docs/fitting.md: Ashikhmin-Shirley, Modified Phong,
Ward and the compact metallic model fitted to a Cook-Torrance target under the
least-squares and the perceptual metrics.

Run ``python -m plausible.fitting.crossmodel`` (a few minutes on one core).
"""

from __future__ import annotations

import sys
import time

from .. import registry
from .fit import fit
from .targets import as_target

TARGET = "cook-torrance:m=0.2:rs=0.9"
MODELS = ("ashikhmin-shirley", "modified-phong", "ward", "neumann-metal")
METRICS = ("l2-cos", "log", "perceptual")


def run(target=TARGET, models=MODELS, metrics=METRICS, starts=2, seed=0, progress=None):
    """Fit every model under every metric: a list of :class:`~plausible.fitting.fit.FitResult`."""
    tgt = as_target(registry.make_from_spec(target))
    out = []
    for name in models:
        for metric in metrics:
            out.append(fit(name, tgt, metric, starts=starts, seed=seed, progress=progress))
    return out


def markdown(results) -> str:
    """The results as a Markdown table."""
    lines = ["| model | metric | parameters | l2-cos | log | E_f (max, f cos) | E_a (max, albedo) | highlight | time (s) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        free = {k: v for k, v in r.params.items() if not isinstance(v, str)}
        ps = ", ".join(f"{k}={float(v):.4g}" for k, v in free.items() if v is not None)
        e = r.errors
        lines.append(f"| {r.model.name} | {r.metric} | {ps} | {e['l2-cos']:.4f} | {e['log']:.4f} | "
                     f"{e['fcos_max']:.4f} | {e['albedo_max']:.4f} | {e['highlight']:.4f} | {r.seconds:.0f} |")
    return "\n".join(lines)


def main(argv=None):  # pragma: no cover - a script
    t = time.monotonic()
    res = run()
    print(f"target: {TARGET}\n")
    print(markdown(res))
    print(f"\ntotal {time.monotonic() - t:.0f} s")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
