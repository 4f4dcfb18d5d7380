"""Markdown tables from pytest-benchmark JSON: ``python benchmarks/report.py out/bench.json``.

Ratios first (time / Mitsuba ``roughconductor``'s time for the same operation,
lower is faster), then absolute numbers with the machine they were taken on."""

from __future__ import annotations

import json
import platform
import sys


def main(path):
    d = json.load(open(path))
    bs = d["benchmarks"]
    cpu = d["machine_info"].get("cpu", {})
    med = {}
    for b in bs:
        e = b["extra_info"]
        med[(e.get("group"), e.get("case"), e.get("backend"))] = (b["stats"]["median"], e)
    print(f"Machine: {cpu.get('brand_raw', '?')} ({cpu.get('count', '?')} cores), "
          f"Python {d['machine_info']['python_version']}, {d['datetime']}\n")
    ops = ("eval", "pdf", "sample")
    bes = ("numpy", "api-drjit", "drjit", "mitsuba")
    print("| model | " + " | ".join(f"{op} {be}" for op in ops for be in bes) + " |")
    print("|---|" + "---:|" * (len(ops) * len(bes)))
    cases = sorted({k[1] for k in med if k[0] and k[0].startswith("throughput")})
    for c in cases:
        row = []
        for op in ops:
            ref = med.get((f"throughput-{op}", "roughconductor", "reference"))
            for be in bes:
                t = med.get((f"throughput-{op}", c, be))
                row.append(f"{t[0] / ref[0]:.2f}" if t and ref else "")
        print(f"| {c} | " + " | ".join(row) + " |")
    print("\nAbsolute (M directions/s, median; first call s; traced peak MB):\n")
    print("| group | case | backend | median s | M dir/s | first call s | peak MB | extra |")
    print("|---|---|---|---:|---:|---:|---:|---|")
    for (g, c, be), (t, e) in sorted(med.items(), key=lambda kv: (kv[0][0] or "", kv[0][1] or "", kv[0][2] or "")):
        n = e.get("n", 1)
        extra = {k: v for k, v in e.items() if k not in ("group", "case", "backend", "op", "n", "peak_bytes",
                                                           "first_call_s")}
        print(f"| {g} | {c} | {be} | {t:.4g} | {n / t / 1e6:.3g} | "
              f"{e['first_call_s']:.3g} | " if "first_call_s" in e else f"| {g} | {c} | {be} | {t:.4g} | "
              f"{n / t / 1e6:.3g} | | ", end="")
        print(f"{e['peak_bytes'] / 1e6:.1f} | " if "peak_bytes" in e else " | ", end="")
        print(", ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}" for k, v in extra.items()) + " |")
    print(f"\n(platform: {platform.platform()})")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "out/bench.json")
