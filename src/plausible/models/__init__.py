"""Models, one module per family.  Every module here is imported by the registry,
so adding a model means adding one module (plus its tests)."""
