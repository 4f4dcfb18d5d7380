"""Issue 30: parameters as data.  Import time of ``plausible`` beyond NumPy, and
(see the functions below) the work that varies parameters: kernel compilations
counted by Dr.Jit's kernel history, fits, checks of new parameter sets, every
published fit checked in one command.  Each benchmark records the machine's
load average (``os.getloadavg``) next to its numbers: the machine is shared."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest

from conftest import record


def load() -> str:
    """The 1-, 5- and 15-minute load averages, as ``uptime`` prints them."""
    return "%.2f %.2f %.2f" % os.getloadavg()


def import_times(module: str) -> dict:
    """Cumulative import time (s) of every module ``python -X importtime -c 'import
    module'`` reports, in a fresh process."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    r = subprocess.run([sys.executable, "-X", "importtime", "-c", f"import {module}"], env=env,
                       capture_output=True, text=True, check=True)
    out = {}
    for line in r.stderr.splitlines():
        m = re.match(r"import time:\s+\d+ \|\s+(\d+) \|(\s*)(\S+)", line)
        if m:
            out[m.group(3)] = int(m.group(1)) * 1e-6
    return out


def test_import_time(benchmark):
    """``import plausible`` beyond NumPy (target 0.3 s): the cumulative import time
    of ``plausible`` minus that of ``numpy``, median of 5 fresh processes.  Also
    whether ``scipy.stats`` was imported.  Reference, same run: ``import scipy.stats``
    beyond NumPy, which ``plausible`` imported eagerly before issue 30."""
    runs = [import_times("plausible") for _ in range(5)]
    beyond = sorted(r["plausible"] - r.get("numpy", 0.0) for r in runs)
    ref = sorted(r["scipy.stats"] - r.get("numpy", 0.0) for r in (import_times("scipy.stats") for _ in range(5)))
    record(benchmark, "issue-30", "import plausible, beyond NumPy (s)", backend="-", op="import", n=1,
           beyond_numpy_s=beyond[2], numpy_s=sorted(r.get("numpy", 0.0) for r in runs)[2],
           scipy_stats="scipy.stats" in runs[0], reference_scipy_stats_s=ref[2], load=load())
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)
