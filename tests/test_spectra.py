"""Metal optical constants and the spectrum -> XYZ -> linear sRGB pipeline."""

from importlib import resources

import numpy as np
import pytest

from plausible import spectra


def test_cmf_table_matches_published_cie_values():
    # CIE 1931 2-degree observer and D65 (CIE 15:2004 tables), quoted values.
    wl, xb, yb, zb, d65 = spectra.cie_table()
    assert wl[0] == 360 and wl[-1] == 830 and np.all(np.diff(wl) == 5)
    ref = {450: (0.3362, 0.038, 1.7721), 555: (0.5121, 1.0, 0.00575), 600: (1.0622, 0.631, 0.0008)}
    for w, (x, y, z) in ref.items():
        i = int(np.where(wl == w)[0][0])
        assert (xb[i], yb[i], zb[i]) == pytest.approx((x, y, z), abs=1e-4)
    d65_ref = {400: 82.7549, 500: 109.354, 560: 100.0, 600: 90.0062, 700: 71.6091}
    for w, v in d65_ref.items():
        assert d65[wl == w][0] == pytest.approx(v, abs=1e-3)


def test_cmf_integrals_are_equal_and_equal_energy_white_is_neutral():
    wl, xb, yb, zb, _ = spectra.cie_table()
    ix, iy, iz = xb.sum(), yb.sum(), zb.sum()
    # The CIE functions are normalised to equal areas; on the 5 nm grid they agree to 4e-4.
    assert ix / iy == pytest.approx(1.0, abs=5e-4)
    assert iz / iy == pytest.approx(1.0, abs=5e-4)
    xyz = spectra.spectrum_to_xyz(wl, np.ones_like(wl), illuminant="E")
    assert xyz == pytest.approx([1.0, 1.0, 1.0], abs=5e-4)


def test_d65_white_maps_to_rgb_one():
    wl = spectra.cie_table()[0]
    xyz = spectra.spectrum_to_xyz(wl, np.ones_like(wl), illuminant="D65")
    assert xyz[1] == pytest.approx(1.0, abs=1e-12)
    assert spectra.xyz_to_linear_srgb(xyz) == pytest.approx([1.0, 1.0, 1.0], abs=1e-3)


def test_srgb_matrix_matches_iec_61966_2_1():
    published = np.array([[3.2406, -1.5372, -0.4986],
                          [-0.9689, 1.8758, 0.0415],
                          [0.0557, -0.2040, 1.0570]])
    derived = np.linalg.inv(spectra._rgb_to_xyz_matrix())
    # The standard prints 4 decimals of a matrix derived from slightly different
    # rounding; the difference is below 4e-4 in every entry.
    assert np.max(np.abs(derived - published)) < 5e-4
    # Broken input: swapping two primaries is detected.
    assert np.max(np.abs(derived[[1, 0, 2]] - published)) > 0.5


def test_metal_colours():
    au, ag, cu, al = (spectra.metal_rgb(m) for m in ("gold", "silver", "copper", "aluminium"))
    assert au[0] > au[1] > au[2] and au[2] < 0.5        # gold is yellow
    assert cu[0] > cu[1] > cu[2] and cu[0] - cu[2] > 0.3  # copper is reddish
    assert ag.min() > 0.9 and ag.max() / ag.min() < 1.07  # silver: bright and nearly neutral
    assert al.min() > 0.85 and al.max() / al.min() < 1.03  # aluminium: neutral
    # Symbols and names are the same metals.
    assert np.array_equal(spectra.metal_rgb("Au"), au)


def test_known_reflectances_of_metals():
    # Textbook facts (e.g. Palik's handbook; Johnson & Christy 1972): gold absorbs blue,
    # reflects red; silver reflects above 90 % across the visible from 450 nm on.
    assert spectra.metal_reflectance("Au", 450.0) < 0.45
    assert spectra.metal_reflectance("Au", 700.0) > 0.95
    assert np.all(spectra.metal_reflectance("Ag", np.arange(450.0, 781.0, 10.0)) > 0.9)
    # Fresnel: reflectance rises to 1 at grazing incidence.
    assert spectra.metal_reflectance("Cu", 500.0, 1e-8) == pytest.approx(1.0, abs=1e-6)


def test_interpolation_reproduces_the_file_nodes():
    text = resources.files("plausible").joinpath("data", "Cu_nk.csv").read_text().splitlines()
    rows = np.array([l.split(",") for l in text if l and not l.startswith("#")][1:], float)
    n, k = spectra.metal_nk("copper", rows[:, 0])
    assert np.array_equal(n, rows[:, 1]) and np.array_equal(k, rows[:, 2])
    mid = 0.5 * (rows[10, 0] + rows[11, 0])
    n_mid, _ = spectra.metal_nk("Cu", mid)
    assert n_mid == pytest.approx(0.5 * (rows[10, 1] + rows[11, 1]), rel=1e-12)


def test_bad_inputs():
    with pytest.raises(ValueError, match="unknown metal"):
        spectra.metal_nk("unobtainium", 500.0)
    with pytest.raises(ValueError, match="wavelengths"):
        spectra.metal_nk("Au", 1000.0)
    with pytest.raises(ValueError, match="illuminant"):
        spectra.metal_rgb("Au", illuminant="A")
