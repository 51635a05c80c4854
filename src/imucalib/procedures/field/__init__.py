"""Field calibration by hand, without equipment (docs/field.md).

:mod:`.plan` (the guided session), :mod:`.observations` (log → static poses and rotations),
:mod:`.analysis` (the fits), :mod:`.result` (the triad model and the report),
:mod:`.procedure` (the registered ``"field"`` procedure).
"""
