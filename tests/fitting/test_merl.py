"""MERL reader/writer: file layout and scales against the published format, the
lookup against an independent transcription of the reference reader
(BRDFRead.cpp), round trips, missing data, and the model contract."""

import math

import numpy as np
import pytest

import plausible
from plausible.analysis import albedo, direction
from plausible.fitting import MerlBRDF, read_merl, tabulate, write_merl
from plausible.models.merl import NCELLS, RES, cell_centres

from reference import check_sampling


# -- an independent transcription of the reference reader's lookup -----------------

def _rotate(v, axis, ang):
    # rotate_vector of BRDFRead.cpp (Rodrigues)
    v, axis = np.asarray(v, float), np.asarray(axis, float)
    return (v * math.cos(ang) + axis * np.dot(axis, v) * (1 - math.cos(ang))
            + np.cross(axis, v) * math.sin(ang))


def _ref_index(wi, wo):
    ti, pi_ = math.acos(wi[2]), math.atan2(wi[1], wi[0])
    to, po = math.acos(wo[2]), math.atan2(wo[1], wo[0])
    vin = np.array([math.sin(ti) * math.cos(pi_), math.sin(ti) * math.sin(pi_), math.cos(ti)])
    vout = np.array([math.sin(to) * math.cos(po), math.sin(to) * math.sin(po), math.cos(to)])
    half = (vin + vout) / np.linalg.norm(vin + vout)
    th, ph = math.acos(half[2]), math.atan2(half[1], half[0])
    tmp = _rotate(vin, [0, 0, 1], -ph)
    diff = _rotate(tmp, [0, 1, 0], -th)
    td, pd = math.acos(diff[2]), math.atan2(diff[1], diff[0])
    ih = 0 if th <= 0 else min(max(int(math.sqrt(th / (math.pi / 2) * 90 * 90)), 0), 89)
    id_ = min(max(int(td / (math.pi * 0.5) * 90), 0), 89)
    if pd < 0:
        pd += math.pi
    ip = min(max(int(pd / math.pi * 360 / 2), 0), 179)
    return ip + id_ * 180 + ih * 180 * 90


def _random_pairs(n, seed):
    rng = np.random.default_rng(seed)
    def up(k):
        z = rng.uniform(0.05, 1, k); p = rng.uniform(0, 2 * math.pi, k); s = np.sqrt(1 - z * z)
        return np.stack([s * np.cos(p), s * np.sin(p), z], -1)
    return up(n), up(n)


@pytest.fixture(scope="module")
def indexed():
    """A MERL table whose value in every cell is its own flat index (all channels)."""
    v = np.broadcast_to(np.arange(NCELLS, dtype=float).reshape(RES), (3,) + RES)
    return MerlBRDF(v, "index table")


def test_lookup_matches_reference_reader(indexed):
    wi, wo = _random_pairs(400, 11)
    got = indexed.eval(wi, wo)[:, 0]
    ref = np.array([_ref_index(a, b) for a, b in zip(wi, wo)], dtype=float)
    assert np.array_equal(got, ref)


def test_lookup_is_reciprocal(indexed):
    wi, wo = _random_pairs(2000, 12)
    assert np.array_equal(indexed.eval(wi, wo), indexed.eval(wo, wi))


def test_cell_centres_fall_in_their_own_cells(indexed):
    wi, wo = cell_centres()
    rng = np.random.default_rng(0)
    ii = tuple(rng.integers(0, n, 3000) for n in RES)
    ok = (wi[ii][:, 2] > 1e-9) & (wo[ii][:, 2] > 1e-9)
    expect = (ii[2] + 180 * (ii[1] + 90 * ii[0])).astype(float)
    assert np.array_equal(indexed.eval(wi[ii][ok], wo[ii][ok])[:, 0], expect[ok])


def test_file_layout_and_scales(tmp_path):
    # Lambertian rd = (0.3, 0.5, 0.7): f = rd/pi everywhere above the horizon
    m = plausible.make("lambertian", rd=[0.3, 0.5, 0.7])
    p = write_merl(tmp_path / "lambert.binary", m)
    raw = p.read_bytes()
    assert len(raw) == 12 + 3 * 90 * 90 * 180 * 8
    assert tuple(np.frombuffer(raw[:12], "<i4")) == (90, 90, 180)
    planes = np.frombuffer(raw[12:], "<f8").reshape(3, 90, 90, 180)
    wi, wo = cell_centres()
    up = (wi[..., 2] > 1e-12) & (wo[..., 2] > 1e-12)
    for c, (rd, s) in enumerate(zip((0.3, 0.5, 0.7), (1.0, 1.15, 1.66))):
        assert np.allclose(planes[c][up], rd / math.pi * 1500.0 / s, rtol=1e-14)
        assert np.all(planes[c][~up] == 0)
    r = read_merl(p)
    assert np.allclose(r.eval([0.3, 0.1, 0.9], [-0.2, 0.4, 0.8]), np.array([0.3, 0.5, 0.7]) / math.pi,
                       rtol=1e-14)


