"""Integrals of the contract: the floor between the contract and the models' users.

* :mod:`.quadrature` -- the panel rules and the frames about a lobe (mirror
  direction, half vector) that refine toward a sharp peak;
* :mod:`.albedo` -- directional albedo with an error bound, albedo curves and
  tables, pdf integrals, the isotropy probe.

They use only the contract (:mod:`plausible.bxdf`), the backends and the
vector math, so a model defined by an integral of another (``pumped-up``)
may import them; :mod:`plausible.analysis` builds its checks on them and
publishes them (``plausible.albedo``, ``plausible.analysis.albedo_curve``, ...).
"""
