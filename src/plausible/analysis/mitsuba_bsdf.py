"""The contract around a ``mitsuba.BSDF`` (any plugin; Mitsuba is imported lazily).

Conventions, Mitsuba 3 to :mod:`plausible.bxdf`:

* **Directions.**  Mitsuba's BSDF methods take ``si.wi`` (the direction the
  path arrived from, in the local shading frame) and ``wo``; both point away
  from the surface, as plausible's do.  The contract here is
  ``eval(wi, wo)`` with plausible's ``wi = si.wi`` and ``wo = wo``: ``sample(wi, u)``
  is Mitsuba's ``sample(ctx, si, u[0], u[1:])`` from ``si.wi``, ``pdf`` is Mitsuba's
  ``pdf``, so the sampling checks test exactly what Mitsuba's integrators use.
* **Cosine.**  Mitsuba's ``eval`` is ``f cos(theta_o)``; the contract's ``eval`` is
  ``f``: the value is divided by ``cos(theta_o)`` (of the float32 direction
  Mitsuba saw, so the division undoes the multiplication to the last bit).
  Mitsuba's sample weight ``f cos / pdf`` is the contract's weight as it is.
* **Transport modes.**  ``BSDFContext.mode``: in ``Radiance`` (path tracing)
  ``si.wi`` points to the camera, so the contract's ``f(wi, wo)`` is the BRDF of
  light arriving from ``wo`` seen from ``wi`` and its albedo is what a path
  tracer's throughput averages; in ``Importance`` (light tracing) ``si.wi`` is the
  light side and the albedo is the reflected fraction of the incident energy.  A
  mode-consistent plugin has ``f_radiance(a, b) = f_importance(b, a)``; the two
  differ only for a non-reciprocal BSDF.  Both are probed; where they differ
  both are checked (:meth:`MitsubaBSDF.views`).
* **Components.**  ``BSDFContext.type_mask`` selects the smooth reflection lobes
  (``DiffuseReflection | GlossyReflection``) when the plugin has others: delta
  lobes (``conductor``, ``plastic``'s coating, ``dielectric``) have no density
  and are excluded from the integrals; their reflectance is measured by sampling
  them alone and reported, added to the smooth albedo (``energy+delta``).
  Transmission lobes are excluded: the reflection hemisphere is checked, and the
  report says transmission was not.
* **Sides.**  Mitsuba's one-sided plugins reflect only above the shading normal.
  A plugin with a reflecting ``BackSide`` component (``twosided``) is checked on
  the back too (directions mirrored through the surface, ``z -> -z``), unless the
  back gives the same values as the front.
* **Precision.**  The RGB and mono LLVM/CUDA variants compute in float32 (no
  double-precision variant is installed with the ``mitsuba`` wheels), so one
  ``eval`` of a smooth lobe is good to about ``1e-7`` relative (``2^-24 = 6e-8``
  per operation; measured asymmetry of ``diffuse`` and ``roughconductor``:
  1.1e-7), but a direction is itself rounded to float32, and a sharp lobe's value
  moves by much more over one ulp of its direction: the sampler of
  ``roughconductor`` (alpha 0.01) at 89 degrees reports a pdf 3.3e-4 away from
  ``pdf()`` at the direction it returned (it computes the pdf from the microfacet
  normal, ``pdf()`` from the half vector of the rounded direction), and
  ``principled`` is asymmetric by 2.1e-5 at grazing.  The adapter declares
  ``precision = 1e-4``; :func:`plausible.analysis.adapters.tolerances` derives
  reciprocity ``<= 1e-4`` and sampling ``<= 1e-3`` from it (a deliberate defect,
  a pdf 10% off or an asymmetric lobe, is 100 times larger).  Every integral is
  summed in float64.  Directions returned by Mitsuba's sampler are kept as
  float32 gave them (not renormalised), so that ``pdf(wi, wo)`` of a sampled
  ``wo`` sees the same bits.  Spectral and polarized variants are refused (their values depend on
  the sampled wavelengths, or are Mueller matrices); use ``llvm_ad_rgb``.
"""

from __future__ import annotations

import contextlib
import math

import numpy as np

from ..arrays.backend import aligned
from ..bxdf import Sample
from ..directions import CHUNK, check_block, as_array, check_directions, norm2
from ..mitsuba.variant import VARIANTS, ensure_variant
from ..vec import HORIZON
from .foreign import ForeignBxDF

