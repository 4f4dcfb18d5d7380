"""The material library: the published fits of the MERL database as ready models.

The fitted parameters of the MERL materials (W. Matusik et al., "A data-driven
reflectance model", SIGGRAPH 2003) published by

* A. Ngan, F. Durand, W. Matusik, "Experimental analysis of BRDF models",
  EGSR 2005 (86 materials, seven models), and
* J. Löw, J. Kronander, A. Ynnerman, J. Unger, "BRDF models for accurate and
  efficient rendering of glossy surfaces", ACM TOG 31(1), 2012 (100 materials,
  fits to their error metrics E1 and E2),

as collected in the ``fits/`` folder of P. Peers' BRDF benchmark ``bbm``
(https://github.com/bsdfbenchmark/bbm, commit 9807fb3, BSD-style licence in
``data/materials/LICENSE-bbm.txt``).  One line per material, e.g.

``alum-bronze = Aggregate(Lambertian(albedo = [..]), NganWard(albedo = [..], roughness = 0.0357))``

Each fit becomes a :class:`plausible.models.sum.Sum` of a Lambertian term and
one specular part (an existing model, or a thin variant of one from
:mod:`plausible.models.published`) scaled by its RGB albedo.  What each of bbm's
model names means, and the derivation of each mapping, is in ``docs/materials.md``.

>>> import plausible
>>> m = plausible.material("alum-bronze", fit="ngan2005/ward")
>>> sorted(plausible.materials())[:2]
['alum-bronze', 'alumina-oxide']
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

import numpy as np

from ..models.ashikhmin_shirley import AshikhminShirleySpecular
from ..models.cook_torrance import CookTorrance
from ..models.he_torrance import HeTorrance
from ..models.lafortune import Lafortune
from ..models.lambert import Lambertian
from ..models.low import LowMicrofacet, LowSmooth
from ..models.published import AshikhminShirleyDielectric, CookTorranceWide, NganBlinnPhong
from ..models.sum import Sum
from ..models.ward import Ward
from ..arrays.ops import PI
from ..text import closest

NGAN = "A. Ngan, F. Durand, W. Matusik, Experimental analysis of BRDF models, EGSR 2005"
LOW = ("J. Löw, J. Kronander, A. Ynnerman, J. Unger, BRDF models for accurate and efficient "
       "rendering of glossy surfaces, ACM TOG 31(1), 2012")
SOURCE = "bbm (P. Peers), https://github.com/bsdfbenchmark/bbm, fits/, commit 9807fb3 (BSD-style licence)"


@dataclass(frozen=True)
class FitSet:
    """One published fit set: ``key`` (e.g. ``"ngan2005/ward"``), the data file,
    bbm's model name, the citation, and ``reason`` why it cannot be loaded
    (empty when it can)."""

    key: str
    file: str
    model: str
    citation: str
    description: str
    reason: str = ""

    @property
    def built(self) -> bool:
        return not self.reason


FIT_SETS = (
    FitSet("ngan2005/ashikhmin-shirley", "ngan_ashikhminshirley.fit", "NganAshikhminShirley", NGAN,
           "isotropic Ashikhmin-Shirley specular lobe, Schlick Fresnel (R0), RGB albedo; no coupled diffuse term"),
    FitSet("ngan2005/blinn-phong", "ngan_blinnphong.fit", "NganBlinnPhong", NGAN,
           "Blinn-Phong lobe rho (n+2)/(2 pi) (n.h)^n"),
    FitSet("ngan2005/cook-torrance", "ngan_cooktorrance.fit", "NganCookTorrance", NGAN,
           "Beckmann D, V-groove G, Schlick F (R0), normalised by pi: rho D G F / (pi cos_i cos_o)"),
    FitSet("ngan2005/lafortune", "ngan_lafortune.fit", "NganLafortune", NGAN,
           "one isotropic Lafortune lobe times (n+2) / (2 pi max(|Cxy|,|Cz|)^n)"),
    FitSet("ngan2005/ward", "ngan_ward.fit", "NganWard", NGAN,
           "isotropic Ward (1992), 1 / (4 pi a^2 sqrt(cos_i cos_o))"),
    FitSet("ngan2005/ward-duer", "ngan_wardduer.fit", "NganWardDuer", NGAN,
           "isotropic Ward-Dür, 1 / (4 pi a^2 cos_i cos_o)"),
    FitSet("ngan2005/he", "ngan_he.fit", "NganHe", NGAN,
           "He et al. 1991 directional diffuse (Westin's reading, real index eta, RGB wavelengths "
           "0.645/0.526/0.444 um, Beckmann's rough limit from g = 18), times an RGB albedo"),
    FitSet("low2012/ashikhmin-shirley-e1", "low_ashikhminshirley_E1.fit", "LowAshikhminShirley", LOW,
           "isotropic Ashikhmin-Shirley lobe with the exact dielectric Fresnel (index eta), metric E1"),
    FitSet("low2012/ashikhmin-shirley-e2", "low_ashikhminshirley_E2.fit", "LowAshikhminShirley", LOW,
           "isotropic Ashikhmin-Shirley lobe with the exact dielectric Fresnel (index eta), metric E2"),
    FitSet("low2012/cook-torrance-e1", "low_cooktorrance_E1.fit", "LowCookTorrance", LOW,
           "original Cook-Torrance: unnormalised Beckmann, V-groove G, dielectric F, / pi; metric E1"),
    FitSet("low2012/cook-torrance-e2", "low_cooktorrance_E2.fit", "LowCookTorrance", LOW,
           "original Cook-Torrance: unnormalised Beckmann, V-groove G, dielectric F, / pi; metric E2"),
    FitSet("low2012/microfacet-e2", "low_lowmicrofacet_E2.fit", "LowMicrofacetFit", LOW,
           "Löw et al. microfacet model A (1 + B (1 - n.h))^-C G F / (pi cos_i cos_o), metric E2"),
    FitSet("low2012/smooth-e2", "low_lowsmooth_E2.fit", "LowSmooth", LOW,
           "Löw et al. smooth-surface model A (1 + B |Ip + Op|^2)^-C F(theta_d), metric E2"),
)

#: The wavelengths (micrometres) of bbm's RGB channels (``Config::wavelength()``),
#: which its ``NganHe`` evaluates the He fits at.
NGAN_HE_WAVELENGTHS = (0.645, 0.526, 0.444)

#: The fit set used when none is named.
DEFAULT_FIT = "ngan2005/ashikhmin-shirley"


# -- parsing ------------------------------------------------------------------------

@dataclass(frozen=True)
class Term:
    """One term of a fit line: bbm's model name and its parameters (floats or lists)."""

    model: str
    params: dict


