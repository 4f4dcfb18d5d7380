"""Figures of Ashikhmin & Shirley, "An anisotropic Phong light reflection model"
(tech report UUCS-00-014 and JGT 2000), rendered with plausible's Mitsuba plugins."""

from __future__ import annotations

import math

import numpy as np

import plausible
from plausible.analysis import albedo, direction

from .core import CURVE_TOL, figure
from . import scenes as S

EXPONENTS = (10, 100, 1000, 10000)
RED = (0.8, 0.06, 0.04)
TR = "Ashikhmin & Shirley, tech report 2000"
JGT = "Ashikhmin & Shirley, JGT 2000"


def as_bsdf(nu, nv, rs, rd):
    return {"type": "ashikhmin_shirley", "nu": float(nu), "nv": float(nv), "rs": S.rgb(rs), "rd": S.rgb(rd)}


def _patch_check(ctx, img, width, model, label, res):
    """Mean of the pixels around the image centre (normal incidence) against the
    directional albedo there; tolerance = 4 standard errors of the pixel mean plus
    the albedo's change across the patch (the patch spans incidence 0..theta_max).
    A colour model: the channel means (as the pixels).  The albedos to an error bound of
    :data:`~plausible.figures.core.CURVE_TOL` (1e-5), far below the tolerance."""
    r = S.radius_map(res, width)
    rmax = max(0.06, 2.0 * 2 * width / res)
    sel = r <= rmax
    px = img[sel].mean(axis=-1)
    got, se = float(px.mean()), float(px.std(ddof=1) / math.sqrt(px.size))
    # to CURVE_TOL (1e-5): the tolerance is at least 4 standard errors of the pixel mean (1e-3 or more);
    # at normal incidence, the value of an albedo curve that this process integrated already (remembering)
    a0 = float(np.mean(albedo(model, direction(0.0), tol=CURVE_TOL).value))
    a1 = float(np.mean(albedo(model, direction(math.asin(min(rmax, 0.999))), tol=CURVE_TOL).value))
    tol = 4 * se + abs(a1 - a0)
    ctx.measure(f"{label}: centre luminance", got, a0, tol,
                note=f"{sel.sum()} pixels within {math.degrees(math.asin(min(rmax, .999))):.1f} deg of normal "
                     f"incidence; expected = plausible.albedo at 0 deg (at the patch edge: {a1:.4f})")
    return got, se, a0


#: Incidence angles (degrees) of the rim check, and plausible.albedo of nu = nv = 10 there
#: (the prediction of the sphere's rim: 0.688 / 0.613 / 0.539 / 0.504).
RIM_ANGLES = (30.0, 60.0, 80.0, 89.0)


def tilted_plane_furnace(mi, bsdf: dict, theta_deg: float, res: int, spp: int):
    """A large flat patch of ``bsdf`` in the unit furnace, seen by an orthographic
    camera at ``theta_deg`` from its normal (one bounce): every pixel is the
    directional albedo at that incidence, the radiance the sphere's rim shows at the
    same angle (a silhouette pixel would mix angles and the background)."""
    t = math.radians(theta_deg)
    o = [5.0 * math.sin(t), 0.0, 5.0 * math.cos(t)]
    return mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 2},
        "sensor": S.orthographic(mi, 0.05, res, spp, origin=o, target=(0, 0, 0), up=(0, 1, 0)),
        "plane": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([20.0, 20.0, 1.0]), "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
    })


def rim_checks(ctx, mi, n, rs, rd):
    """The furnace's prediction away from the sphere centre: the radiance at
    incidence 30, 60, 80, 89 deg (the rim) against plausible.albedo there, 4 s.e."""
    model = plausible.make("ashikhmin-shirley", nu=n, nv=n, rs=rs, rd=rd)
    for i, t in enumerate(RIM_ANGLES):
        img = S.render(mi, tilted_plane_furnace(mi, as_bsdf(n, n, rs, rd), t, 16, ctx.spp(2)), seed=100 + i)
        px = img.mean(axis=-1).ravel()
        got, se = float(px.mean()), float(px.std(ddof=1) / math.sqrt(px.size))
        want = float(albedo(model, direction(math.radians(t))))
        ctx.measure(f"nu = nv = {n:g}, incidence {t:g} deg (the rim): furnace radiance vs plausible.albedo", got,
                    want, 4 * se, note=f"a flat patch seen at {t:g} deg in the furnace, {px.size} pixels, 4 s.e.")
        ctx.tick()


