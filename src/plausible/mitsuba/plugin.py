"""The plugin class: a thin ``mi.BSDF`` around a model's hooks.

A plugin class has to be made after the Mitsuba variant is set, hence the
factory :func:`make_plugin_class`; what its methods do is written as functions
of this module and of :mod:`plausible.mitsuba.props`, which can be read and
tested alone:

* :func:`bsdf_flags` -- Mitsuba's flags and components from what the model
  declares (its lobes, :meth:`plausible.bxdf.BxDF.components`, one component
  each; else :attr:`plausible.bxdf.BxDF.LOBES`), the isotropy probe
  :func:`plausible.analysis.is_isotropic`, the textures and the registry's
  ``reciprocal``;
* the plugin's ``eval``, ``pdf`` and ``sample`` compose the lobes that the
  ``BSDFContext`` enables (:func:`plausible.bxdf.mixture_f`, ``mixture_pdf``,
  ``mixture_sample``); ``eval_diffuse_reflectance`` sums the diffuse lobes'
  albedos; in polarized variants every value is a depolarizer;
* :func:`mitsuba_progress` -- long computations at load reported in Mitsuba's log;
* :func:`array_safe` -- can the model's sampler take a per-point value of a
  parameter (a dry run);
* :func:`traversable` -- how each parameter appears in ``mi.traverse``
  (a Dr.Jit array and its flags);
* :class:`ParamState` -- the plugin's parameters: textures, the traversed
  arrays, the NumPy model built from them (which checks every range and
  constraint) and the values the hooks receive at a shading point.

A plugin's life: ``__init__`` reads the properties (:func:`props.read_param`),
checks the textures (:func:`props.check_texture`, :func:`props.check_pointwise`)
and builds the model; ``parameters_changed`` (after ``params.update()``) does
the same again from the traversed values, and restores the previous values if
the new ones are refused.
"""

from __future__ import annotations

import time
from types import SimpleNamespace

import numpy as np

from .. import progress, registry, vec
from ..integrals.albedo import is_isotropic
from ..bxdf import add_values, mixture_f, mixture_pdf, mixture_sample
from . import props as P


def lobe_kinds(lobe) -> frozenset:
    """The kinds of a :class:`plausible.bxdf.Lobe` (``"diffuse"``, ``"glossy"``) as a set."""
    return frozenset({lobe.kind}) if isinstance(lobe.kind, str) else frozenset(lobe.kind)


def bsdf_flags(mi, model, info, varying: bool, isotropic: bool | None = None):
    """``(flags, components, sampled)`` of a model, as pbrt's ``BxDF::Flags()``
    and Mitsuba's ``m_components``: one component per lobe of
    :meth:`plausible.bxdf.BxDF.components`, in order.

    A component is ``DiffuseReflection`` and/or ``GlossyReflection`` from its
    lobe's kind, ``FrontSide``; ``Anisotropic`` (glossy components) where
    :func:`~plausible.analysis.is_isotropic` says the value changes as both
    directions rotate about the normal; ``SpatiallyVarying`` for varying
    textures; ``NonSymmetric`` for non-reciprocal models.  ``flags`` is their
    union; ``sampled[k]`` the type a sample of component ``k`` reports:
    ``GlossyReflection``, or ``DiffuseReflection`` for a purely diffuse lobe.
    ``isotropic``: the probe's answer where the caller has it already.
    """
    F = mi.BSDFFlags
    common = F.FrontSide
    if varying:
        common |= F.SpatiallyVarying
    if not info.reciprocal:
        common |= F.NonSymmetric
    aniso = not (is_isotropic(model) if isotropic is None else isotropic)
    components, sampled = [], []
    for lobe in model.components():
        kinds = lobe_kinds(lobe)
        c = common
        if "diffuse" in kinds:
            c |= F.DiffuseReflection
        if "glossy" in kinds:
            c |= F.GlossyReflection
            if aniso:
                c |= F.Anisotropic
        components.append(c)
        sampled.append(F.GlossyReflection if "glossy" in kinds else F.DiffuseReflection)
    flags = components[0]
    for c in components[1:]:
        flags |= c
    return flags, components, sampled


def lobe_types(mi, model) -> list:
    """Per component of :func:`bsdf_flags`: the list of its lobe's types
    (``DiffuseReflection``, ``GlossyReflection``), what ``BSDFContext.is_enabled``
    is asked about."""
    F = mi.BSDFFlags
    table = {"diffuse": F.DiffuseReflection, "glossy": F.GlossyReflection}
    return [[table[k] for k in sorted(lobe_kinds(lobe))] for lobe in model.components()]


