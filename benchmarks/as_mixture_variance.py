"""Variance of the one-sample albedo estimator of Ashikhmin-Shirley for two
choices of the lobe-selection probability ``ps``.

The estimator is the sample weight ``f cos(theta_o) / pdf`` (its mean is the
directional albedo); both strategies draw the same number of samples at the
same cost, so the variance ratio is the efficiency ratio.

* ``ps = 0.5``: fixed even mixture;
* ``ps = Fs / (Fs + Ad)`` (the model's choice, per incident direction):
  ``Fs = F(cos theta_i)`` (Schlick with ``rs``), ``Ad = rd (1 - rs) (1 - (1 -
  cos theta_i / 2)^5)``, the diffuse term's exact albedo.

Run: ``python benchmarks/as_mixture_variance.py [--samples N] [--seed S]``;
prints a Markdown table (recorded in docs/models/ashikhmin-shirley.md).
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from plausible.models.ashikhmin_shirley import AshikhminShirley, specular_probability
from plausible.arrays.ops import NP


class HalfMixture(AshikhminShirley):
    """The same model sampled with the fixed mixture weight ``ps = 0.5``."""

    def spec_probability(self, ops, wi, q):
        return 0.5


def weights(model, theta_deg, n, seed):
    t = math.radians(theta_deg)
    wi = np.array([math.sin(t), 0.0, math.cos(t)])
    u = np.random.default_rng(seed).random((n, 3))
    return model.sample(wi, u).weight


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=200_000)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)

    rows = []
    for rs in (0.05, 0.5, 1.0):
        for rd in (0.0, 0.5, 1.0):
            for n in (10.0, 1000.0):
                for theta in (0.0, 45.0, 80.0):
                    kw = dict(nu=n, nv=n, rs=rs, rd=rd)
                    ours, half = AshikhminShirley(**kw), HalfMixture(**kw)
                    c = math.cos(math.radians(theta))
                    ps = float(specular_probability(NP, np.float64(c), rs, rd))
                    wo = weights(ours, theta, args.samples, args.seed)
                    wh = weights(half, theta, args.samples, args.seed)
                    rows.append((rs, rd, n, theta, ps, wo.mean(), wh.var(ddof=1), wo.var(ddof=1)))

    print(f"{args.samples} samples per cell, seed {args.seed}.\n")
    print("| rs | rd | nu = nv | theta_i | ps (ours) | albedo | Var, ps = 0.5 | Var, ours | ratio |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for rs, rd, n, th, ps, a, vh, vo in rows:
        ratio = vh / vo if vo > 0 else (math.inf if vh > 0 else 1.0)
        print(f"| {rs:g} | {rd:g} | {n:g} | {th:g} | {ps:.3f} | {a:.4f} | {vh:.3e} | {vo:.3e} | "
              f"{ratio:.2f} |")
    vh = np.array([r[6] for r in rows])
    vo = np.array([r[7] for r in rows])
    both = vo > 0
    print(f"\nours lower in {np.sum(vo < vh)} of {len(rows)} cells, higher in {np.sum(vo > vh)}; "
          f"geometric mean of Var(0.5)/Var(ours) over cells with Var(ours) > 0: "
          f"{math.exp(np.mean(np.log(vh[both] / vo[both]))):.2f}; "
          f"worst ratio {np.min(vh[both] / vo[both]):.2f}; "
          f"sum of variances {vh.sum():.4g} (0.5) vs {vo.sum():.4g} (ours)")


if __name__ == "__main__":
    main()
