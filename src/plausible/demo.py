"""The demo job (``make demo``): verify every registered model and plot the
albedo curves the papers discuss.  Writes into ``--out`` (default ``out/``):

* ``check.json`` and ``check.md`` -- :func:`plausible.check` of every model on its
  defaults and declared extreme parameters (quick mode);
* ``albedo-*.png`` / ``albedo-*.csv`` -- directional albedo curves:
  Neumann et al. fig. 1 (Phong n = 150 and the models compared with it),
  fig. 3/4 (reciprocal Phong and Blinn, n = 20), Ashikhmin-Shirley's furnace
  (rs = 1, rd = 0, nu = nv in {10, 100, 1000, 10000}) and the Modified Phong of the notes.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.progress import track

from . import registry
from .analysis import albedo_curve, check
from .analysis.suite import model_variants
from .plotting import default_thetas, plot_albedo_curves

CURVES = {
    "neumann-fig1": ("Albedo at grazing: Phong n = 150 vs Cook-Torrance and Ward (m = 0.1)",
                     ["reciprocal-phong:ks=1:n=150", "cook-torrance:m=0.1:rs=1", "ward:alpha_x=0.1:alpha_y=0.1:rs=1:rd=0"]),
    "neumann-fig3-4": ("Reciprocal Phong and Blinn, n = 20",
                       ["reciprocal-phong:ks=1:n=20", "reciprocal-blinn:ks=1:n=20"]),
    "neumann-fig7": ("Compact metallic model for several n",
                     ["neumann-metal:n=5", "neumann-metal:n=20", "neumann-metal:n=100", "neumann-metal:n=1000"]),
    "as-furnace": ("Ashikhmin-Shirley specular lobe in a furnace (rs = 1, rd = 0)",
                   [f"ashikhmin-shirley:nu={n}:nv={n}:rs=1:rd=0" for n in (10, 100, 1000, 10000)]),
    "modified-phong": ("Modified Phong of the notes (n = 30, kd = 0.5, ks = 0.2)",
                       ["modified-phong:kd=0.5:ks=0.2:n=30"]),
}


def run(out: Path, console: Console | None = None) -> dict:
    console = console or Console()
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.time()
    models = [m for name in registry.names() for m in model_variants(name)]
    reports = []
    for m in track(models, description="checking models", console=console):
        reports.append(check(m, quick=True))
    (out / "check.json").write_text(json.dumps([r.to_dict() for r in reports], indent=1))
    lines = ["| model | parameters | claims plausible | reciprocity | energy (max albedo) | sampling | chi2 (p) |",
             "|---|---|---|---|---|---|---|"]
    for m, r in zip(models, reports):
        claims = m.info.reciprocal and m.info.energy_conserving
        cells = [f"{'PASS' if x.passed else 'FAIL'} {x.figure:.4g}" for x in r.results]
        lines.append(f"| {m.name} | {r.params} | {'yes' if claims else 'no'} | " + " | ".join(cells) + " |")
    (out / "check.md").write_text("\n".join(lines) + "\n")
    th = default_thetas(46)
    written = []
    for key, (title, specs) in track(list(CURVES.items()), description="albedo curves", console=console):
        curves = []
        for spec in specs:
            try:
                m = registry.make_from_spec(spec)
            except ValueError as e:   # a model not in this build
                console.print(f"[yellow]skip {spec}: {e}")
                continue
            curves.append((spec, th, albedo_curve(m, th)))
        if not curves:
            continue
        plot_albedo_curves(curves, out / f"albedo-{key}.png", title)
        data = np.column_stack([np.degrees(th)] + [np.mean(np.atleast_2d(np.asarray(c[2].value).T), axis=0)
                                                   for c in curves])
        np.savetxt(out / f"albedo-{key}.csv", data, delimiter=",", header="theta_deg," + ",".join(c[0] for c in curves))
        written.append(key)
    ok = sum(r.as_claimed(m.info) for m, r in zip(models, reports))
    summary = dict(models=len(models), as_claimed=ok, seconds=round(time.time() - t0, 1), curves=written)
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    console.print((out / "check.md").read_text())
    console.print(f"wrote {out}/check.json, check.md and {len(written)} albedo plots in {summary['seconds']} s")
    return summary


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="out", help="output directory")
    a = ap.parse_args(argv)
    run(Path(a.out))


if __name__ == "__main__":
    main()
