"""The figures report in quick mode (made once per session), checked on its outputs:
files, finite non-blank images, furnace centres against plausible.albedo, index
links, the cache, and the page in a real headless browser."""

from __future__ import annotations

import math
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba")

import plausible  # noqa: E402
from plausible.analysis import albedo, direction  # noqa: E402
from plausible.figures import Context, names  # noqa: E402
from plausible.figures import scenes as S  # noqa: E402
from plausible.figures.paper_neumann import output_radiance  # noqa: E402
from plausible.figures.report import run, write_index  # noqa: E402

pytestmark = pytest.mark.drjit


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("figures")
    res = run(out, quick=True)
    return out, res


def _read_exr(path):
    S.mitsuba()
    return np.array(mi.Bitmap(str(path)), dtype=np.float64)


def test_every_figure_made_with_its_files(report):
    out, res = report
    assert set(res) == set(names())
    for name, m in res.items():
        assert m["status"] == "ok", (name, m.get("error"))
        assert m["items"], name
        for it in m["items"]:
            for key in ("png", "exr", "file"):
                if it.get(key):
                    assert (out / name / it[key]).stat().st_size > 0, (name, it[key])


def test_images_finite_and_not_blank(report):
    from matplotlib.image import imread

    out, res = report
    n_exr = 0
    for name, m in res.items():
        for it in m["items"]:
            if it.get("png"):
                png = imread(out / name / it["png"])
                assert png.std() > 0.01, (name, it["png"])        # not one flat colour
            if it.get("exr"):
                img = _read_exr(out / name / it["exr"])
                assert np.all(np.isfinite(img)), (name, it["exr"])
                assert img.max() > 0.05 and img.std() > 1e-3, (name, it["exr"])
                n_exr += 1
    assert n_exr >= 15


def _centre(img, width=1.05):
    """Mean and standard error of the pixels near the centre of one furnace sphere
    (the same patch rule as the figure), and the patch's largest incidence."""
    res = img.shape[0]
    r = S.radius_map(res, width)
    rmax = max(0.06, 2.0 * 2 * width / res)
    px = img[r <= rmax].mean(axis=-1)
    return px.mean(), px.std(ddof=1) / math.sqrt(px.size), math.asin(rmax)


def _furnace_agrees(img, model):
    got, se, tmax = _centre(img)
    a0 = float(albedo(model, direction(0.0)))
    a1 = float(albedo(model, direction(tmax)))
    return abs(got - a0) <= 4 * se + abs(a1 - a0), (got, se, a0)


def test_furnace_centres_match_the_albedo(report):
    """Recomputed from the EXR itself (not from the figure's own numbers): each of
    the 16 sphere centres equals plausible.albedo at normal incidence within
    4 standard errors plus the albedo's change over the patch."""
    out, res = report
    img = _read_exr(out / "as-furnace" / "furnace.exr")
    ex = res["as-furnace"]["params"]["exponents"]
    n = len(ex)
    h = img.shape[0] // n
    for i, nu in enumerate(ex):
        for j, nv in enumerate(ex):
            tile = img[i * h:(i + 1) * h, j * h:(j + 1) * h]
            ok, info = _furnace_agrees(tile, plausible.make("ashikhmin-shirley", nu=nu, nv=nv, rs=1.0, rd=0.0))
            assert ok, (nu, nv, info)
    # the figure's own checks say the same
    checks = [x for x in res["as-furnace"]["measurements"] if "centre luminance" in x["quantity"]]
    assert len(checks) == 16 and all(x["ok"] for x in checks)


def test_furnace_check_detects_a_wrong_albedo(report):
    """The comparison fails when the tile is compared with another model's albedo
    (nu = nv = 10 sphere against nu = nv = 100)."""
    out, res = report
    img = _read_exr(out / "as-furnace" / "furnace.exr")
    h = img.shape[0] // 4
    ok, _ = _furnace_agrees(img[:h, :h], plausible.make("ashikhmin-shirley", nu=100, nv=100, rs=1.0, rd=0.0))
    assert not ok


def test_half_sphere_profile_matches_the_albedo_curve(report):
    _, res = report
    rings = [x for x in res["as-half-sphere"]["measurements"] if x["quantity"].startswith("ring")]
    assert len(rings) >= 5 and all(x["ok"] for x in rings), rings