@figure("as-furnace", "Spheres in a white furnace", f"{TR}, fig. 2",
        "Spheres in a furnace. As the exponents get larger, less energy is \u201clost\u201d. For the center of the "
        "darkest sphere, n_u = n_v = 10, the luminance is about 68% of the background luminance.",
        renders=True, exponents=EXPONENTS, rs=1.0, rd=0.0)
def furnace(ctx, exponents, rs, rd):
    mi = S.mitsuba()
    res, spp, width = ctx.res(0.375, minimum=24), ctx.spp(), 1.05
    ctx.steps(len(exponents) ** 2 + len(RIM_ANGLES))
    imgs, labels, rows = [], [], []
    for k, (nu, nv) in enumerate((a, b) for a in exponents for b in exponents):
        # one seed per sphere: independent noise
        img = S.render(mi, S.furnace(mi, as_bsdf(nu, nv, rs, rd), res, spp, width), seed=k)
        model = plausible.make("ashikhmin-shirley", nu=nu, nv=nv, rs=rs, rd=rd)
        got, se, a0 = _patch_check(ctx, img, width, model, f"nu={nu:g}, nv={nv:g}", res)
        imgs.append(img)
        labels.append(f"nu={nu:g} nv={nv:g}\ncentre {got:.3f}\u00b1{se:.3f} | albedo {a0:.3f}")
        rows.append((nu, nv, got, se, a0))
        ctx.tick()
    n = len(exponents)
    ctx.image("furnace", S.mosaic(imgs, n, n), caption="rows nu, columns nv (10 ... 10^4); background = 1")
    ctx.plot("furnace-labelled", S.grid_figure(imgs, n, n, labels, title="white furnace: centre pixel vs "
                                               "directional albedo at normal incidence"),
             caption="each sphere with its measured centre luminance and plausible.albedo at normal incidence")
    rows = np.array(rows)
    ctx.table("centres", dict(nu=rows[:, 0], nv=rows[:, 1], centre=rows[:, 2], centre_se=rows[:, 3],
                              albedo_normal=rows[:, 4]))
    rim_checks(ctx, mi, exponents[0], rs, rd)
    diag = [(r[2], r[3]) for r in rows if r[0] == r[1]]
    rises = [b[0] - a[0] for a, b in zip(diag, diag[1:])]
    ctx.measure("'As the exponents get larger, less energy is lost': smallest rise of the rendered centre from one "
                "diagonal sphere (nu = nv) to the next, in standard errors", min(
                    r / float(np.hypot(a[1], b[1])) for r, a, b in zip(rises, diag, diag[1:])), at_least=2.0,
                note="centres " + " / ".join(f"{c:.4f}" for c, _ in diag))
    ctx.measure("nu = nv = 10: directional albedo at normal incidence vs the paper's 'about 68%'", rows[0, 4],
                0.68, 0.02, note=f"plausible.albedo; the render's centre reads {rows[0, 2]:.3f} +- {rows[0, 3]:.3f}; "
                "'about' read as +-2 points")


def _spheres_grid(ctx, bsdfs):
    mi = S.mitsuba()
    ctx.steps(1)
    img = S.render(mi, S.sphere_grid(mi, bsdfs, ctx.res(1.5), ctx.spp()), seed=0)
    ctx.tick()
    return img


@figure("as-gold", "Metallic spheres on a texture-mapped plane", f"{TR}, fig. 3; {JGT}, fig. 1",
        "Figure 3 shows a set of golden spheres on a texture-mapped Lambertian plane. As the values of "
        "parameters n_u and n_v change, the appearance of the spheres shift from rough metal to almost perfect "
        "mirror, and from highly anisotropic to the more familiar phong-like behavior.",
        renders=True, exponents=EXPONENTS, rd=0.0, rs="gold (conductor Fresnel of Au at normal incidence, sRGB)")
def gold(ctx, exponents, rd, rs):
    g = S.gold_rgb()
    img = _spheres_grid(ctx, [as_bsdf(a, b, g, rd) for a in exponents for b in exponents])
    ctx.image("gold", img, caption="rows (back to front) nu = 10, 100, 1000, 10^4; columns (left to right) "
                                   f"nv = 10 ... 10^4; rs = ({g[0]:.2f}, {g[1]:.2f}, {g[2]:.2f})")


@figure("as-red-spheres", "Polished red spheres", f"{TR}, fig. 6",
        "A set of polished red spheres with different phong exponents n_u, n_v is shown in Figure 6. For all "
        "spheres R_s is set to 0.05 across the visible spectrum which is a typical value for plastics.",
        renders=True, exponents=EXPONENTS, rs=0.05, rd=RED)
