"""Figures of Neumann, Neumann & Szirmay-Kalos, "Compact metallic reflectance
models" / albedo pumping-up (1999): albedo curves and output radiance."""

from __future__ import annotations

import math

import numpy as np

import plausible
from plausible.analysis import albedo_curve
from plausible.plotting import default_thetas
from plausible.progress import within

from . import figure
from .lobes import plane_f

SRC = "Neumann, Neumann & Szirmay-Kalos 1999"
RADIANCE_ANGLES = (0.0, 40.0, 80.0)


def output_radiance(model, theta_l_deg: float, view_deg):
    """Output radiance toward ``V`` under a unit point light at distance 1 in
    direction ``L`` (sec. 3.1: irradiance ``cos theta_L``): ``f(L, V) cos theta_L``,
    with ``L`` and ``V`` in the plane of incidence (``V`` at signed angle
    ``view_deg``; the mirror direction of ``L`` is at ``-theta_L``)."""
    f, _ = plane_f(model, theta_l_deg, view_deg)
    return f * math.cos(math.radians(theta_l_deg))


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def albedo_figure(ctx, name, title, specs, points=46):
    """Albedo against incidence of ``specs`` (label -> model): plot + CSV; returns the curves."""
    plt = _plt()
    th = default_thetas(points if not ctx.quick else 8)
    ctx.steps(len(specs) * len(th))
    curves = {}
    for label, m in specs.items():
        r = albedo_curve(m, th, progress=within(ctx.tick))
        v = np.asarray(r.value)
        curves[label] = v.mean(axis=-1) if v.ndim > 1 else v
    fig, ax = plt.subplots(figsize=(6.2, 4.0))
    for label, v in curves.items():
        ax.plot(np.degrees(th), v, label=label)
    ax.axhline(1.0, color="0.5", lw=0.8, ls="--")
    ax.set_xlabel("incidence angle (degrees)")
    ax.set_ylabel("directional albedo")
    ax.set_xlim(0, 90)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    ctx.plot(name, fig, caption=title)
    ctx.table(name, {"theta_deg": np.degrees(th), **curves})
    return th, curves


def radiance_figure(ctx, name, title, specs, angles=RADIANCE_ANGLES):
    """Output radiance (unit point light) against the viewing angle, for each light angle."""
    plt = _plt()
    view = np.linspace(-89.5, 89.5, 359)
    fig, axes = plt.subplots(1, len(angles), figsize=(4.0 * len(angles), 3.4), sharey=False)
    cols = {"view_deg": view}
    for ax, tl in zip(np.atleast_1d(axes), angles):
        for label, m in specs.items():
            y = output_radiance(m, tl, view)
            cols[f"{label} @ L={tl:g}"] = y
            ax.plot(view, y, label=label)
        ax.axvline(-tl, color="0.6", lw=0.7, ls=":")
        ax.set_title(f"light at {tl:g} deg", fontsize=9)
        ax.set_xlabel("viewing angle (deg; mirror at -theta_L)")
        ax.grid(alpha=.3)
    np.atleast_1d(axes)[0].set_ylabel("output radiance f cos(theta_L)")
    np.atleast_1d(axes)[0].legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    ctx.plot(name, fig, caption=title)
    ctx.table(name, cols)


@figure("neumann-fig1", "Albedo at grazing: Phong, Cook-Torrance and Ward", f"{SRC}, fig. 1",
        "Albedo functions of the Phong (n = 150), He-Torrance, Cook-Torrance (m = 0.1) and Ward (m = 0.1) "
        "models. ... Note that the Cook-Torrance and the Ward models diverge at grazing angles, while the Phong "
        "... BRDFs badly decrease for greater incident angles.",
        phong="reciprocal-phong:ks=1:n=150", cook_torrance="cook-torrance:m=0.1:rs=1",
        cook_torrance_g1="cook-torrance:m=0.1:rs=1:fresnel=none:geometry=none",
        ward="ward:alpha_x=0.1:alpha_y=0.1:rs=1:rd=0")
def fig1(ctx, phong, cook_torrance, cook_torrance_g1, ward):
    from plausible.analysis import albedo, direction

    specs = {s: plausible.registry.make_from_spec(s) for s in (phong, cook_torrance, cook_torrance_g1, ward)}
    th, c = albedo_figure(ctx, "albedo", "Albedo against incidence (Fresnel = 1)", specs)
    # the paper's claims: Phong decreases toward grazing; Cook-Torrance and Ward diverge (grow without bound)
    grazing = (89.0, 89.9, 89.99)
    for s, m in specs.items():
        a = [float(albedo(m, direction(math.radians(t)))) for t in grazing]
        rising = a[0] < a[1] < a[2]
        ctx.measure(f"{s}: albedo at 0 deg", c[s][0])
        ctx.measure(f"{s}: albedo at 89 / 89.9 / 89.99 deg", a[2],
                    note=f"{a[0]:.4f} / {a[1]:.4f} / {a[2]:.4f}: " + ("rising" if rising else "not rising"))
        if s == phong:
            ctx.measure("Phong n = 150 decreases toward grazing: albedo(89.99)", a[2], at_most=0.5 * c[s][0])
        elif s in (cook_torrance_g1, ward):
            ctx.measure(f"{s} diverges: albedo(89.99) / albedo(89.9) (> 1 means rising)", a[2] / a[1])
            ctx.measure(f"{s} diverges: albedo(89.9) / albedo(89.99)", a[1] / a[2], at_most=1.0)
    ctx.note("Cook-Torrance with the V-groove shadowing term (the registry default) does not diverge; with "
             "G = 1 it diverges like 1/cos(theta_i) (docs/models/cook-torrance.md). Ward's albedo diverges only "
             "within about a degree of grazing (docs/models/ward.md).")