__all__ = ["MitsubaBSDF", "load_bsdf_dict", "load_bsdf_xml"]

#: Relative precision declared for a float32 Mitsuba variant (see the module docstring):
#: float32 rounds a direction by 2^-24 relative, and a sharp lobe's value moves by far more
#: than that over one ulp (the pdf of roughconductor alpha 0.01 at 89 degrees: the sampler's
#: pdf and pdf() at the sampled direction differ by 3.3e-4; principled's f(a, b) and f(b, a)
#: by 2.1e-5 at grazing).
FLOAT32_PRECISION = 1e-4

#: The variant set when none is (:func:`plausible.mitsuba.ensure_variant`): LLVM, RGB, float32.
DEFAULT_VARIANT = VARIANTS[0]

#: Incidence angles (degrees) of the delta-lobe reflectance of a purely specular plugin.
DELTA_THETAS = (0, 10, 20, 30, 40, 50, 60, 70, 75, 80, 85, 88, 89, 89.5, 89.9)


def load_bsdf_dict(d: dict):
    """``mi.load_dict(d)`` as a BSDF (sets the variant if none is); ValueError if it is not one."""
    mi = ensure_variant()
    if not isinstance(d, dict) or "type" not in d:
        raise ValueError(f"d must be a dict with a 'type', as mi.load_dict takes it; got {d!r}")
    try:
        obj = mi.load_dict(d)
    except Exception as e:  # Mitsuba raises RuntimeError or its own exceptions with the plugin's message
        raise ValueError(f"mi.load_dict({d}) failed: {str(e).strip().splitlines()[-1]}") from None
    if not isinstance(obj, mi.BSDF):
        raise ValueError(f"{d.get('type')!r} is a Mitsuba {type(obj).__name__}, not a BSDF")
    return obj


def load_bsdf_xml(path: str, id: str | None = None):
    """The BSDF with ``id`` in the Mitsuba XML file ``path``: the file's root if it is
    a ``<bsdf>``, else a shape's BSDF of that id, else the ``<bsdf id=...>`` element
    loaded on its own.  ValueError naming the ids found when there is none."""
    import xml.etree.ElementTree as ET

    mi = ensure_variant()
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise ValueError(f"{path}: {e}") from None
    ids = [el.get("id") for el in root.iter("bsdf") if el.get("id")]
    if root.tag == "bsdf" and (id is None or root.get("id") == id):
        try:
            return mi.load_file(path)
        except Exception as e:      # Mitsuba's parser: a missing version attribute, an unknown plugin, ...
            raise ValueError(f"{path}: Mitsuba cannot load it: {str(e).strip().splitlines()[-1]}") from None
    if id is None:
        raise ValueError(f"{path}: the root is not a <bsdf> and no id was given; BSDF ids in the file: "
                         f"{', '.join(ids) or 'none'}")
    el = next((e for e in root.iter("bsdf") if e.get("id") == id), None)
    if el is None:
        raise ValueError(f"{path}: no <bsdf id={id!r}>; BSDF ids in the file: {', '.join(ids) or 'none'}")
    try:   # load the scene, so that defaults, references and textures resolve as Mitsuba resolves them
        scene = mi.load_file(path)
        for shape in scene.shapes():
            b = shape.bsdf()
            if b is not None and b.id() == id:
                return b
    except Exception:  # a scene that does not load on its own (missing meshes): load the element alone
        pass
    el.set("version", root.get("version", "3.0.0"))
    try:
        return mi.load_string(ET.tostring(el, encoding="unicode"))
    except Exception as e:
        raise ValueError(f"{path}, id {id!r}: {str(e).strip().splitlines()[-1]}") from None


def _flags(mi, bsdf):
    F = mi.BSDFFlags
    comps = [int(bsdf.flags(i)) for i in range(bsdf.component_count())] or [int(bsdf.flags())]
    smooth = int(F.DiffuseReflection | F.GlossyReflection)
    delta = int(F.DeltaReflection) | int(F.Delta1D) & int(F.Reflection)
    trans = int(F.Transmission) | int(F.Null)
    return comps, smooth, delta, trans