def array_safe(mi, model, name: str) -> bool:
    """Can the sampling hooks take a per-point (array) value of ``q.name``?

    A hook may use a Python ``if`` on a sampling parameter (allowed for plain
    floats, e.g. Modified Phong's lobe-choice probability); then that
    parameter is sampled with its texture's mean (still unbiased: ``pdf`` and
    ``sample`` use the same ``q``).  Checked with a dry run on two-element arrays.
    """
    from ..arrays.ops import drjit_ops

    if not _dr().is_array_v(mi.Float):
        return False  # a scalar variant: one value per call, never an array
    ops = drjit_ops(mi.Float)
    q = dict(vars(model.q))
    q[name] = mi.Float([0.4, 0.6]) * float(q[name] or 1.0)
    qn = SimpleNamespace(**q)
    w = (mi.Float([0.1, 0.2]), mi.Float([0.0, 0.1]), mi.Float([0.9, 0.95]))
    try:
        model._pdf(ops, w, w, qn)
        model._sample(ops, w, w, qn)
    except Exception:  # noqa: BLE001 - any failure means "not array-safe"
        return False
    return True


def traversable(mi, prm, value):
    """``(array, flags)`` under which a non-texture parameter appears in
    ``mi.traverse``, or None (:meth:`Param.traversal <plausible.params.Param.traversal>`
    says how: a nested model spec or an open choice do not appear):

    * continuous scalars and grey colours: ``mi.Float`` of width 1, differentiable;
    * integers: ``mi.UInt32``; choices: ``mi.UInt32``, the index in ``prm.choices``;
    * structured values (Lafortune's lobes): ``mi.Float``, the numbers row by row;

    the last three non-differentiable.
    """
    t = prm.traversal(value)
    if t is None:
        return None
    numbers, integer, differentiable = t
    nd = mi.ParamFlags.NonDifferentiable
    if integer:
        return mi.UInt32(numbers), nd
    if not differentiable:
        return mi.Float(numbers), nd
    if not _dr().is_array_v(mi.Float):  # a scalar variant: a Python float
        return mi.Float(numbers), mi.ParamFlags.Differentiable
    return _dr().opaque(mi.Float, numbers), mi.ParamFlags.Differentiable


def untraverse(prm, array, template):
    """The Python value of a traversed array (inverse of :func:`traversable`;
    :meth:`Param.from_traversal <plausible.params.Param.from_traversal>`)."""
    return prm.from_traversal(np.array(array, dtype=np.float64).ravel(), template)


def mitsuba_progress(mi, plugin: str):
    """A :mod:`plausible.progress` factory that reports through Mitsuba's log: a
    long computation at load (``pumped_up``'s albedo tables, 17.6 s cold for an
    anisotropic base) is announced once at ``Warn`` (Mitsuba's default level
    shows it) with where its result is cached, then every 10 % at ``Info``."""
    from ..integrals.cache import table_cache_dir

    def factory(total: int, label: str = ""):
        cache = table_cache_dir()
        where = (f"cached on disk in {cache}; PLAUSIBLE_CACHE_DIR moves the cache, "
                 f"PLAUSIBLE_CACHE_DIR='' turns it off" if cache else "the disk cache is off")
        mi.Log(mi.LogLevel.Warn, f"{plugin}: computing {label or 'a table'} once "
                                 f"({total} steps; {where})")
        state = {"done": 0, "next": 0.1, "t0": time.perf_counter()}

        def tick(n: int = 1) -> None:
            state["done"] += n
            frac = state["done"] / max(total, 1)
            if frac >= state["next"] - 1e-12:
                mi.Log(mi.LogLevel.Info, f"{plugin}: {label} {100 * frac:.0f} % "
                                         f"({time.perf_counter() - state['t0']:.1f} s)")
                state["next"] = (int(frac * 10 + 1e-9) + 1) / 10
        return tick

    return factory


def channel_mean(c):
    """Mean over the channels of a Mitsuba Spectrum / Color3f (a Float)."""
    total = c[0]
    for i in range(1, len(c)):
        total = total + c[i]
    return total * (1.0 / len(c))


