"""Models, one module per family.  Every module here is imported by the registry,
so adding a model means adding one module (plus its tests).

Imports in a model module go at the top, NumPy included (a required dependency;
the NumPy-only code of a model, ``peak_directions`` and ``_validate``, uses it
directly); only optional dependencies are imported where they are used."""