def _rows(dr, v) -> np.ndarray:
    """A Mitsuba value (``Float``, ``Color3f``, ``Vector3f``) as a NumPy array ``(components, n)``,
    read component by component after one ``dr.eval``: ``.numpy()`` of a nested array launches
    a copy kernel with its size as a literal, compiled again for every new number of directions
    (mitsuba-builtins compiled 422 kernels, most of them these copies)."""
    if not hasattr(v, "numpy"):
        return np.asarray(v).reshape(1, -1)
    if dr.depth_v(v) <= 1:
        return np.asarray(v.numpy()).reshape(1, -1)
    dr.eval(v)
    return np.stack([np.asarray(c.numpy()) for c in v])


@contextlib.contextmanager
def device_exact(mi, dr):
    """Dr.Jit's ``FastMath`` off inside the block on a CUDA variant: Dr.Jit then emits IEEE
    division and square root (``div.rn``, ``sqrt.rn``) instead of ``div.approx.ftz``/
    ``sqrt.approx.ftz``, so that the analysis measures the BSDF, not the device's approximate
    arithmetic (on an H200 Mitsuba's GGX roughconductor read 5e-4 relative asymmetry with fast
    math, 1e-7 as on LLVM without it; ../shared/gpu/README.md).  Nothing changes on LLVM, whose
    kernels keep their cache."""
    if not str(mi.variant()).startswith("cuda"):
        yield
        return
    was = dr.flag(dr.JitFlag.FastMath)
    dr.set_flag(dr.JitFlag.FastMath, False)
    try:
        yield
    finally:
        dr.set_flag(dr.JitFlag.FastMath, was)


