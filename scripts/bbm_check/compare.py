"""plausible's published fits against bbm's own evaluation (compiled by run.sh).

    python compare.py BBM_FITS_DIR BUILD_DIR

For every fit set whose file is in BBM_FITS_DIR, every material: plausible.material(name,
fit).eval at 48 pairs (24 random, 24 within about 1 degree of the mirror direction, cosines
from 0.02), against ``evalfit`` (bbm as it is) and, for ngan2005/he, ``evalfit-full`` (its
series summed in full).  Prints per set the largest relative difference
max |plausible - bbm| / (|bbm| + 1e-12 max |bbm|) over pairs and channels, the median over
materials, how many materials differ by more than 1e-5, and for how many bbm's value is not
finite at some pair (those are left out of the statistics; plausible's must be finite)."""

import subprocess
import sys
from pathlib import Path

import numpy as np

import plausible
from plausible.catalogue import fit_sets


def pairs(seed=7, n=24):
    rng = np.random.default_rng(seed)
    z = rng.uniform(0.02, 1, (2, n))
    p = rng.uniform(0, 2 * np.pi, (2, n))
    s = np.sqrt(1 - z * z)
    a, b = np.stack([s * np.cos(p), s * np.sin(p), z], -1)
    m = np.stack([-a[:, 0], -a[:, 1], a[:, 2]], -1) + rng.normal(scale=0.02, size=(n, 3))
    m[:, 2] = np.abs(m[:, 2])
    m /= np.linalg.norm(m, axis=-1, keepdims=True)
    return np.concatenate([a, a]), np.concatenate([b, m])


def bbm_eval(program, fit_file, wi, wo):
    text = "\n".join(" ".join(f"{x:.17g}" for x in row) for row in np.hstack([wi, wo]))
    out = subprocess.run([str(program), str(fit_file)], input=text, capture_output=True, text=True, check=True).stdout
    rows = {}
    for line in out.splitlines():
        name, i, *rgb = line.split()
        rows.setdefault(name, {})[int(i)] = [float(v) for v in rgb]
    return {k: np.array([v[i] for i in range(len(wi))]) for k, v in rows.items()}


def deviation(got, ref):
    if not np.any(ref) and not np.any(got):
        return 0.0
    return float(np.max(np.abs(got - ref) / (np.abs(ref) + 1e-12 * np.max(np.abs(ref)))))


def main(fits_dir, build):
    fits_dir, build = Path(fits_dir), Path(build)
    wi, wo = pairs()
    print("| fit set | fits | bbm | largest relative difference (material) | median | over 1e-5 | bbm not finite |")
    print("|---|---|---|---|---|---|---|")
    for fs in fit_sets.fits():
        if not (fits_dir / fs.file).exists():
            continue
        programs = [("as written", build / "evalfit")]
        if fs.key == "ngan2005/he":
            programs.append(("series in full", build / "evalfit-full"))
        for label, prog in programs:
            ref = bbm_eval(prog, fits_dir / fs.file, wi, wo)
            assert len(ref) == len(plausible.materials(fs.key)), (fs.key, len(ref))
            bad = [n for n, r in ref.items() if not np.all(np.isfinite(r))]
            for n in bad:   # plausible is finite where bbm is not
                assert np.all(np.isfinite(plausible.material(n, fit=fs.key).eval(wi, wo))), n
            devs = sorted((deviation(plausible.material(n, fit=fs.key).eval(wi, wo), r), n)
                          for n, r in ref.items() if n not in bad)
            d = [x for x, _ in devs]
            print(f"| {fs.key} | {len(ref)} | {label} | {devs[-1][0]:.1e} ({devs[-1][1]}) | {np.median(d):.1e} | "
                  f"{sum(x > 1e-5 for x in d)} | {len(bad)} |")


if __name__ == "__main__":
    main(*sys.argv[1:3])