def test_round_trip_model_to_file_to_model(tmp_path):
    m = plausible.make("ashikhmin-shirley", nu=50, nv=50, rs=[0.1, 0.2, 0.3], rd=[0.5, 0.4, 0.3])
    r = read_merl(write_merl(tmp_path / "as.binary", m))
    # exact at the cell centres
    wi, wo = cell_centres()
    rng = np.random.default_rng(1)
    ii = tuple(rng.integers(0, n, 3000) for n in RES)
    assert np.allclose(r.eval(wi[ii], wo[ii]), m.eval(wi[ii], wo[ii]), rtol=1e-14, atol=0)
    # anywhere: the value of the model at the centre of the reference reader's cell
    a, b = _random_pairs(300, 4)
    idx = np.array([_ref_index(x, y) for x, y in zip(a, b)])
    ih, rem = np.divmod(idx, 90 * 180)
    id_, ip = np.divmod(rem, 180)
    assert np.allclose(r.eval(a, b), m.eval(wi[ih, id_, ip], wo[ih, id_, ip]), rtol=1e-14, atol=0)
    # the albedo of the table agrees with the model's to the table's resolution
    for t in (0.0, 40.0, 70.0):
        w = direction(math.radians(t))
        assert np.allclose(albedo(r, w).value, albedo(m, w).value, atol=2e-3)


def test_missing_cells(tmp_path):
    v = tabulate(plausible.make("lambertian", rd=0.5))
    v[:, 10:20] = -1.0                      # theta_h cells 10..19 unmeasured
    r = read_merl(write_merl(tmp_path / "holes.binary", v))
    assert np.all(r.values[:, 10:20] == -1.0)
    wi, wo = cell_centres()
    a, b = wi[15, 30, 40], wo[15, 30, 40]
    assert r.missing(a, b) and np.all(r.eval(a, b) == 0)
    a, b = wi[40, 30, 40], wo[40, 30, 40]
    assert not r.missing(a, b) and np.allclose(r.eval(a, b), 0.5 / math.pi, rtol=1e-14)


def test_bad_files_raise(tmp_path):
    bad = tmp_path / "bad.binary"
    np.array([90, 90, 360], "<i4").tofile(bad)
    with pytest.raises(ValueError, match="not a MERL BRDF file"):
        read_merl(bad)
    short = tmp_path / "short.binary"
    with open(short, "wb") as fh:
        np.array([90, 90, 180], "<i4").tofile(fh)
        np.zeros(100).tofile(fh)
    with pytest.raises(ValueError, match="expected 4374000"):
        read_merl(short)
    with pytest.raises(ValueError, match="shape"):
        MerlBRDF(np.zeros((3, 90, 90, 90)))


def test_contract_sampling_is_consistent(indexed):
    check_sampling(MerlBRDF(tabulate(plausible.make("modified-phong", n=20)), "phong"), [0.4, 0.1, 0.9])


def test_fit_to_a_merl_file_recovers_the_model(tmp_path):
    # a MERL table of a known model, fitted back at the cells' centres (where the table is the
    # model): measured nu 49.99999997, rs 0.1, rd 0.4; the bounds leave room for the optimiser
    from plausible.fitting import fit

    truth = dict(nu=50.0, nv=50.0, rs=0.1, rd=0.4)
    p = write_merl(tmp_path / "as.binary", plausible.make("ashikhmin-shirley", **truth))
    r = fit("ashikhmin-shirley", str(p), "l2-cos", starts=1)
    assert r.target.channels == 3 and r.target.albedo.shape == (7, 3)
    assert abs(r.params["nu"] / 50 - 1) < 0.01 and abs(r.params["nv"] / 50 - 1) < 0.01
    assert np.allclose(r.params["rs"], 0.1, rtol=0.05) and np.allclose(r.params["rd"], 0.4, rtol=0.05)
    assert r.errors["albedo_max"] < 0.02


def test_fit_targets_sit_at_cell_centres(tmp_path):
    # a sixth of sample_pairs lie on MERL cell edges (whole degrees), where the nearest cell is
    # decided by the last bit; a MERL target is compared at the centres of the cells instead,
    # where the table of a model equals the model (tabulate samples the centres)
    from plausible.fitting import metrics as M

    m = plausible.make("ashikhmin-shirley", nu=50.0, nv=50.0, rs=0.1, rd=0.4)
    r = read_merl(write_merl(tmp_path / "as.binary", m))
    wi, wo = r.measured_pairs(*M.sample_pairs(r.peak_directions))
    assert np.allclose(r.eval(wi, wo).mean(axis=-1), m.eval(wi, wo), rtol=1e-12)
    rng = np.random.default_rng(3)
    for _ in range(3):     # 1e-9 rad from a centre is deep inside its cell
        d = wo + rng.normal(size=wo.shape) * 1e-9
        assert np.array_equal(r.eval(wi, d), r.eval(wi, wo))