class ParamState:
    """The parameters of one plugin instance (see the module docstring).

    ``textures``: name -> Mitsuba texture; ``arrays``: name -> traversed Dr.Jit
    array (with ``flags``); ``fixed``: values never traversed (a model spec);
    ``given``: the parameters the scene set; ``model``: the NumPy model built
    from the current values (textures at their clamped mean).
    """

    def __init__(self, mi, plugin, info, props, alias, log=None, make=None, ignore=(), warn=None):
        self.mi, self.plugin, self.info = mi, plugin, info
        self.log = log
        self.warn = warn if warn is not None else (lambda text: mi.Log(mi.LogLevel.Warn, text))
        self.make = make if make is not None else info.cls
        keys = [k for k in props.keys() if k not in ignore]
        material = props["material"] if "material" in props else None
        if material is not None:
            P.check_material(plugin, info, keys)
        converted = P.converted_values(plugin, props, keys)
        conv_keys = [k for k in keys if k in P.CONVERTED.get(plugin, {})]
        keys = [k for k in keys if k not in conv_keys]
        self.given = P.given_names(plugin, info, keys, alias)
        for name in converted:
            if name in self.given:
                raise ValueError(f"{plugin}: parameter {name!r} given twice (as {self.given[name]!r} "
                                 f"and as {', '.join(conv_keys)}; converted names)")
            self.given[name] = "+".join(conv_keys)
        self.textures, values = {}, {}
        for prm in info.params:
            key = self.given.get(prm.name)
            if prm.name in converted:
                v = prm.validate(converted[prm.name], plugin)
            else:
                v = prm.default if key is None else P.read_param(mi, prm, props, key, plugin)
            if isinstance(v, mi.Object):
                self.textures[prm.name] = v
            elif isinstance(v, np.ndarray) and prm.is_color:
                self.textures[prm.name] = P.srgb(mi, v, bool(prm.hi > 1.0))
            else:
                values[prm.name] = v
        if material is not None:
            self.textures.update(P.metal_textures(mi, material, plugin))
            if "fresnel" in values and "fresnel" not in self.given and \
                    "conductor" in info.param("fresnel").choices:
                values["fresnel"] = "conductor"
                self.given["fresnel"] = "material"
        for name in self.textures:
            values.pop(name, None)
        self.derived = {k for k, v in values.items()
                        if v is None and k in info.cls.DERIVED and k not in self.given}
        self.warned, self.warnings = set(), []
        # what params.update() changed (None: everything, as at load); textures' means; the
        # last pointwise check's inputs
        self.dirty, self.means, self.pointwise_key, self._iso = None, {}, None, (None, None)
        self.known = {k: self._check_texture(k) for k in self.textures}
        self.arrays, self.flags, self.fixed = {}, {}, {}
        for name, v in values.items():
            t = None if name in self.derived or v is None else traversable(mi, info.param(name), v)
            if t is None:
                self.fixed[name] = v
            else:
                self.arrays[name], self.flags[name] = t
        self.templates = dict(values)
        self.exact = {n: (values[n], np.array(a)) for n, a in self.arrays.items()}
        self.q_opaque = ()
        self.build()
        self.varying = [k for k, t in self.textures.items() if P.texture_varies(t)]
        # sampling constants that may change (traversed arrays, constant textures such as
        # <rgb>) and that the sampler takes as arrays: opaque, so a new value is kernel data
        changing = [k for k, f in self.flags.items() if f == mi.ParamFlags.Differentiable]
        changing += [k for k in self.textures if k not in self.varying and k in self.q_const]
        self.q_opaque = [k for k in changing if array_safe(mi, self.model, k)]
        self._set_sampling()
        self.q_varying = [k for k in self.varying if array_safe(mi, self.model, k)]
        for k in set(self.varying) - set(self.q_varying):
            self._log(f"{plugin}: sampling uses the mean of texture {k!r} (the model's "
                      f"sampler is not array-safe in it)")
        self.fast = FastUpdate(self)

    def _log(self, text):
        if self.log is not None:
            self.log(text)

    def _check_texture(self, name) -> bool:
        """Is the texture of ``name`` known to lie in the range (else it is clamped per
        shading point)?  A texture with texels outside is warned about once per plugin
        (:func:`props.range_warning`; ``warnings`` keeps the texts)."""
        prm, tex = self.info.param(name), self.textures[name]
        found = P.check_texture(self.mi, self.plugin, prm, tex)
        text = P.range_warning(self.plugin, prm, tex, found, self.given.get(name))
        if text is not None and id(tex) not in self.warned:  # one texture, one warning (Ward's alpha)
            self.warned.add(id(tex))
            self.warnings.append(text)
            self.warn(text)
        elif not found.total:
            self._log(f"{self.plugin}: the range of texture {name!r} cannot be read; "
                      f"it is clamped to {prm.range_text()} per shading point")
        return found.known

    def values(self) -> dict:
        """The current Python value of every non-texture parameter: the value last
        accepted while its traversed array still holds it (so a float64 value the
        scene gave is not rounded to the array's float32, which could push a
        constraint such as ``kd + ks <= 1`` over its bound), else the array's."""
        out = dict(self.fixed)
        for name, a in self.arrays.items():
            prm = self.info.param(name)
            value, image = self.exact.get(name, (None, None))
            if image is not None and self.dirty is not None and name not in self.dirty:
                out[name] = value  # not among the parameters params.update() changed: not read back
            elif image is not None and np.array_equal(np.asarray(a), image):
                out[name] = value
            else:
                out[name] = prm.validate(untraverse(prm, a, self.templates[name]), self.plugin)
        return out

    def build(self):
        """Build the NumPy model from the current values (every range and
        constraint checked by the model), the textures' pointwise constraints,
        and what the hooks need (``q``, flags)."""
        vals, consts, no_mean = self._consts()
        with progress.reporting(progress.ambient() or mitsuba_progress(self.mi, self.plugin)):
            model = self._make_without_means(consts, no_mean)
        known = {k: t for k, t in self.textures.items() if self.known[k] and P.texture_varies(t)}
        if known and P.has_constraints(self.info):
            base = {k: v for k, v in consts.items() if k not in known}
            # again only where a textured value or another parameter changed (1.4 s for a 256^2 map)
            key = (sorted(known), repr(sorted(base.items())))
            if self.dirty is None or set(known) & self.dirty or key != self.pointwise_key:
                pts = P.values_at_uv(self.mi, self.info, known, P.uv_grid(self.mi, known.values()))
                P.check_pointwise(self.plugin, self.info, base, pts, warn=self._log)
            self.pointwise_key = key
        self._set_model(model, vals)
        self.m_flags, self.components, self.sampled_types = bsdf_flags(
            self.mi, model, self.info, any(P.texture_varies(t) for t in self.textures.values()),
            self._isotropic(model, consts))
        self.lobe_types = lobe_types(self.mi, model)

    def _set_model(self, model, vals):
        """Keep ``model`` (built from ``vals``), the values to restore if a later update
        is refused, and the sampling constants."""
        changing = model.for_changing_data()  # a new value compiles nothing (He-Torrance: every term)
        self._model, self.pending = (model if changing is None else changing), {}
        self.accepted = {k: np.array(a) for k, a in self.arrays.items()}  # restored if refused
        self.exact = {k: (vals[k], self.accepted[k]) for k in self.arrays}
        self._set_sampling()

    @property
    def model(self):
        """The NumPy model of the current values.  After updates that took the fast path
        (:class:`FastUpdate`, which builds none) it is built here, when first asked for;
        the plugin's hooks run on :attr:`hooks` instead."""
        if self.pending:
            self.dirty = set()  # every value the fast path took is in ``exact`` and ``means``
            vals, consts, no_mean = self._consts()
            self._set_model(self._make_without_means(consts, no_mean), vals)
        return self._model

    @model.setter
    def model(self, model):
        self._model, self.pending = model, {}

    @property
    def hooks(self):
        """The model whose hooks the plugin calls: the last one built.  The fast path
        changes only values the hooks read from ``p`` and ``q`` (kernel data), never
        the model's structure, so this model serves them unchanged."""
        return self._model

    def _consts(self):
        """``(values, constants, textures without a mean)``: :meth:`values`, with each
        texture's mean clamped into its range (read again where ``dirty``)."""
        vals = self.values()
        consts = {k: v for k, v in vals.items() if v is not None}
        no_mean = []
        for name, tex in self.textures.items():
            prm = self.info.param(name)
            if self.dirty is None or name in self.dirty or name not in self.means:
                self.means[name] = P.texture_mean(tex)
            mean = self.means[name]
            if mean is None:
                no_mean.append(name)
                continue
            consts[name] = min(max(mean, prm.lo), prm.hi)
        return vals, consts, no_mean

    def _isotropic(self, model, consts) -> bool:
        """:func:`~plausible.analysis.is_isotropic` of ``model`` (the probe: two NumPy
        evaluations of 96 pairs, 2-3 ms, most of a ``params.update()``), probed again only
        when what can change it changed: a scalar parameter, or whether a colour is zero (a
        colour scales a lobe: at zero an anisotropic lobe vanishes).  A new colour of an
        optimisation step reuses the answer."""
        key = tuple(sorted((k, bool(np.all(np.asarray(v) == 0)) if self.info.param(k).is_color else repr(v))
                           for k, v in consts.items()))
        if self._iso[0] != key:
            self._iso = (key, is_isotropic(model))
        return self._iso[1]

    def describe(self) -> str:
        """The parameters as the scene gave them: numbers as values, a texture as
        its class and name (``rd=BitmapTexture('wood.jpg')``), never its mean."""
        from ..text import fmt

        vals = self.values()
        parts = []
        for prm in self.info.params:
            if prm.name in self.textures:
                parts.append(f"{prm.name}={P.texture_label(self.textures[prm.name])}")
            elif prm.name in vals and vals[prm.name] is not None:
                parts.append(f"{prm.name}={fmt(vals[prm.name], other=repr)}")
        return f"{type(self.model).__name__}({', '.join(parts)})"

    def _make_without_means(self, consts, no_mean):
        """The NumPy model, with each texture that has no mean (``mesh_attribute``)
        standing for its parameter's default, or the bottom of its range where the
        default breaks a constraint with the other values.  That value serves only
        the model's constants (flags, the sampling constants of a sampler that is
        not array-safe in it): at a shading point the texture is evaluated and
        clamped to the range."""
        for name in no_mean:
            prm = self.info.param(name)
            d = prm.default
            consts[name] = float(np.mean(d)) if d is not None else prm.lo
        try:
            return self.make(**consts)
        except ValueError:
            if not no_mean:
                raise
        for name in no_mean:
            consts[name] = float(self.info.param(name).lo)
        return self.make(**consts)

    def _set_sampling(self):
        """The sampling constants ``q`` of the model.  Those of :attr:`q_opaque` are
        read from the current values when the hooks are traced (:meth:`q`), so a new
        value is kernel data and compiles nothing."""
        self.q_const = dict(vars(self._model.q))

    def changed(self, keys) -> bool:
        """After ``params.update()`` of the parameters ``keys`` (Mitsuba passes the names
        that changed; none: all): the fast path where it applies (:class:`FastUpdate`;
        returns False: nothing else changed), else check the textures among them,
        rebuild, or restore the previous values and raise if the new ones are refused
        (returns True: the flags may have changed)."""
        if keys and self.fast.take(keys):
            return False
        self.dirty = set(keys) if keys else None
        for k, a in self.arrays.items():
            if (not keys or k in keys) and self.flags[k] == self.mi.ParamFlags.Differentiable:
                _dr().make_opaque(a)  # as Mitsuba's own plugins: a literal given is kernel data
        for k in [k for k in self.textures if k in keys or not keys]:  # the textures that changed
            try:
                self.known[k] = self._check_texture(k)
            except ValueError as err:
                # a texture cannot be given back its old data: it is clamped from now on
                self.known[k] = False
                raise ValueError(f"{err} (params.update() refused; the texture is clamped to "
                                 f"the range per shading point)") from None
        try:
            self.build()
        except ValueError as err:
            for k, a in self.accepted.items():
                self.mi.set_property(self.arrays[k], type(self.arrays[k])(a))
            raise ValueError(f"{err} (params.update() refused; the previous values are kept)") from None
        return True

    # -- the values the hooks receive --------------------------------------------------
    def p(self, si):
        """Every parameter at the shading point ``si``: textures evaluated (scalars
        as the channel mean of ``eval``, since Mitsuba 3.9's ``checkerboard.eval_1``
        swaps its colours), clamped to the range where it is not known; the
        traversed arrays as they are (so derivatives flow); derived values."""
        mi, dr = self.mi, _dr()
        vals = dict(self._model.params)
        for name, a in self.arrays.items():
            if self.flags[name] == mi.ParamFlags.Differentiable:
                vals[name] = a
        for name, tex in self.textures.items():
            prm = self.info.param(name)
            v = tex.eval(si) if prm.is_color else channel_mean(tex.eval(si))
            if not self.known[name]:
                v = dr.clip(v, max(prm.lo, -1e30), min(prm.hi, 1e30))
            vals[name] = v
        ns = SimpleNamespace(**vals)
        for name in self.derived:
            setattr(ns, name, self.info.cls.DERIVED[name](ns))
        return ns

    def q(self, si):
        """The sampling parameters at ``si`` (channel means, detached; per point where
        the sampler is array-safe, the model's constants otherwise): the traversed
        numbers and constant textures of :attr:`q_opaque` as they are now (kernel data,
        not literals), varying textures at ``si``."""
        dr = _dr()
        vals = dict(self.q_const)
        for k in self.q_opaque:
            if k in self.arrays:
                vals[k] = dr.detach(self.arrays[k])
                continue
            v = channel_mean(dr.detach(self.textures[k].eval(si)))
            if not self.known[k]:
                prm = self.info.param(k)
                v = dr.clip(v, max(prm.lo, -1e30), min(prm.hi, 1e30))
            vals[k] = v
        for k in self.q_varying:
            v = channel_mean(self.textures[k].eval(si))
            if not self.known[k]:
                prm = self.info.param(k)
                v = _dr().clip(v, max(prm.lo, -1e30), min(prm.hi, 1e30))
            vals[k] = v
        return SimpleNamespace(**vals)


