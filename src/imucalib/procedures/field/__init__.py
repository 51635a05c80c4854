"""Field calibration by hand, without equipment (docs/field.md).

:mod:`.plan` (the guided session), :mod:`.analysis` (the fits, on the static poses and
rotations of :mod:`imucalib.procedures.common.static_intervals`), :mod:`.accel_model` (the
accelerometer's form and terms, chosen by the poses), :mod:`.rotations` (the gyro from the
rotations), :mod:`.result` (the triad model and the report), :mod:`.procedure` (the
registered ``"field"`` procedure).
"""