class MitsubaBSDF(ForeignBxDF):
    """The contract of :mod:`plausible.bxdf` around a ``mitsuba.BSDF`` (see the module docstring).

    ``mode``: ``"radiance"`` or ``"importance"``; ``side``: ``"front"`` or ``"back"``;
    ``uv``: the surface point at which textures are evaluated; ``params``: shown in
    the report (e.g. the dict the plugin was loaded from).  Raises ValueError for a
    BSDF that does not reflect at all, or a spectral / polarized variant.
    """

    def __init__(self, bsdf, *, mode: str = "radiance", side: str = "front", uv=(0.5, 0.5),
                 params: dict | None = None, name: str | None = None):
        import drjit as dr
        import mitsuba as mi

        self._mi, self._dr, self.bsdf = mi, dr, bsdf
        if mode not in ("radiance", "importance"):
            raise ValueError(f"mode must be 'radiance' or 'importance', got {mode!r}")
        if side not in ("front", "back"):
            raise ValueError(f"side must be 'front' or 'back', got {side!r}")
        if mi.is_spectral or mi.is_polarized:
            raise ValueError(f"Mitsuba variant {mi.variant()} is spectral or polarized: the checks need "
                             f"RGB or mono values; set {DEFAULT_VARIANT} before loading the BSDF")
        self.mode, self.side, self.uv = mode, side, tuple(float(x) for x in uv)
        self.plugin = name or str(bsdf).splitlines()[0].split("[", 1)[0].strip(" :") or type(bsdf).__name__
        self.params = dict(params) if params is not None else _traverse_params(mi, bsdf)
        self.precision = FLOAT32_PRECISION   # every installed variant is float32, scalar_rgb too
        comps, smooth, delta, trans = _flags(mi, bsdf)
        self.declares_flags = any(comps)
        has = lambda bits: [i for i, c in enumerate(comps) if c & bits]  # noqa: E731
        self.smooth_components = has(smooth) if self.declares_flags else [0]
        self.delta_components = has(delta)
        self.transmission_components = has(trans)
        if not self.smooth_components and not self.delta_components:
            raise ValueError(f"{self.plugin}: not a reflective BSDF (component flags "
                             f"{[_flag_names(mi, c) for c in comps]}): nothing to check on the reflection "
                             "hemisphere")
        back = int(mi.BSDFFlags.BackSide)
        self.has_back = any(c & back and c & (smooth | delta) for c in comps)
        self.mask = smooth if (self.delta_components or self.transmission_components) else None
        self.channels = self._probe_channels()
        self.not_applicable = {}
        if not self.smooth_components:
            why = "only delta lobes: nothing to integrate (their reflectance is reported as energy+delta)"
            self.not_applicable = dict(reciprocity=why, energy=why, sampling=why, chi2=why)
        self.notes = self._notes(comps)
        # the declared anisotropy (is_isotropic's probe compares at float64 precision, and float32
        # rounding would make every plugin look anisotropic); a plugin that hides its anisotropy
        # is checked at azimuth 0 only
        if self.declares_flags:
            self.isotropic = not int(bsdf.flags()) & int(mi.BSDFFlags.Anisotropic)

    @property
    def name(self):
        tags = [] if (self.mode, self.side) == ("radiance", "front") else [self.mode, self.side]
        return f"mitsuba:{self.plugin}" + (f" [{', '.join(tags)}]" if tags else "")

    def __repr__(self):
        return f"MitsubaBSDF({self.plugin}, mode={self.mode}, side={self.side})"

    # -- Mitsuba calls ----------------------------------------------------------------------
    def _ctx(self, mask=None):
        mi = self._mi
        ctx = mi.BSDFContext(mi.TransportMode.Radiance if self.mode == "radiance" else mi.TransportMode.Importance)
        m = self.mask if mask is None else mask
        if m is not None:
            ctx.type_mask = m
        return ctx

    def _si(self, wi32):
        mi, dr = self._mi, self._dr
        si = dr.zeros(mi.SurfaceInteraction3f, wi32.shape[1])
        si.wi = mi.Vector3f(wi32[0], wi32[1], wi32[2])
        si.uv = mi.Point2f(*self.uv)
        return si

    def _local(self, w):
        """plausible's local directions, rows ``(n, 3)`` -> the ones Mitsuba sees: float32,
        mirrored for the back side, as contiguous components ``(3, n)`` (one conversion,
        from which Dr.Jit copies each component without a strided gather)."""
        w = aligned(np.asarray(w).T, np.float32)     # each component on its own aligned row
        if self.side == "back":
            w[2] = -w[2]
        return w

    def _vec(self, w32):
        return self._mi.Vector3f(w32[0], w32[1], w32[2])

    def _spectrum(self, v, n, scale=None):
        """Mitsuba's value read back once, as float64 rows ``(n,)`` or ``(n, channels)``,
        divided by ``scale`` (shape ``(n,)``) if given (in float64: the float32 values
        convert exactly, so this is the division of their float64 copies)."""
        a = _rows(self._dr, v).reshape(-1, n)
        a = a.T if a.shape[0] > 1 else a[0]
        if scale is None:
            return a.astype(np.float64)
        return np.divide(a, scale[:, None] if a.ndim == 2 else scale, dtype=np.float64)

    def _probe_channels(self):
        v = self._mi_eval(np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.0, 1.0]]))
        return v.shape[1] if v.ndim == 2 else None

    def _mi_eval(self, a, b):
        wi, wo = self._local(a), self._local(b)
        with device_exact(self._mi, self._dr):
            v = self.bsdf.eval(self._ctx(), self._si(wi), self._vec(wo))
            return self._spectrum(v, len(a), np.abs(wo[2].astype(np.float64)))

    def _mi_pdf(self, a, b):
        wi, wo = self._local(a), self._local(b)
        with device_exact(self._mi, self._dr):
            return np.asarray(self.bsdf.pdf(self._ctx(), self._si(wi), self._vec(wo)).numpy(), dtype=np.float64)

    # -- the contract --------------------------------------------------------------------------
    _reads_rows_only = True   # _local converts the rows to float32 (a copy)

    def _directions(self, name, w):
        return _as_float32_directions(name, w)

    def _value(self, a, b):
        return self._mi_eval(a, b)

    def _density(self, a, b):
        return self._mi_pdf(a, b)

    def sample(self, wi, u, mask=None) -> Sample:
        mi = self._mi
        a, uu, shape = self._sample_rows(wi, u)
        uu = aligned(np.minimum(uu, 1 - 2.0 ** -24).T, np.float32)   # components (3, n)
        tail = (self.channels,) if self.channels else ()
        wo = np.zeros((len(a), 3))
        wo[:, 2] = -1.0
        weight = np.zeros((len(a),) + tail)
        pdf = np.zeros(len(a))
        for s in range(0, len(a), CHUNK):
            e = min(s + CHUNK, len(a))
            wi32 = self._local(a[s:e])
            with device_exact(mi, self._dr):
                bs, w = self.bsdf.sample(self._ctx(mask), self._si(wi32), mi.Float(uu[0, s:e]),
                                         mi.Point2f(uu[1, s:e], uu[2, s:e]))
                self._dr.eval(bs.wo, bs.pdf, w)     # one kernel for the three (each .numpy() would launch its own)
            o = _rows(self._dr, bs.wo).astype(np.float64).T
            if self.side == "back":
                o[:, 2] = -o[:, 2]
            # Mitsuba's float32 direction as it is (|wo| = 1 +- 1e-7): renormalising it in float64
            # would move it by up to an ulp when it is rounded again, and the pdf of a sharp lobe
            # (alpha 0.01 at 89 degrees) changes by 1e-3 over one ulp
            nrm = np.linalg.norm(o, axis=-1)
            good = np.isfinite(nrm) & (nrm > 0)
            o = np.where(good[:, None], _unit32(o, nrm), np.array([0.0, 0.0, -1.0]))
            p = np.asarray(bs.pdf.numpy(), dtype=np.float64)
            ww = self._spectrum(w, e - s)
            ok = good & (o[:, 2] > HORIZON) & (a[s:e, 2] > HORIZON) & (p > 0)
            wo[s:e] = o
            pdf[s:e] = np.where(ok, p, 0.0)
            weight[s:e] = np.where(ok[:, None] if tail else ok, ww, 0.0)
        return Sample(wo.reshape(shape + (3,)), weight.reshape(shape + tail), pdf.reshape(shape))

    # -- beyond the contract: views, notes, delta lobes -------------------------------------------
    def with_(self, **kw):
        """The same BSDF under another ``mode`` / ``side``."""
        args = dict(mode=self.mode, side=self.side, uv=self.uv, params=self.params, name=self.plugin)
        args.update(kw)
        return MitsubaBSDF(self.bsdf, **args)

    def views(self) -> list:
        """``[(label, contract), ...]``: importance transport and the back side, each
        where it gives values that differ from the radiance front (probed on 256
        random pairs, relative ``10 * precision``)."""
        out = []
        if not self.smooth_components:
            return out
        imp = self.with_(mode="importance")
        if not _same(self, imp, self.precision):
            out.append(("importance", imp))
        if self.has_back:
            back = self.with_(side="back")
            if not _reflects(back):
                self.notes.append("back side: declared, but eval is 0 there (nothing reflected): not checked")
            elif not _same(self, back, self.precision):
                out.append(("back", back))
                imp_b = back.with_(mode="importance")
                if not _same(back, imp_b, self.precision):
                    out.append(("back, importance", imp_b))
        return out

    def _notes(self, comps):
        mi = self._mi
        n = [f"Mitsuba {mi.__version__} plugin {self.plugin!r}, variant {mi.variant()} (float32): "
             f"declared precision {self.precision:g}, so reciprocity tolerance {self.precision:g} and "
             f"sampling tolerance {max(1e-6, 10 * self.precision):g}; f = eval / cos(theta_o); "
             f"wi = si.wi ({self.mode} transport, {self.side} side)"]
        if not self.declares_flags:
            n.append("the plugin declares no flags: treated as one smooth reflection lobe")
        if self.delta_components:
            n.append(f"delta lobes (components {self.delta_components}) excluded from the integrals; their "
                     "reflectance is added to the smooth albedo in energy+delta")
        if self.transmission_components:
            n.append(f"transmission (components {self.transmission_components}) NOT checked: reflection "
                     "hemisphere only")
        return n

    def delta_reflectance(self, wi, n: int = 64) -> np.ndarray:
        """Reflectance of the delta lobes alone at ``wi`` (3,): the mean sample weight
        with only the delta reflection lobes enabled (a delta lobe's weight is its
        reflectance; ``n`` uniform numbers average over a stochastic lobe choice)."""
        if not self.delta_components:
            return np.zeros(self.channels) if self.channels else 0.0
        F = self._mi.BSDFFlags
        rng = np.random.default_rng(11)
        s = self.sample(np.broadcast_to(np.asarray(wi, float), (n, 3)), rng.random((n, 3)),
                        mask=int(F.DeltaReflection) | (int(F.Delta1D) & int(F.Reflection)))
        return s.weight.mean(axis=0)

    def annotate(self, report):
        """Add ``energy+delta`` (delta reflectance plus the smooth albedo of the
        ``energy`` grid; max over it <= 1 + 1e-4) when the plugin has delta lobes."""
        from ..integrals.albedo import direction
        from .checks import PropertyResult

        if not self.delta_components or (self.mode, self.side) != ("radiance", "front"):
            return
        try:
            grid = [(g["theta_deg"], g["phi_deg"], g["albedo"]) for g in report["energy"].details["grid"]]
        except (KeyError, TypeError):
            grid = [(t, 0.0, 0.0) for t in DELTA_THETAS]
        rows = []
        for t, p, a in grid:
            d = float(np.max(np.atleast_1d(self.delta_reflectance(direction(math.radians(t), math.radians(p))))))
            rows.append(dict(theta_deg=t, phi_deg=p, smooth=a, delta=d, total=a + d))
        w = max(rows, key=lambda r: r["total"])
        report.results.append(PropertyResult(
            "energy+delta", w["total"] <= 1 + 1e-4, w["total"], "<= 1 + 0.0001 (smooth albedo + delta reflectance)",
            dict(theta_i_deg=w["theta_deg"], phi_i_deg=w["phi_deg"], smooth=w["smooth"], delta=w["delta"]),
            dict(grid=rows)))


