"""Wall time of a fitting batch against the number of local worker processes (the batch
engine's, plausible.engine; a Dask LocalCluster before issue 41), and the
per-fit cost that the docs' cluster estimate (docs/fitting.md, "Batches") is
computed from.  Run: ``python benchmarks/batch_scaling.py [--workers 1,2]``."""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time

from plausible.fitting import batch

TARGETS = ["cook-torrance:m=0.2:rs=0.9", "ward:alpha_x=0.15:alpha_y=0.15:rs=0.6:rd=0.2",
           "ashikhmin-shirley:nu=80:nv=80:rs=0.3:rd=0.4", "modified-phong:kd=0.3:ks=0.4:n=30"]
MODELS = ["modified-phong", "ashikhmin-shirley"]
METRICS = ["l2-cos", "log"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--workers", default="1,2")
    ap.add_argument("--starts", type=int, default=2)
    a = ap.parse_args()
    print(f"{len(TARGETS)} targets x {len(MODELS)} models x {len(METRICS)} metrics, starts={a.starts}, "
          f"{os.cpu_count()} cores")
    for w in (int(x) for x in a.workers.split(",")):
        with tempfile.TemporaryDirectory() as d:
            t0 = time.monotonic()
            s = batch.fit_batch(TARGETS, MODELS, METRICS, d, workers=w, starts=a.starts)
            wall = time.monotonic() - t0
            secs = [r["seconds"] for r in batch.load_results(d)]
        print(f"workers={w}: {s.done} fits in {wall:.1f} s wall; per fit median {statistics.median(secs):.2f} s, "
              f"sum {sum(secs):.1f} s; speed-up over the sum {sum(secs) / wall:.2f}")


if __name__ == "__main__":
    main()