class FastUpdate:
    """The fast path of ``params.update()`` (issue 43): a new value that is kernel data
    only, taken in a few microseconds, without a NumPy model, ``mi.traverse`` or a new
    Dr.Jit object, so that an update costs what a built-in's does (``roughplastic``'s
    colour: 12 us; docs/benchmarks.md).

    What may take it (``names``): the traversed differentiable numbers and the constant
    textures (``<rgb>``, :func:`props.constant_reader`) whose sampling constants the
    hooks read as they are (:attr:`ParamState.q_opaque`), of a model whose traced code
    depends on its values only through ``p`` and ``q`` (the contract of
    :mod:`plausible.kernel_params`; :meth:`~plausible.bxdf.BxDF.for_changing_data`
    returns the model itself: He-Torrance's copy that sums every term does), unless the
    model has constraints between parameters and textures checked point by point.

    An update takes it (:meth:`take`) when every new value lies in its range (a colour:
    every channel, its texture in range before), no colour becomes or stops being zero,
    a scalar cannot change the ``Anisotropic`` flag (the model is isotropic at a generic
    point of its scalars, so at every one; or the flag is set already, and stays set),
    and the model's constraints hold (:meth:`~plausible.bxdf.BxDF.check_constraints`).
    Anything else takes the full path of :meth:`ParamState.changed`, which gives the
    errors, warnings and clamping."""

    def __init__(self, state):
        self.state = state
        model, F = state.hooks, state.mi.ParamFlags
        data_only = model.for_changing_data() is model
        pointwise = P.has_constraints(state.info) and any(state.known[k] for k in state.varying)
        readers = {k: P.constant_reader(state.mi, state.textures[k]) for k in state.q_opaque
                   if k in state.textures}
        self.readers = {k: r for k, r in readers.items() if r is not None}
        numbers = {k for k in state.q_opaque if k in state.arrays and state.flags[k] == F.Differentiable}
        self.names = frozenset(numbers | set(self.readers)) if data_only and not pointwise else frozenset()
        params = {k: state.info.param(k) for k in self.names}
        self.ranges = {k: (prm.lo, prm.hi) for k, prm in params.items()}
        self.colors = {k for k, prm in params.items() if prm.is_color}
        self.scalars = self.names - self.colors
        self.constrained = P.has_constraints(state.info)
        self.aniso = state.mi.BSDFFlags.Anisotropic
        self.make_opaque = _dr().make_opaque
        self.iso_free = bool(self.scalars) and self._isotropic_anywhere()
        self._sync()

    def _sync(self):
        """After a model was built: whether each colour is zero now (the isotropy
        probe's key, :meth:`ParamState._isotropic`)."""
        model = self.state.hooks
        self.seen = model
        self.zero = {k: bool(np.all(np.asarray(model.params[k]) == 0)) for k in self.colors}

    def _isotropic_anywhere(self) -> bool:
        """Is the model isotropic at a generic point of its scalars (each moved by its own
        factor inside its range)?  Then no value of them makes it anisotropic."""
        model = self.state.hooks
        moved = {}
        for i, k in enumerate(sorted(self.scalars)):
            (lo, hi), v = self.ranges[k], float(model.params[k])
            moved[k] = min(max(v * (1.137 + 0.211 * i) + 0.013 * (i + 1), lo), hi)
        try:
            return is_isotropic(model) and is_isotropic(model.replace(**moved))
        except ValueError:
            return False

    def take(self, keys) -> bool:
        """Take the new values of ``keys`` if all may (see the class); True if taken.
        Written for the fewest Python calls (a dozen; the count is what
        ``tests/mitsuba/test_update_cost.py`` holds against a built-in's)."""
        st = self.state
        if not self.names.issuperset(keys):
            return False
        if st._model is not self.seen:
            self._sync()
        new, images = {}, {}
        for k in keys:
            lo, hi = self.ranges[k]
            if k in self.readers:
                if not st.known[k]:
                    return False  # clamped before: the full path checks it again
                c = self.readers[k]()
                for x in c:
                    if not lo <= x <= hi:  # outside, or NaN: the full path warns or refuses
                        return False
                v = sum(c) / len(c)
            else:
                v = st.arrays[k][0]
                if not lo <= v <= hi:
                    return False
                images[k] = v
            if k in self.colors:
                if (v == 0) != self.zero[k]:
                    return False
            elif not (self.iso_free or st.m_flags & self.aniso):
                return False
            new[k] = v
        if self.constrained and not self._constraints_hold(new):
            return False
        for k, v in images.items():
            st.exact[k] = (v, np.array((v,), dtype=np.float32))
            st.accepted[k] = st.exact[k][1]
            self.make_opaque(st.arrays[k])  # a literal given (mi.Float(0.4)) is kernel data too
        for k in self.colors.intersection(new):
            self.zero[k] = new[k] == 0
            if k in self.readers:
                st.means[k] = new[k]
        st.pending.update(new)
        return True

    def _constraints_hold(self, new) -> bool:
        """The model's constraints between parameters at the new values: checked on the
        values alone (:meth:`~plausible.bxdf.BxDF.check_constraints`), or by building the
        model where one of its values is derived from others (Neumann's ``c``)."""
        st = self.state
        values = dict(st._model._params)
        values.update(st.pending)
        values.update(new)
        try:
            if st.derived:
                st.make(**{k: v for k, v in values.items() if k not in st.derived})
            else:
                type(st._model).check_constraints(values)
        except ValueError:
            return False  # the full path refuses the value with the model's own message
        return True