def red_spheres(ctx, exponents, rs, rd):
    img = _spheres_grid(ctx, [as_bsdf(a, b, rs, rd) for a in exponents for b in exponents])
    ctx.image("red-spheres", img, caption="rows (back to front) nu = 10 ... 10^4; columns nv = 10 ... 10^4")


@figure("as-cylinder", "Brushed-metal cylinder", f"{JGT}, fig. 2",
        "A cylinder with the appearance of brushed metal created with the new model with R_d = 0, R_s = 0.9, "
        "n_u = 10, n_v = 100.", renders=True, nu=10.0, nv=100.0, rs=0.9, rd=0.0)
def cylinder(ctx, nu, nv, rs, rd):
    mi = S.mitsuba()
    T = mi.ScalarTransform4f()
    b = as_bsdf(nu, nv, rs, rd)
    shapes = {"cyl": {"type": "cylinder", "radius": 1.0, "p0": [0, 0, -1.0], "p1": [0, 0, 2.0], "bsdf": b},
              "cap": {"type": "disk", "to_world": T.translate([0, 0, 2.0]), "bsdf": b}}
    lights = S.studio_lights(sky=0.15)
    lights["key"] = S.lamp([9.0, -15.0, 4.5], 540.0, radius=3.0)   # a point light of 60 at a third the distance
    res = ctx.res(1.5)
    ctx.steps(1)
    sensor = S.perspective(mi, [0, -9, 3.0], [0, 0, 0.4], res, ctx.spp(), fov=34.0, up=[0, 0, 1])
    img = S.render(mi, S.studio(mi, shapes, sensor, lights=lights), seed=0)
    ctx.tick()
    ctx.image("cylinder", img, caption="Mitsuba's cylinder: tangent u (nu = 10) runs around the circumference, "
                                       "v (nv = 100) along the axis, so the highlight spreads around it")
    ctx.note("Tangent orientation as in docs/mitsuba.md: on Mitsuba's cylinder sh_frame.s = dp/du runs around "
             "the circumference, so the smaller exponent nu widens the lobe around the cylinder, the look of "
             "fine grooves along the axis.")


@figure("as-three-views", "Three views of a polished red sphere", f"{TR}, fig. 5; {JGT}, fig. 3",
        "Three views for n_u = n_v = 400 and a red substrate. ... we can observe strengthening of the specular "
        "reflection near the silhouette of the sphere along with simultaneous decrease in the intensity of the "
        "red color.", renders=True, nu=400.0, nv=400.0, rs=0.05, rd=RED)
def three_views(ctx, nu, nv, rs, rd):
    mi = S.mitsuba()
    b = as_bsdf(nu, nv, rs, rd)
    res, spp = ctx.res(), ctx.spp()
    elevations = (8.0, 35.0, 70.0)
    ctx.steps(len(elevations))
    for el in elevations:
        e = math.radians(el)
        sensor = S.perspective(mi, [0, -7 * math.cos(e), 7 * math.sin(e)], [0, 0, 0], res, spp, fov=28.0,
                               up=[0, 0, 1])
        img = S.render(mi, S.studio(mi, {"sphere": {"type": "sphere", "radius": 1.0, "bsdf": b}}, sensor), seed=0)
        ctx.image(f"view-{el:g}", img, caption=f"camera elevation {el:g} deg")
        ctx.tick()
    # the effect, on the model itself: specular albedo rises and diffuse albedo falls toward grazing
    spec = plausible.make("ashikhmin-shirley-specular", nu=nu, nv=nv, rs=rs)
    diff = plausible.make("ashikhmin-shirley-diffuse", rs=rs, rd=1.0)
    sa, da = [], []
    for t in (0.0, 60.0, 85.0):
        sa.append(float(albedo(spec, direction(math.radians(t)))))
        da.append(float(albedo(diff, direction(math.radians(t)))))
        ctx.measure(f"specular albedo at {t:g} deg (rs = {rs})", sa[-1])
        ctx.measure(f"diffuse albedo per unit rd at {t:g} deg", da[-1])
    ctx.measure("'strengthening of the specular reflection near the silhouette': specular albedo at 85 deg / at 0 deg",
                sa[-1] / sa[0], at_least=2.0)
    ctx.measure("'simultaneous decrease in the intensity of the red color': diffuse albedo at 85 deg / at 0 deg",
                da[-1] / da[0], at_most=0.9)