class _Links(HTMLParser):
    def __init__(self):
        super().__init__()
        self.links, self.imgs = [], 0

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.imgs += 1
            self.links.append(a["src"])
        if tag == "a" and not a.get("href", "#").startswith("#"):
            self.links.append(a["href"])


def test_index_links_resolve(report):
    out, res = report
    p = _Links()
    p.feed((out / "index.html").read_text())
    assert p.imgs >= len(res)
    missing = [x for x in p.links if not (out / x).is_file()]
    assert not missing, missing


def test_rerun_uses_the_cache_and_changed_inputs_do_not(report):
    out, _ = report
    again = run(out, only=["checks"], quick=True)
    assert again["checks"]["cached"] is True
    changed = run(out, only=["checks"], quick=True, spp=3)
    assert changed["checks"]["cached"] is False
    run(out, only=["checks"], quick=True)   # restore for the other tests


def test_measure_flags_a_check_that_does_not_hold(tmp_path):
    ctx = Context(tmp_path)
    assert ctx.measure("x", 1.0, 1.0, 0.01)["ok"] is True
    assert ctx.measure("x", 1.05, 1.0, 0.01)["ok"] is False
    assert ctx.measure("y", 1.2, at_most=1.0)["ok"] is False
    assert ctx.measure("y", 0.9, at_most=1.0)["ok"] is True


def test_output_radiance_closed_form():
    """Reciprocal Phong, light at 0 deg: the output radiance toward the mirror
    direction (the normal) is ks (n + 2) / (2 pi); at 40 deg, toward the mirror
    (-40 deg) it is ks (n + 2) / (2 pi) cos 40."""
    m = plausible.make("reciprocal-phong", ks=1.0, n=20.0)
    assert output_radiance(m, 0.0, [0.0])[0] == pytest.approx(22 / (2 * math.pi), rel=1e-12)
    assert output_radiance(m, 40.0, [-40.0])[0] == pytest.approx(22 / (2 * math.pi) * math.cos(math.radians(40)),
                                                                 rel=1e-12)


# -- a real browser ---------------------------------------------------------------

def _chromium():
    for exe in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(exe):
            return shutil.which(exe)
    return None


def _loaded(page: Path):
    exe = _chromium()
    if exe is None:
        pytest.skip("chromium is not installed (make setup installs Debian's chromium)")
    r = subprocess.run([exe, "--headless", "--disable-gpu", "--no-sandbox", "--allow-file-access-from-files",
                        "--virtual-time-budget=20000", "--dump-dom", page.resolve().as_uri()],
                       capture_output=True, text=True, timeout=120)
    m = re.search(r'data-images="(\d+)/(\d+)"', r.stdout)
    assert m, (r.stdout[-500:], r.stderr[-2000:])
    return int(m.group(1)), int(m.group(2))


def test_every_image_loads_in_a_headless_browser(report):
    out, _ = report
    p = _Links()
    p.feed((out / "index.html").read_text())
    ok, total = _loaded(out / "index.html")
    assert total == p.imgs and ok == total


def test_browser_check_detects_a_broken_image(tmp_path):
    write_index(tmp_path, {"x": dict(title="x", status="ok", items=[dict(kind="plot", png="missing.png")])})
    ok, total = _loaded(tmp_path / "index.html")
    assert total == 1 and ok == 0


def test_quick_mode_checks_hold_or_say_they_are_not_measured_at_that_quality(report):
    """Issue 44: `plausible figures --quick` (the CI mode) exited 1 with 4 checks that its
    sample counts cannot decide (as-furnace's rise, as-gold's and materials-atlas's hot
    pixels).  Now every check holds or carries no verdict with the reason why."""
    _, res = report
    bad = [(n, x["quantity"]) for n, m in res.items() for x in m["measurements"] if x.get("ok") is False]
    assert bad == []
    unmeasured = [x for m in res.values() for x in m["measurements"] if x.get("unmeasured")]
    assert unmeasured and all("not measured at this quality" in x["unmeasured"] and "ok" not in x
                              for x in unmeasured)
    assert any("1.08579" in t and "n < 2" in t for t in res["neumann-fig7"]["notes"])