def _pumped(base, correction, times):
    try:
        return plausible.make("pumped-up", base=base, correction=correction, times=times)
    except ValueError as e:
        if "unknown model" in str(e):
            return None
        raise


def _pumping(ctx, base, n, correction, times):
    base_name = base
    if ctx.quick:
        times = times[:1]
    base = f"{base_name}:n={n:g}:ks=1"
    specs = {base: plausible.registry.make_from_spec(base)}
    for k in times:
        m = _pumped(base, correction, k)
        if m is None:
            ctx.note("the 'pumped-up' model is not registered in this build: only the base model is shown")
            break
        specs[f"pumped {k}x ({correction})"] = m
    th, c = albedo_figure(ctx, "albedo", f"Albedo of {base_name} (n = {n:g}) and its {correction} pumped-up "
                          "versions", specs)
    radiance_figure(ctx, "radiance", f"Output radiance of {base_name} (n = {n:g}) at 0, 40, 80 degrees", specs)
    vals = list(c.values())
    for (label, v) in c.items():
        ctx.measure(f"{label}: albedo at 0 deg", v[0])
    for a, b, la in zip(vals, vals[1:], list(c)[1:]):
        ctx.measure(f"{la}: albedo >= previous at every angle (pumping raises it)",
                    float(np.all(b >= a - 1e-4)), 1.0, 0.0)
    for la, v in c.items():
        ctx.measure(f"{la}: max albedo over incidence (energy bound 1)", float(v.max()), at_most=1.0 + 1e-4,
                    note="1e-4 = the integrator's accuracy")


for _i, (_base, _corr, _fig) in enumerate([("reciprocal-phong", "max", "3"), ("reciprocal-blinn", "max", "4"),
                                           ("reciprocal-phong", "controlled", "5"),
                                           ("reciprocal-blinn", "controlled", "6")]):
    _name = f"neumann-fig{_fig}"
    _model = "Phong" if "phong" in _base else "Blinn"
    _cap = {"max": f"Albedo and reflected radiance of the reciprocal {_model} model and its pumped-up versions "
                   "(n = 20). ... Note that the albedos resulted by recursive pumping-ups converge to the albedo of "
                   "the ideal mirror (constant 1).",
            "controlled": f"Controlled pumping-up of the reciprocal {_model} model (n = 20). ... The process "
                          "will converge to an albedo that is below the constant 1."}[_corr]
    figure(_name, f"Reciprocal {_model} (n = 20) pumped up, correction {_corr}", f"{SRC}, fig. {_fig}", _cap,
           base=_base, n=20.0, correction=_corr, times=(1, 2, 3))(_pumping)


@figure("neumann-fig7", "The compact metallic model: albedo for several n, output radiance for n = 100",
        f"{SRC}, fig. 7", "The albedo function for different n parameters and the output radiance (n = 100) of "
        "the new model.", exponents=(2, 5, 20, 100, 1000), radiance_n=100)
def fig7(ctx, exponents, radiance_n):
    specs = {f"neumann-metal n={n:g}": plausible.make("neumann-metal", n=n) for n in exponents}
    th, c = albedo_figure(ctx, "albedo", "Albedo of the compact metallic model", specs)
    for la, v in c.items():
        ctx.measure(f"{la}: max albedo over incidence (energy bound 1)", float(v.max()), at_most=1.0 + 1e-4,
                    note="1e-4 = the integrator's accuracy")
    radiance_figure(ctx, "radiance", f"Output radiance of the compact metallic model, n = {radiance_n:g}",
                    {f"n={radiance_n:g}": plausible.make("neumann-metal", n=radiance_n)})


METALS = {"hull": "Au", "turret": "Au", "barrel": "Au", "pyr_al": "Al", "pyr_ag": "Ag", "pyr_cu": "Cu",
          "pyr_au": "Au"}

_PYRAMID_OBJ = """v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv 0 0 1.3
f 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\nf 1 3 2\nf 1 4 3
"""


def metal_spectrum(metal: str) -> dict:
    """Mitsuba ``irregular`` spectrum of the metal's reflectance at normal incidence,
    computed from its tabulated (n, k) by :func:`plausible.spectra.metal_reflectance`."""
    from plausible import spectra

    wl = np.arange(360.0, 831.0, 10.0)
    r = np.clip(spectra.metal_reflectance(metal, wl), 0.0, 1.0)
    return {"type": "irregular", "wavelengths": ", ".join(f"{x:g}" for x in wl),
            "values": ", ".join(f"{x:.6f}" for x in r)}


