"""plausible's he-torrance variants against bbm's He ('paper'), HeWestin ('westin') and
HeHolzschuch ('errata', 10 terms), evaluated by bbm itself (run.sh's programs).

    python variants.py BUILD_DIR

Four parameter sets at compare.py's 48 pairs, RGB wavelengths 0.645/0.526/0.444 um (bbm's),
complex index eta + i k; prints the largest relative difference per model and set."""

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

import plausible
from compare import pairs

VARIANT = {"He": "paper", "HeWestin": "westin", "HeHolzschuch": "errata"}
SETS = [(0.03, 1.0, 1.5, 0.0), (0.03, 0.5, 0.2, 3.0), (0.18, 3.0, 1.5, 0.0), (0.1, 1.7, 0.2, 3.0)]


def main(build):
    wi, wo = pairs()
    text = "\n".join(" ".join(f"{x:.17g}" for x in r) for r in np.hstack([wi, wo]))
    lines = [f"{name}-{i} = {name}(roughness = {s}, autocorrelation = {t}, eta = ([{n},{n},{n}],[{k},{k},{k}]))"
             for i, (s, t, n, k) in enumerate(SETS) for name in VARIANT]
    with tempfile.NamedTemporaryFile("w", suffix=".fit", delete=False) as fh:
        fh.write("\n".join(lines) + "\n")
    for prog in ("evalfit", "evalfit-full"):
        out = subprocess.run([str(Path(build) / prog), fh.name], input=text, capture_output=True, text=True,
                             check=True).stdout
        rows = {}
        for line in out.splitlines():
            name, j, *rgb = line.split()
            rows.setdefault(name, {})[int(j)] = [float(v) for v in rgb]
        print(f"| bbm {prog} | variant | sigma0, tau (um) | eta + i k | largest relative difference |")
        print("|---|---|---|---|---|")
        for name, d in sorted(rows.items()):
            base, i = name.rsplit("-", 1)
            s, t, n, k = SETS[int(i)]
            ref = np.array([d[j] for j in range(len(wi))])
            m = plausible.make("he-torrance", sigma0=s, tau=t, wavelength=[0.645, 0.526, 0.444], fresnel="conductor",
                               eta=n, k=k, variant=VARIANT[base], rough="series" if base == "HeHolzschuch" else "beckmann")
            dev = np.max(np.abs(m.eval(wi, wo) - ref) / (np.abs(ref) + 1e-12 * np.max(np.abs(ref))))
            print(f"| {base} | {VARIANT[base]} | {s}, {t} | {n} + {k}i | {dev:.1e} |")


if __name__ == "__main__":
    main(sys.argv[1])
