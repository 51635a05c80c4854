"""The accelerometer multi-position tumble (IEEE Std 1293), registered as ``"tumble"``.

docs/tumble.md. :mod:`.plan` (:func:`~imucalib.procedures.tumble.plan.generate_tumble_plan`),
:mod:`.observations` (records → means and body-frame gravity), :mod:`.fourier` (the Fourier
reduction, the inversion and identifiability, Eqs. (T.1)–(T.9)), :mod:`.analysis`
(:func:`~imucalib.procedures.tumble.analysis.analyze_tumble`), :mod:`.procedure` (the registry's
``tumble``).
"""