_TOKEN = re.compile(r"\s*(?:(?P<num>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)|(?P<name>[A-Za-z_]\w*)|(?P<sym>[\[\](),=]))")


def _tokens(text: str, where: str):
    pos, out = 0, []
    text = text.rstrip()
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m or m.end() == pos:
            raise ValueError(f"{where}: cannot parse {text[pos:pos + 20]!r} (column {pos + 1})")
        out.append(("num", float(m["num"])) if m["num"] else ("name", m["name"]) if m["name"]
                   else ("sym", m["sym"]))
        pos = m.end()
    return out


def _parse_value(toks, i, where):
    kind, v = toks[i]
    if kind == "num":
        return v, i + 1
    if (kind, v) == ("sym", "["):
        vals, i = [], i + 1
        while toks[i] != ("sym", "]"):
            x, i = _parse_value(toks, i, where)
            vals.append(x)
            if toks[i] == ("sym", ","):
                i += 1
        return vals, i + 1
    raise ValueError(f"{where}: expected a number or a [list], got {v!r}")


def _parse_call(toks, i, where):
    """``Name(k = v, ...)`` or ``Aggregate(call, call, ...)`` -> list of :class:`Term`."""
    kind, name = toks[i]
    if kind != "name" or toks[i + 1] != ("sym", "("):
        raise ValueError(f"{where}: expected Model(...), got {name!r}")
    i += 2
    terms, params = [], {}
    while toks[i] != ("sym", ")"):
        if toks[i][0] == "name" and toks[i + 1] == ("sym", "("):
            sub, i = _parse_call(toks, i, where)
            terms.extend(sub)
        elif toks[i][0] == "name" and toks[i + 1] == ("sym", "="):
            key = toks[i][1]
            params[key], i = _parse_value(toks, i + 2, where)
        else:
            raise ValueError(f"{where}: unexpected {toks[i][1]!r}")
        if toks[i] == ("sym", ","):
            i += 1
    i += 1
    if name == "Aggregate":
        return terms, i
    return [Term(name, params)], i


def parse_line(line: str, where: str = "fit line") -> tuple[str, tuple]:
    """``"name = Aggregate(Lambertian(albedo = [..]), Model(k = v))"`` ->
    ``(name, (Term, Term))``.  Raises :class:`ValueError` naming ``where``."""
    if "=" not in line:
        raise ValueError(f"{where}: expected 'name = Model(...)', got {line.strip()!r}")
    name, expr = line.split("=", 1)
    toks = _tokens(expr, where)
    try:
        terms, i = _parse_call(toks, 0, where)
    except IndexError:
        raise ValueError(f"{where}: unexpected end of line") from None
    if i != len(toks):
        raise ValueError(f"{where}: trailing text after the model")
    return name.strip(), tuple(terms)


