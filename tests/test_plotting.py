"""Plots that survive real labels (issue 47 item 1): the layout read back from the
saved PNG (the axes' frame found by its black spines, nothing cut at the canvas
edge), the public lobe and hemisphere helpers against the model's own numbers, and
the layout checker fed a broken figure."""

import math

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

import plausible
from plausible.cli import main
from plausible.plotting import (albedo_figure, hemisphere_grid, layout_problems, plot_albedo_curves,
                                plot_hemisphere, plot_lobe_polar)

LONG = ("material:nickel@ngan2005/ashikhmin-shirley", "material:alum-bronze@ngan2005/cook-torrance",
        "material:gold-metallic-paint3@ngan2005/ward")


def axes_span(png):
    """``(left, right)`` pixel columns of the axes frame of a saved plot: the outermost
    columns holding a vertical run of dark pixels longer than a quarter of the image
    (the left and right spines; text, curves and the grey grid have none)."""
    a = np.asarray(Image.open(png).convert("L"), dtype=int)
    dark = a < 80
    longest = np.zeros(a.shape[1], int)
    run = np.zeros(a.shape[1], int)
    for row in dark:
        run = np.where(row, run + 1, 0)
        longest = np.maximum(longest, run)
    cols = np.flatnonzero(longest > a.shape[0] // 4)
    return (int(cols[0]), int(cols[-1])) if cols.size else (0, 0)


def border_is_blank(png, margin=2):
    """Nothing drawn within ``margin`` pixels of the canvas edge (a cut legend or title touches it)."""
    a = np.asarray(Image.open(png).convert("L"), dtype=int)
    edge = np.concatenate([a[:margin].ravel(), a[-margin:].ravel(), a[:, :margin].ravel(), a[:, -margin:].ravel()])
    return bool(np.all(edge > 245))


def test_the_png_checks_see_a_squeezed_axes_and_a_cut_legend(tmp_path):
    # the checks can fail: a figure laid out by hand with its axes in a strip and its legend off the canvas
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(6.4, 4.2), dpi=120)
    ax = fig.add_axes((0.75, 0.1, 0.2, 0.8))
    ax.plot([0, 1], [0, 1], label="a label far too long for the canvas " * 4)
    ax.legend(loc="upper right", bbox_to_anchor=(1.6, 1.0))
    fig.savefig(tmp_path / "bad.png")
    left, right = axes_span(tmp_path / "bad.png")
    assert (right - left) / 768 < 0.3 and not border_is_blank(tmp_path / "bad.png")
    problems = layout_problems(fig)
    assert any("axes 0 spans" in p for p in problems) and any("legend reaches outside" in p for p in problems)
    plt.close(fig)


@pytest.mark.parametrize("target", LONG)
def test_fit_out_albedo_png_keeps_its_axes_and_legend_with_long_material_labels(tmp_path, target):
    r = CliRunner().invoke(main, ["fit", "ward", "--target", target, "--out", str(tmp_path), "--time-limit", "3",
                                  "--metric", "l2-cos"])
    assert r.exit_code == 0, r.output
    for name in ("albedo.png", "plane.png"):
        png = tmp_path / name
        width = Image.open(png).size[0]
        left, right = axes_span(png)
        assert (right - left) / width > 0.75, (name, left, right, width)
        assert border_is_blank(png), name


