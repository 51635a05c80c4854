"""What every procedure shares: the procedure protocol and the generic analysis steps.

Contents
--------
:mod:`~imucalib.procedures.common.procedure`
    :class:`Procedure` and :class:`ProcedureResult`, the protocols a procedure folder implements.
:mod:`~imucalib.procedures.common.reference`
    Reference inputs: table angles → gravity and angular rate in the body frame, Earth rate and
    g at the site.
:mod:`~imucalib.procedures.common.windows`
    Statistics of a valid window: running moments of a long window, the scatter about the
    once-per-revolution harmonic.
:mod:`~imucalib.procedures.common.noise`
    The noise model of window means (:func:`estimate_noise`, :func:`window_mean_se`).
:mod:`~imucalib.procedures.common.design`
    :func:`build_design`: the triad design per observation and model term.

Each module is imported from its own path (this package imports nothing eagerly).
"""