def _tank_scene(mi, out, material, res, spp):
    from . import scenes as S

    T = mi.ScalarTransform4f()
    obj = out / "pyramid.obj"
    obj.write_text(_PYRAMID_OBJ)
    shapes = {
        "hull": {"type": "cube", "to_world": T.translate([0, 0, 0.45]) @ T.scale([1.6, 0.9, 0.35])},
        "turret": {"type": "cylinder", "radius": 0.55, "p0": [-0.2, 0, 0.8], "p1": [-0.2, 0, 1.25]},
        "turret_top": {"type": "disk", "to_world": T.translate([-0.2, 0, 1.25]) @ T.scale(0.55)},
        "barrel": {"type": "cylinder", "radius": 0.08, "p0": [0.3, 0, 1.05], "p1": [2.3, 0, 1.1]},
    }
    for name, (x, y) in {"pyr_al": (-2.6, -2.2), "pyr_ag": (-0.4, -2.6), "pyr_cu": (1.8, -2.4),
                         "pyr_au": (3.4, -0.6)}.items():
        shapes[name] = {"type": "obj", "filename": str(obj), "face_normals": True,
                        "to_world": T.translate([x, y, 0.1]) @ T.rotate([0, 0, 1], 30) @ T.scale(0.6)}
    for name, d in shapes.items():
        d["bsdf"] = material(METALS.get(name.replace("_top", ""), "Au"))
    shapes["ground"] = {"type": "rectangle", "to_world": T.translate([0, 0, 0.1]) @ T.scale(12),
                        "bsdf": {"type": "diffuse", "reflectance": {"type": "spectrum", "value": 0.35}}}
    lights = {"sky": {"type": "constant", "radiance": {"type": "spectrum", "value": 0.45}},
              "sun": {"type": "point", "position": [3.0, -4.0, 6.0], "intensity": {"type": "spectrum", "value": 90.0}},
              "fill": {"type": "point", "position": [-5.0, -2.0, 3.0], "intensity": {"type": "spectrum", "value": 30.0}}}
    sensor = S.perspective(mi, [1.5, -9.5, 4.5], [0.3, -1.0, 0.6], res, spp, fov=50.0, up=[0, 0, 1])
    d = {"type": "scene", "integrator": {"type": "path", "max_depth": 6}, "sensor": sensor}
    d.update(shapes)
    d.update(lights)
    return mi.load_dict(d)


@figure("neumann-fig8", "Golden tank with aluminium, silver, copper and golden pyramids", f"{SRC}, fig. 8",
        "A golden tank with aluminum, silver, copper and golden pyramids rendered using the reciprocal Phong model "
        "(top) and using the Phong model pumped-up once (bottom) (left: n = 20, right: n = 5000). ... The scene is "
        "illuminated by both point lightsources and sky-light.", renders=True, exponents=(20.0, 5000.0),
        metals="reflectance at normal incidence from each metal's tabulated (n, k), spectral (llvm_ad_spectral)")
def fig8(ctx, exponents, metals):
    from . import scenes as S

    mi = S.mitsuba(S.SPECTRAL)
    try:
        res, spp = ctx.res(1.0), ctx.spp()
        ctx.steps(2 * len(exponents))
        imgs, labels = [], []
        for pumped in (False, True):
            for n in exponents:
                if pumped:
                    def mat(metal, n=n):
                        return {"type": "pumped_up", "base": f"reciprocal-phong:ks=1:n={n:g}", "correction": "max",
                                "times": 1, "rs": metal_spectrum(metal)}
                else:
                    def mat(metal, n=n):
                        return {"type": "reciprocal_phong", "n": n, "ks": metal_spectrum(metal)}
                img = S.render(mi, _tank_scene(mi, ctx.out, mat, res, spp), seed=0)
                label = f"{'pumped once' if pumped else 'reciprocal Phong'}, n = {n:g}"
                ctx.image(f"tank-{'pumped' if pumped else 'phong'}-{n:g}", img, caption=label)
                imgs.append(img)
                labels.append(label)
                ctx.measure(f"{label}: mean image value", float(img.mean()))
                ctx.tick()
        k = len(exponents)
        for i, n in enumerate(exponents):
            ctx.measure(f"n = {n:g}: pumped / unpumped mean image value (pumping brightens)",
                        float(imgs[k + i].mean() / imgs[i].mean()))
        ctx.plot("tank-grid", S.grid_figure(imgs, 2, k, labels, title="top: reciprocal Phong; bottom: pumped once"),
                 caption="the four renders side by side")
    finally:
        S.mitsuba(S.RGB)
    ctx.note("Both rows use the same spectral reflectance (each metal's Fresnel reflectance at normal incidence "
             "from its (n, k)), so the rows differ only by the pumping.")
