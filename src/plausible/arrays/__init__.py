"""The array floor: the namespaces the one math is written against.

* :mod:`.ops` -- ``NP`` (NumPy) and ``drjit_ops(Float)`` (Dr.Jit), the
  component-wise operations every formula takes as ``ops``;
* :mod:`.symbolic` -- ``SYM``, which records what a model's hooks compute as an
  expression graph (printed as GLSL by :mod:`plausible.export`);
* :mod:`.backend` -- the dispatcher that picks NumPy or Dr.Jit for a call
  (``plausible.use_backend``, ``PLAUSIBLE_BACKEND``) and the Dr.Jit kernels of
  the front end and of the quadrature.

Nothing here imports the contract, the models or anything above them.
"""