@lru_cache(maxsize=None)
def fit_data(key: str) -> dict:
    """``{material name: (Term, ...)}`` of fit set ``key``, in file order."""
    fs = fit_set(key)
    text = resources.files("plausible").joinpath("data", "materials", fs.file).read_text(encoding="utf-8")
    out = {}
    for no, line in enumerate(text.splitlines(), 1):
        if not line.strip() or line.startswith("#"):
            continue
        name, terms = parse_line(line, f"{fs.file}:{no}")
        out[name] = terms
    return out


# -- lookup ---------------------------------------------------------------------------

def suggest(word: str, options) -> str:
    """``"; did you mean A, B?"`` for the options closest to ``word`` (:func:`plausible.text.closest`), else ``""``."""
    close = closest(word, options)
    return f"; did you mean {', '.join(close)}?" if close else ""


def fit_set(key: str) -> FitSet:
    """The :class:`FitSet` named ``key`` (ValueError with the closest keys otherwise)."""
    for fs in FIT_SETS:
        if fs.key == key:
            return fs
    keys = [f.key for f in FIT_SETS]
    raise ValueError(f"unknown fit {key!r}{suggest(key, keys)} (fits: {', '.join(keys)})")


def fits() -> list[FitSet]:
    """Every published fit set (loadable or not; see :attr:`FitSet.reason`)."""
    return list(FIT_SETS)


def materials(fit: str | None = None) -> dict:
    """``{material name: (fit keys...)}``: every material and the fit sets that have
    it (only ``fit`` when given), sorted by name."""
    keys = [fit_set(fit).key] if fit else [f.key for f in FIT_SETS]
    out: dict = {}
    for k in keys:
        for name in fit_data(k):
            out.setdefault(name, []).append(k)
    return {n: tuple(out[n]) for n in sorted(out)}


def terms(name: str, fit: str = DEFAULT_FIT) -> tuple:
    """The parsed terms of material ``name`` in fit set ``fit`` (no model built)."""
    data = fit_data(fit_set(fit).key)
    if name not in data:
        names = sorted(set(data) | set(materials()))
        raise ValueError(f"unknown material {name!r} in fit {fit!r}{suggest(name, names)} "
                         f"({len(data)} materials in this fit; 'plausible materials' lists them)")
    return data[name]


# -- building -------------------------------------------------------------------------

def _rgb(v, where):
    a = np.asarray(v, dtype=np.float64).ravel()
    if a.size == 1:
        return float(a[0])
    if a.size != 3:
        raise ValueError(f"{where}: expected a number or an RGB triple, got {v!r}")
    return a


def _need(term, key, where):
    if key not in term.params:
        raise ValueError(f"{where}: {term.model} lacks parameter {key!r} (has {', '.join(term.params)})")
    return term.params[key]


def build_term(term: Term, where: str = "term"):
    """A :class:`~plausible.bxdf.BxDF` part and its scale (``None`` for 1) for one
    bbm term.  The mapping of each model is derived in ``docs/materials.md``."""
    p = term.params
    g = lambda k: _need(term, k, where)  # noqa: E731
    name = term.model
    if name == "Lambertian":
        return Lambertian(rd=_rgb(g("albedo"), where)), None
    if name in ("LowMicrofacetFit", "LowSmooth"):
        abc = dict(A=_rgb(g("A"), where), B=float(g("B")), C=float(g("C")), eta=float(g("eta")))
        if name == "LowSmooth":
            return LowSmooth(**abc), None
        return LowMicrofacet(normalization="pi", **abc), None   # bbm's lowmicrofacetfit: / pi
    albedo = _rgb(g("albedo"), where)
    if name == "NganAshikhminShirley":
        n = float(g("sharpness"))
        return AshikhminShirleySpecular(nu=n, nv=n, rs=float(g("fresnelReflectance"))), albedo
    if name == "NganBlinnPhong":
        return NganBlinnPhong(ks=1.0, n=float(g("sharpness"))), albedo
    if name == "NganCookTorrance":
        # D G F / (pi cos_i cos_o) = (4 / pi) * [D G F / (4 cos_i cos_o)]
        part = CookTorrance(m=float(g("roughness")), rs=float(g("eta")), fresnel="schlick", geometry="vgroove")
        return part, albedo * (4.0 / PI)
    if name == "NganLafortune":
        cxy, cz, n = float(g("Cxy")), float(g("Cz")), float(g("sharpness"))
        c = max(abs(cxy), abs(cz))
        if c == 0:
            raise ValueError(f"{where}: Cxy and Cz are both zero")
        # rho (C.(L*V))^n (n+2) / (2 pi c^n) = (n+2)/(2 pi) ((C/c).(L*V))^n
        lobe = (cxy / c, cxy / c, cz / c, n, (n + 2.0) / (2.0 * PI))
        return Lafortune(lobes=[lobe], rd=0.0), albedo
    if name in ("NganWard", "NganWardDuer"):
        a = float(g("roughness"))
        variant = "ward" if name == "NganWard" else "duer"
        return Ward(alpha_x=a, alpha_y=a, rs=1.0, rd=0.0, variant=variant), albedo
    if name == "LowAshikhminShirley":
        return AshikhminShirleyDielectric(n=float(g("sharpness")), eta=float(g("fresnelReflectance"))), albedo
    if name == "LowCookTorrance":
        # unnormalised Beckmann (no 1/pi) over pi: D_u G F / (pi ci co) = 4 * [D G F / (4 ci co)]
        part = CookTorranceWide(m=float(g("roughness")), rs=1.0, fresnel="conductor",
                                eta=float(g("eta")), k=0.0, geometry="vgroove")
        return part, albedo * 4.0
    if name == "NganHe":
        # bbm's nganhe: he_base<fresnel::cook, errata, westin, ..., rough threshold 18> scaled by
        # its albedo (docs/materials.md: eta = 1.0 makes F exactly 0)
        part = HeTorrance(sigma0=float(g("roughness")), tau=float(g("autocorrelation")),
                          wavelength=NGAN_HE_WAVELENGTHS, fresnel="dielectric", eta=float(g("eta")),
                          rd=0.0, variant="westin", rough="beckmann")
        return part, albedo
    raise ValueError(f"{where}: bbm model {name!r} is not implemented in plausible")