@figure("as-lambert-vs-as", "Lambertian sphere next to an Ashikhmin-Shirley sphere (n = 5)", f"{JGT}, fig. 4",
        "An image with a Lambertian sphere (left) and a sphere with n_u = n_v = 5. ... Note how the ball on the "
        "right has highlights near the edge of the model, and how the constant-BRDF ball on the left is more "
        "\u201cflat\u201d.", renders=True, nu=5.0, nv=5.0, rs=0.05, rd=(0.25, 0.4, 0.8))
def lambert_vs_as(ctx, nu, nv, rs, rd):
    mi = S.mitsuba()
    shapes = {"lam": {"type": "sphere", "center": [-1.15, 0, 0], "radius": 1.0,
                      "bsdf": {"type": "lambertian", "rd": S.rgb(rd)}},
              "as": {"type": "sphere", "center": [1.15, 0, 0], "radius": 1.0, "bsdf": as_bsdf(nu, nv, rs, rd)}}
    lights = {"sky": {"type": "constant", "radiance": S.rgb(0.05)},
              # point lights of 55 and 20 at a third the distance, as spherical lamps (scenes.lamp)
              "back": S.lamp([6.0, 18.0, 9.0], 495.0, radius=3.0),
              "front": S.lamp([-9.0, -18.0, 6.0], 180.0, radius=3.0)}
    res = ctx.res(1.5)
    ctx.steps(1)
    sensor = S.perspective(mi, [0, -8, 1.0], [0, 0, 0], res, ctx.spp(), fov=32.0, up=[0, 0, 1])
    img = S.render(mi, S.studio(mi, shapes, sensor, lights=lights), seed=0)
    ctx.tick()
    ctx.image("lambert-vs-as", img, caption="left: Lambertian rd; right: Ashikhmin-Shirley nu = nv = 5, same rd, "
                                            "rs = 0.05; lit from behind-right and front-left")


@figure("as-half-sphere", "Half of a diffusely illuminated sphere (rs = 0.05, rd = 1)", f"{TR}, fig. 4",
        "Half of a diffusely illuminated sphere with R_s = 0.05 and R_d = 1. ... For large n there is little "
        "loss of energy by the specular term, so any darkening of the sphere is due to the diffuse component.",
        renders=True, nu=1000.0, nv=1000.0, rs=0.05, rd=1.0)
