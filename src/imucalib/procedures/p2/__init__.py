"""Procedure P2: array full-temperature calibration (docs/p2.md).

Modules: ``plan`` (the plan generator), ``observations`` (window means per unit),
``reduction`` (the closed form and the least squares of one temperature point), ``analysis``
(temperature models, the result and the decision of one unit), ``batch`` (every unit, on local
cores or a Dask cluster), ``procedure`` (the registered object).
"""