def material(name: str, fit: str = DEFAULT_FIT) -> Sum:
    """The model of material ``name`` as fitted in fit set ``fit``.

    ``fit`` is a key of :func:`fits` (``"ngan2005/ashikhmin-shirley"``,
    ``"ngan2005/ward"``, ``"low2012/cook-torrance-e2"``, ...).  Returns a
    :class:`~plausible.models.sum.Sum` (Lambertian + scaled specular part) with
    RGB colours.  Unknown names raise :class:`ValueError` listing the closest
    matches; fits of models plausible does not implement raise with the reason.
    """
    fs = fit_set(fit)
    if not fs.built:
        ok = ", ".join(f.key for f in FIT_SETS if f.built)
        raise ValueError(f"fit {fs.key!r} ({fs.model}) cannot be loaded: {fs.reason} "
                         f"(see docs/materials.md). Loadable fits: {ok}")
    ts = terms(name, fs.key)
    parts = []
    for k, t in enumerate(ts):
        parts.append(build_term(t, f"{fs.file}: {name}: term {k + 1}"))
    return Sum(parts, name=f"{name}@{fs.key}", spec=f"material:{name}@{fs.key}")


def parse_spec(spec: str) -> tuple[str, str]:
    """``"material:NAME@FIT"`` (or ``"NAME@FIT"``, ``"NAME"``) -> ``(NAME, FIT)``;
    also ``material:name=NAME:fit=FIT``."""
    body = spec.split(":", 1)[1] if spec.startswith("material:") else spec
    if "=" in body:
        kv = {}
        for item in body.split(":"):
            if "=" not in item:
                raise ValueError(f"material spec {spec!r}: expected name=NAME:fit=FIT or NAME@FIT")
            k, v = item.split("=", 1)
            kv[k.strip()] = v.strip()
        unknown = set(kv) - {"name", "fit"}
        if unknown or "name" not in kv:
            raise ValueError(f"material spec {spec!r}: parameters are 'name' and 'fit' "
                             f"(got {', '.join(sorted(kv))})")
        return kv["name"], kv.get("fit", DEFAULT_FIT)
    name, _, fit = body.partition("@")
    if not name.strip():
        raise ValueError(f"material spec {spec!r}: expected material:NAME@FIT, e.g. "
                         f"material:alum-bronze@{DEFAULT_FIT}")
    return name.strip(), (fit.strip() or DEFAULT_FIT)


def spec(name: str, fit: str = DEFAULT_FIT) -> str:
    """``"material:NAME@FIT"``, the spec that :func:`parse_spec` reads back."""
    return f"material:{name}@{fit}"


def from_spec(spec: str) -> Sum:
    """:func:`material` of ``"material:NAME@FIT"`` (see :func:`parse_spec`)."""
    return material(*parse_spec(spec))


__all__ = ["DEFAULT_FIT", "FIT_SETS", "FitSet", "Term", "build_term", "fit_data", "fit_set", "fits",
           "from_spec", "material", "materials", "parse_line", "parse_spec", "spec", "terms"]