def _dr():
    import drjit as dr

    return dr


def _lobe_methods(mi, dr):
    """The plugin's direction bookkeeping over the model's lobes (a ``mi.BSDF``
    subclass of the current variant; :func:`make_plugin_class` derives from it)."""
    from ..arrays.ops import drjit_ops

    class PlausibleLobes(mi.BSDF):
        # -- direction bookkeeping ---------------------------------------------------
        @staticmethod
        def _split(v):
            return (v.x, v.y, v.z)

        def _enabled(self, ctx):
            """Per component: does ``ctx`` ask for it (``type_mask`` and ``component``,
            Mitsuba's ``BSDFContext.is_enabled`` with the lobe's type, as
            ``roughplastic`` asks; a lobe of both kinds where either is asked
            for)?  A Python list (the context is not traced)."""
            return [any(ctx.is_enabled(t, k) for t in kinds) for k, kinds in enumerate(self.state.lobe_types)]

        @staticmethod
        def _unpolarized(v):
            """A value of the model (a Float, or a tuple of channels) as Mitsuba's
            ``UnpolarizedSpectrum``.  In the monochrome variants (``llvm_ad_mono``,
            ``*_mono_polarized``) three channels (an RGB colour held as numbers or a
            ``Color3f``: a published fit, a MERL table) become their luminance, ``mi.luminance``
            (Rec. 709 weights), as Mitsuba's own ``srgb`` texture evaluates there."""
            if mi.is_monochromatic and (isinstance(v, mi.Color3f) or isinstance(v, tuple) and len(v) == 3):
                v = mi.luminance(v if isinstance(v, mi.Color3f) else mi.Color3f(*v))
            return mi.UnpolarizedSpectrum(*v) if isinstance(v, tuple) else mi.UnpolarizedSpectrum(v)

        @staticmethod
        def _spectrum(v):
            """A value of the model as Mitsuba's ``Spectrum``; in the polarized
            variants a depolarizer (only ``M00``), as Mitsuba's ``diffuse`` and
            ``roughplastic`` return: the models have no polarization."""
            s = v if isinstance(v, mi.UnpolarizedSpectrum) else PlausibleLobes._unpolarized(v)
            return mi.depolarizer(s) if mi.is_polarized else s

        def _value(self, ctx, si, wo_c, enabled):
            """``f(light, view) cos(theta_o)`` of the enabled lobes (unpolarized);
            plausible's ``wi`` (light) is Mitsuba's ``wo`` in Radiance mode and
            ``si.wi`` in Importance mode."""
            ops = drjit_ops(mi.Float)
            wi_c = self._split(si.wi)
            light, view = (wi_c, wo_c) if ctx.mode == mi.TransportMode.Importance else (wo_c, wi_c)
            f = mixture_f(ops, self.state.hooks, light, view, self.state.p(si), enabled, components=True)
            return self._unpolarized(f) * dr.maximum(wo_c[2], 0.0)

    return PlausibleLobes