#: Directions whose length is within this of 1 are passed to Mitsuba as they are (rounded
#: to float32), not renormalised: float32 cannot tell them from unit vectors (2^-22).
UNIT_SLACK = 2.0 ** -20


def _unit32(w, nrm):
    """``w / |w|`` except where ``|w|`` is within :data:`UNIT_SLACK` of 1 (then ``w``;
    ``w`` itself, no copy, when every row is)."""
    near = np.abs(nrm - 1.0) <= UNIT_SLACK
    if np.all(near):
        return w
    return np.where(near[..., None], w, w / np.where(nrm > 0, nrm, 1.0)[..., None])


def _as_float32_directions(name, w):
    """Validated directions (as :func:`plausible.directions.as_directions`), normalised only
    where they are not unit vectors to float32 precision: a direction the adapter
    returned from Mitsuba's sampler goes back to Mitsuba with the same bits."""
    a = as_array(name, w)
    if a.size <= 3 * CHUNK:   # one pass: the check's |a|^2 is the norm's (norm2 is np.sum(a * a, -1) bitwise)
        s = check_block(name, a)
    else:
        check_directions(name, a)
        s = norm2(a)
    return _unit32(a, np.sqrt(s))


def _flag_names(mi, bits: int) -> str:
    """``'DiffuseReflection|FrontSide'`` for the single-bit BSDFFlags set in ``bits``."""
    names = [k for k in ("Null", "DiffuseReflection", "DiffuseTransmission", "GlossyReflection", "GlossyTransmission",
                         "DeltaReflection", "DeltaTransmission", "Anisotropic", "SpatiallyVarying", "NonSymmetric",
                         "FrontSide", "BackSide") if bits & int(getattr(mi.BSDFFlags, k))]
    return "|".join(names) or "none"