def test_albedo_plot_of_five_models_keeps_the_legend_and_clips_phongs_26_with_a_note(tmp_path):
    models = ["lambertian", "phong:n=10", "ward", "cook-torrance", "ashikhmin-shirley:nu=100:nv=100"]
    png = tmp_path / "five.png"
    r = CliRunner().invoke(main, ["albedo", *models, "-n", "12", "--plot", str(png)])
    assert r.exit_code == 0, r.output
    left, right = axes_span(png)
    assert (right - left) / Image.open(png).size[0] > 0.75 and border_is_blank(png)
    th = plausible.plotting.default_thetas(12)
    curves = [(m, th, plausible.albedo_curve(plausible.make(m), th))
              for m in models]
    phong_top = float(np.max(curves[1][2].value))
    assert phong_top > 20                                          # original Phong gains energy at grazing
    fig = albedo_figure(curves)
    ax = fig.axes[0]
    assert ax.get_ylim()[1] < 1.3                                  # the others stay readable
    label = ax.get_legend().get_texts()[1].get_text()
    assert f"off scale: up to {phong_top:.3g}" in label
    assert layout_problems(fig) == []
    log = albedo_figure(curves, yscale="log").axes[0]
    assert log.get_yscale() == "log" and log.get_ylim()[1] > phong_top and "off scale" not in log.get_legend().get_texts()[1].get_text()
    r = CliRunner().invoke(main, ["albedo", *models[:2], "-n", "6", "--plot", str(tmp_path / "log.png"), "--log"])
    assert r.exit_code == 0 and (tmp_path / "log.png").stat().st_size > 0
    with pytest.raises(ValueError, match="yscale must be 'linear' or 'log'"):
        plot_albedo_curves(curves, tmp_path / "x.png", yscale="symlog")


def test_polar_lobe_is_f_cos_in_the_plane_of_incidence(tmp_path):
    m = plausible.make("ashikhmin-shirley", nu=50, nv=200, rs=0.3, rd=0.4)
    fig = plot_lobe_polar(m, (20.0, 70.0), tmp_path / "lobe.png", n=91)
    ax = fig.axes[0]
    for k, ti in enumerate((20.0, 70.0)):
        ang, r = ax.lines[2 * k].get_data()
        ti_r = math.radians(ti)
        for a, v in zip(ang[::9], r[::9]):         # light on -x at theta_i, view at signed angle a
            wi = np.array([-math.sin(ti_r), 0.0, math.cos(ti_r)])
            wo = np.array([math.sin(a), 0.0, math.cos(a)])
            assert v == pytest.approx(float(m.eval(wi, wo)) * math.cos(a), rel=1e-12, abs=1e-300)
        assert ang[np.argmax(r)] == pytest.approx(ti_r, abs=math.radians(2.5))   # the peak near the mirror
        assert ax.lines[2 * k + 1].get_xdata()[0] == pytest.approx(-ti_r)         # the light's ray
    assert layout_problems(fig) == [] and border_is_blank(tmp_path / "lobe.png")
    with pytest.raises(ValueError, match=r"theta_i_deg must lie in \[0, 90\)"):
        plot_lobe_polar(m, 95.0)


def test_hemisphere_map_is_f_cos_over_the_projected_disk(tmp_path):
    m = plausible.make("ward", alpha_x=0.1, alpha_y=0.3, rs=0.5, rd=0.2)
    wi = np.array([0.4, -0.2, 0.8944271909999159])
    n = 41
    fig = plot_hemisphere(m, wi, tmp_path / "hemi.png", n=n)
    img = np.asarray(fig.axes[0].images[0].get_array().filled(np.nan))
    rng = np.random.default_rng(4)
    c = (np.arange(n) + 0.5) / n * 2 - 1
    for j, i in rng.integers(0, n, (60, 2)):
        x, y = c[i], c[j]
        if x * x + y * y >= 1:
            assert np.isnan(img[j, i])
            continue
        wo = np.array([x, y, math.sqrt(1 - x * x - y * y)])
        assert img[j, i] == pytest.approx(float(m.eval(wi, wo)) * wo[2], rel=1e-12)
    # the brightest pixel is near the mirror direction (-0.4, 0.2) of wi
    j, i = np.unravel_index(np.nanargmax(img), img.shape)
    assert abs(c[i] + 0.4) < 0.15 and abs(c[j] - 0.2) < 0.25
    assert np.isclose(hemisphere_grid(n)[2][..., 2][n // 2, n // 2], 1.0, atol=1e-3)
    assert layout_problems(fig) == [] and border_is_blank(tmp_path / "hemi.png")
    log = plot_hemisphere(m, wi, n=21, scale="log")
    assert type(log.axes[0].images[0].norm).__name__ == "LogNorm"