def _interface_methods(mi, dr, base):
    """Mitsuba's BSDF interface (``eval``, ``pdf``, ``sample``, the diffuse
    reflectance) on the bookkeeping of ``base`` (:func:`_lobe_methods`)."""
    from ..arrays.ops import drjit_ops

    class PlausibleInterface(base):
        # -- the BSDF interface ------------------------------------------------------
        def eval(self, ctx, si, wo, active=True):
            enabled = self._enabled(ctx)
            if not any(enabled):
                return self._spectrum(dr.zeros(mi.Float, dr.width(wo)))
            ok = active & (si.wi.z > 0) & (wo.z > 0)
            return self._spectrum(dr.select(ok, self._value(ctx, si, self._split(wo), enabled), 0.0))

        def _pdf(self, ctx, si, wo_c, q, enabled):
            ops = drjit_ops(mi.Float)
            return mi.Float(mixture_pdf(ops, self.state.hooks, self._split(si.wi), wo_c, q, enabled, components=True))

        def pdf(self, ctx, si, wo, active=True):
            enabled = self._enabled(ctx)
            if not any(enabled):
                return dr.zeros(mi.Float, dr.width(wo))
            ok = active & (si.wi.z > 0) & (wo.z > 0)
            return dr.select(ok, self._pdf(ctx, si, self._split(wo), self.state.q(si), enabled), 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            ops = drjit_ops(mi.Float)
            enabled = self._enabled(ctx)
            bs = dr.zeros(mi.BSDFSample3f)
            if not any(enabled):
                return bs, self._spectrum(dr.zeros(mi.Float, dr.width(sample1)))
            q = self.state.q(si)
            wi_c = self._split(si.wi)
            wo_c, k = mixture_sample(ops, self.state.hooks, wi_c, (mi.Float(sample1), sample2.x, sample2.y), q, enabled,
                                     components=True)
            # by division: the stored wo is the wo its pdf sees (vec.normalize, CUDA's contraction)
            wo_c = vec.normalize(ops, tuple(mi.Float(c) for c in wo_c), divide=True)
            pdf = self._pdf(ctx, si, wo_c, q, enabled)
            ok = active & (pdf > 0) & (wo_c[2] > 0) & (si.wi.z > 0)
            bs.wo = mi.Vector3f(*wo_c)
            bs.pdf = dr.select(ok, pdf, 0.0)
            bs.eta = 1.0
            bs.sampled_component = mi.UInt32(k)
            types = self.state.sampled_types
            sampled = mi.UInt32(int(types[0]))
            for j in range(1, len(types)):
                sampled = dr.select(bs.sampled_component == j, mi.UInt32(int(types[j])), sampled)
            bs.sampled_type = sampled
            value = self._value(ctx, si, wo_c, enabled)
            return bs, self._spectrum(dr.select(ok, value / dr.select(ok, pdf, 1.0), 0.0))

        def eval_diffuse_reflectance(self, si, active=True):
            """The albedo of the diffuse lobes at ``si.wi`` (their declared
            :attr:`plausible.bxdf.Lobe.albedo`: ``rd``, ``kd``; Ashikhmin-Shirley's
            coupled term ``rd (1 - rs) (1 - (1 - cos/2)^5)``), as ``diffuse`` and
            ``roughplastic`` return their reflectance (the ``aov`` integrator's
            ``albedo``).  On a back face (``si.wi.z < 0``) the albedo of ``si.wi``
            mirrored to the front, as ``diffuse`` returns its reflectance on either
            side.  A model without a diffuse lobe: Mitsuba's default,
            ``pi eval(wo = n)``, as ``roughconductor`` (0 on a back face)."""
            ops = drjit_ops(mi.Float)
            albedos = [lb.albedo for lb in self.state.hooks.components() if lb.albedo is not None]
            if not albedos:
                n = mi.Vector3f(0.0, 0.0, 1.0)
                return self.eval(mi.BSDFContext(), si, n, active) * dr.pi
            p = self.state.p(si)
            wi_c = (si.wi.x, si.wi.y, dr.abs(si.wi.z))
            total = add_values([a(ops, wi_c, p) for a in albedos])
            return self._spectrum(dr.select(active, self._unpolarized(total), 0.0))

    return PlausibleInterface


def make_plugin_class(plugin: str, model_name: str, info=None):
    """A ``mitsuba.BSDF`` subclass wrapping the registered model ``model_name``
    (or the model described by ``info``, a :class:`plausible.params.ModelInfo`)."""
    import drjit as dr
    import mitsuba as mi

    info = info if info is not None else registry.info(model_name)
    alias = P.aliases_for(plugin, info)

    def log(text):
        mi.Log(mi.LogLevel.Debug, text)

    class PlausibleBSDF(_interface_methods(mi, dr, _lobe_methods(mi, dr))):
        INFO = info
        ALIASES = alias
        PLUGIN = plugin

        #: properties read by a subclass itself (not model parameters)
        EXTRA_PROPS: tuple = ()

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.state = ParamState(mi, plugin, info, props, alias, log,
                                    make=self._model_factory(props), ignore=self.EXTRA_PROPS)
            self._set_flags()

        def _model_factory(self, props):
            """``function(**params) -> model``; None: the registry's class."""
            return None

        def _set_flags(self):
            self.m_flags = self.state.m_flags
            self.m_components = list(self.state.components)
            self.anisotropic = bool(self.state.m_flags & mi.BSDFFlags.Anisotropic)

        @property
        def model(self):
            return self.state.model

        # -- parameters ---------------------------------------------------------------
        def traverse(self, callback):
            for k, tex in self.state.textures.items():
                callback.put(k, tex, mi.ParamFlags.Differentiable)
            for k, a in self.state.arrays.items():
                if isinstance(a, (int, float)):
                    continue  # a scalar variant: Mitsuba can only write Dr.Jit types
                callback.put(k, a, self.state.flags[k])

        def parameters_changed(self, keys=()):
            if self.state.changed(keys):
                self._set_flags()

        def to_string(self):
            return f"{plugin}[plausible model {model_name!r}: {self.state.describe()}]"

    PlausibleBSDF.__name__ = "Plausible_" + plugin
    PlausibleBSDF.__qualname__ = PlausibleBSDF.__name__
    return PlausibleBSDF


def make_merl_class():
    """The ``merl`` plugin: a measured BRDF in the MERL binary format
    (:class:`plausible.models.merl.MerlBRDF`, nearest-cell lookup, cosine
    sampling) read from ``<string name="filename" value="..."/>``.  RGB variants
    only (the table holds red, green and blue)."""
    import mitsuba as mi

    from ..models.merl import MerlBRDF, read_merl
    from ..params import ModelInfo

    info = ModelInfo(name="merl", cls=MerlBRDF, params=(), reciprocal=True, energy_conserving=False,
                     description="measured isotropic BRDF, MERL binary format (Matusik et al. 2003)",
                     references=("Matusik, Pfister, Brand, McMillan, 'A data-driven reflectance "
                                 "model', SIGGRAPH 2003",))
    base = make_plugin_class("merl", "merl", info)

    class MerlBSDF(base):
        EXTRA_PROPS = ("filename",)

        def _model_factory(self, props):
            if "filename" not in props:
                raise ValueError("merl: the parameter 'filename' (a MERL .binary file) is required")
            if mi.is_spectral:
                raise ValueError(f"merl: a MERL table holds RGB values; use an RGB variant, "
                                 f"not {mi.variant()!r}")
            model = read_merl(str(props["filename"]))
            return lambda **params: model

        def to_string(self):
            return f"merl[{self.model.source!r}]"

    MerlBSDF.__name__ = MerlBSDF.__qualname__ = "Plausible_merl"
    return MerlBSDF


__all__ = ["make_plugin_class", "make_merl_class", "bsdf_flags", "lobe_types", "lobe_kinds", "array_safe", "traversable", "untraverse",
           "channel_mean", "mitsuba_progress", "ParamState", "FastUpdate"]