# -- where a MERL target is compared: both tangents (issue 29) ----------------------

@pytest.fixture(scope="module")
def ward_table():
    truth = plausible.make("ward", alpha_x=0.2, alpha_y=0.2, rs=0.2, rd=0.3)
    return MerlBRDF(tabulate(truth))


def test_from_half_diff_places_the_half_vector_at_phi_h():
    from plausible.models.merl import from_half_diff, half_diff
    from plausible.arrays.ops import NP

    th, td, pd, ph = 0.4, 0.7, 1.1, np.array([0.0, 0.9, 2.5, -2.0])
    wi, wo = from_half_diff(th, td, pd, ph)
    h = (wi + wo) / np.linalg.norm(wi + wo, axis=-1, keepdims=True)
    np.testing.assert_allclose(np.arctan2(h[:, 1], h[:, 0]), ph, atol=1e-12)
    for got, want in zip(half_diff(NP, tuple(wi.T), tuple(wo.T)), (th, td, pd)):
        np.testing.assert_allclose(got, want, atol=1e-12)


def test_measured_pairs_point_half_vectors_along_both_tangents(ward_table):
    from plausible.fitting import metrics as M

    wi, wo = ward_table.measured_pairs(*M.sample_pairs(ward_table.peak_directions))
    h = wi + wo
    phi_h = np.arctan2(h[:, 1], h[:, 0])
    # the azimuths spread evenly: each quarter of the circle holds a quarter of the pairs
    counts = np.histogram(np.mod(phi_h, 2 * np.pi), bins=4, range=(0, 2 * np.pi))[0]
    assert np.all(np.abs(counts / len(wi) - 0.25) < 0.01)
    # and each pair still lies in the cell it stands for (the reference reader's lookup)
    for k in range(0, len(wi), 97):
        assert _ref_index(wi[k], wo[k]) == _ref_index(*_at_phi_h_zero(wi[k], wo[k]))


def _at_phi_h_zero(wi, wo):
    h = wi + wo
    a = -math.atan2(h[1], h[0])
    return _rotate(wi, [0, 0, 1], a), _rotate(wo, [0, 0, 1], a)


def test_an_anisotropic_fit_to_a_merl_table_recovers_both_roughnesses(ward_table):
    # the pairs of the fit to a MERL file (table targets: no albedo integration, fast)
    from plausible.fitting import fit, metrics as M

    wi, wo = ward_table.measured_pairs(*M.sample_pairs(ward_table.peak_directions))
    r = fit("ward", (wi, wo, ward_table.eval(wi, wo)), "l2-cos", starts=1, fixed={"rd": 0.3})
    assert r.params["alpha_x"] == pytest.approx(0.2, rel=1e-6)
    assert r.params["alpha_y"] == pytest.approx(0.2, rel=1e-6)
    assert np.allclose(r.params["rs"], 0.2, rtol=1e-6) and r.unconstrained == []


def test_a_fit_the_samples_do_not_decide_warns(ward_table):
    # every half vector at phi_h = 0 (h_y = 0): Ward's alpha_y only scales the lobe, as rs does
    from plausible.fitting import UnconstrainedWarning, fit, metrics as M
    from plausible.models.merl import from_half_diff, half_diff
    from plausible.arrays.ops import NP

    wi, wo = ward_table.measured_pairs(*M.sample_pairs(ward_table.peak_directions))
    wi, wo = from_half_diff(*half_diff(NP, tuple(wi.T), tuple(wo.T)))
    assert np.max(np.abs((wi + wo)[:, 1])) < 1e-12
    with pytest.warns(UnconstrainedWarning, match="'alpha_y', 'rs' trade against each other"):
        r = fit("ward", (wi, wo, ward_table.eval(wi, wo)), "l2-cos", starts=1, fixed={"rd": 0.3})
    assert r.unconstrained == [["alpha_y", "rs"]] and r.to_dict()["unconstrained"] == [["alpha_y", "rs"]]


def test_the_command_line_prints_the_unconstrained_warning(ward_table, tmp_path):
    from click.testing import CliRunner

    from plausible.cli import main
    from plausible.fitting import metrics as M, save_table
    from plausible.models.merl import from_half_diff, half_diff
    from plausible.arrays.ops import NP

    wi, wo = ward_table.measured_pairs(*M.sample_pairs(ward_table.peak_directions))
    wi, wo = from_half_diff(*half_diff(NP, tuple(wi.T), tuple(wo.T)))       # h_y = 0 everywhere
    save_table(tmp_path / "t.csv", wi, wo, ward_table.eval(wi, wo))
    r = CliRunner().invoke(main, ["fit", "ward", "--target", str(tmp_path / "t.csv"), "--metric", "l2-cos",
                                  "--starts", "1", "-p", "rd=0.3"])
    assert r.exit_code == 0, r.output
    assert "warning:" in r.output and "'alpha_y', 'rs' trade against each other" in r.output