def half_sphere(ctx, nu, nv, rs, rd):
    import matplotlib.pyplot as plt

    mi = S.mitsuba()
    res, width = ctx.res(1.0, minimum=32), 1.05
    ctx.steps(2)
    img = S.render(mi, S.furnace(mi, as_bsdf(nu, nv, rs, rd), res, ctx.spp(4), width), seed=0)
    ctx.tick()
    ctx.image("half-sphere", img[:, res // 2:], caption="right half of the sphere in a unit furnace")
    model = plausible.make("ashikhmin-shirley", nu=nu, nv=nv, rs=rs, rd=rd)
    r = S.radius_map(res, width)
    lum = img.mean(axis=-1)
    edges = np.array([0.0, 0.15, 0.3, 0.45, 0.6, 0.7, 0.8, 0.87, 0.93])
    rows = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (r >= lo) & (r < hi)
        if sel.sum() < 4:
            continue
        px = lum[sel]
        got, se = float(px.mean()), float(px.std(ddof=1) / math.sqrt(px.size))
        # expected: the albedo averaged over the ring's pixels (area weight ~ r dr), by Gauss-Legendre in r
        x, w = np.polynomial.legendre.leggauss(6)
        rr = 0.5 * (hi - lo) * x + 0.5 * (hi + lo)
        a = np.array([float(albedo(model, direction(math.asin(v)))) for v in rr])
        want = float(np.sum(w * rr * a) / np.sum(w * rr))
        ctx.measure(f"ring r in [{lo:.2f}, {hi:.2f}) (incidence {math.degrees(math.asin(lo)):.0f}-"
                    f"{math.degrees(math.asin(hi)):.0f} deg)", got, want, 4 * se,
                    note="pixel mean vs plausible.albedo averaged over the ring")
        rows.append((lo, hi, got, se, want))
    # "little loss of energy by the specular term, so any darkening of the sphere is due to the diffuse
    # component": the two terms' albedos from the centre to the outer ring (64 deg)
    spec = plausible.make("ashikhmin-shirley-specular", nu=nu, nv=nv, rs=rs)
    diff = plausible.make("ashikhmin-shirley-diffuse", rs=rs, rd=rd)
    drop = {k: float(albedo(m, direction(0.0))) - float(albedo(m, direction(math.radians(64.0))))
            for k, m in (("total", model), ("specular", spec), ("diffuse", diff))}
    ctx.measure("'any darkening of the sphere is due to the diffuse component': the diffuse term's albedo drop from "
                "0 to 64 deg / the model's", drop["diffuse"] / drop["total"], at_least=0.9,
                note=f"drops: model {drop['total']:.4f}, diffuse {drop['diffuse']:.4f}, specular "
                     f"{drop['specular']:.4f} (negative: the specular term reflects more toward the rim)")
    ctx.tick()
    rows = np.array(rows)
    ctx.table("profile", dict(r_lo=rows[:, 0], r_hi=rows[:, 1], luminance=rows[:, 2], se=rows[:, 3],
                              albedo=rows[:, 4]))
    fig, ax = plt.subplots(figsize=(6, 3.6))
    th = np.radians(np.linspace(0, 89, 60))
    ax.plot(np.degrees(th), [float(albedo(model, direction(t))) for t in th], label="plausible.albedo")
    mid = np.degrees(np.arcsin(0.5 * (rows[:, 0] + rows[:, 1])))
    ax.errorbar(mid, rows[:, 2], yerr=2 * rows[:, 3], fmt="o", label="render (ring mean, 2 s.e.)")
    ax.set_xlabel("incidence angle (deg)")
    ax.set_ylabel("luminance / albedo")
    ax.grid(alpha=.3)
    ax.legend()
    fig.tight_layout()
    ctx.plot("half-sphere-profile", fig, caption="rendered luminance against incidence vs the directional albedo")


def rmse_from_pair(a, b) -> tuple:
    """RMSE of a render against its expectation (the converged image) from two renders
    ``a``, ``b`` of the same scene with independent seeds, and the estimate's standard
    error: ``E[(a - b)^2] = 2 Var`` for independent unbiased estimates, so the mean
    squared error is ``mean((a - b)^2) / 2`` over pixels and channels.  No reference
    image is needed, and none adds its own noise (against a ``k``-spp reference the RMSE
    of an ``n``-spp render reads ``sqrt(1 + n / k)`` times too high).  The standard
    error treats pixels as independent (a pixel's channels are averaged first)."""
    d2 = 0.5 * (np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64)) ** 2
    per_px = d2.reshape(d2.shape[0] * d2.shape[1], -1).mean(axis=-1) if d2.ndim == 3 else d2.ravel()
    mse = float(per_px.mean())
    se_mse = float(per_px.std(ddof=1) / math.sqrt(per_px.size))
    rmse = math.sqrt(mse)
    return rmse, (se_mse / (2 * rmse) if rmse > 0 else 0.0)


@figure("as-convergence", "Convergence: 9, 26 and 100 samples per pixel", f"{TR}, fig. 7; {JGT}, fig. 6",
        "A closeup of the model implemented in a path tracer with 9, 26, and 100 samples.",
        renders=True, samples=(9, 26, 100), nu=20.0, nv=200.0, rs=0.05, rd=RED)
def convergence(ctx, samples, nu, nv, rs, rd):
    mi = S.mitsuba()
    res = ctx.res(0.75, minimum=24)
    ctx.steps(2 * len(samples))
    sensor = S.perspective(mi, [1.2, -3.2, 2.2], [0, 0, 0.2], res, samples[0], fov=22.0, up=[0, 0, 1])
    scene = S.studio(mi, {"sphere": {"type": "sphere", "radius": 1.0, "bsdf": as_bsdf(nu, nv, rs, rd)}}, sensor)
    pooled, total = 0.0, 0
    for n in samples:
        img = S.render(mi, scene, seed=1, spp=n)
        ctx.tick()
        twin = S.render(mi, scene, seed=2, spp=n)     # an independent second render: the RMSE needs no reference
        ctx.tick()
        ctx.image(f"spp-{n}", img, caption=f"{n} samples per pixel")
        rmse, se = rmse_from_pair(img, twin)
        ctx.measure(f"RMSE at {n} spp against the converged image", rmse,
                    note=f"from this render and an independent one at {n} spp (seeds 1 and 2): mean squared "
                         f"error = mean((a - b)^2) / 2, +- {se:.1g} (1 s.e.); RMSE x sqrt(spp) = "
                         f"{rmse * math.sqrt(n):.4f}")
        pooled, total = pooled + n * (img + twin), total + 2 * n
    ctx.image("pooled", pooled / total, caption=f"all {len(samples) * 2} renders pooled ({total} spp)")