def _probe_pairs(n: int = 256):
    rng = np.random.default_rng(5)
    d = rng.normal(size=(2, n, 3))
    d[..., 2] = np.abs(d[..., 2]) + 0.05
    return d


def _reflects(a) -> bool:
    d = _probe_pairs()
    return bool(np.any(a.eval(d[0], d[1]) != 0))


def _same(a, b, precision) -> bool:
    d = _probe_pairs()
    fa, fb = a.eval(d[0], d[1]), b.eval(d[0], d[1])
    scale = np.maximum(np.abs(fa), np.abs(fb))
    return bool(np.all(np.abs(fa - fb) <= 10 * precision * scale + 1e-12 * (np.max(scale) + 1e-300)))


def _traverse_params(mi, bsdf) -> dict:
    """Small parameters of ``bsdf`` (``mi.traverse``), as floats or lists, for the report."""
    out = {}
    try:
        for k, v in mi.traverse(bsdf).items():
            try:
                a = np.asarray(v.numpy() if hasattr(v, "numpy") else v, dtype=np.float64).ravel()
            except (TypeError, ValueError):
                continue
            if 0 < a.size <= 3:
                out[k] = float(a[0]) if a.size == 1 else [float(x) for x in a]
    except Exception:  # a Python plugin without traverse(): no parameters to show
        pass
    return out
