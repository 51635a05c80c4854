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
:mod:`~imucalib.procedures.common.static_windows`
    Static window means of all six IMU channels with their reference inputs.
:mod:`~imucalib.procedures.common.drift_model`
    The gyro drift model D0 + D·f on static windows and its generalised least-squares fit
    (g-sensitivity, random drift; docs/g-sensitivity.md).
:mod:`~imucalib.procedures.common.static_positions`
    Plan parts of the static-position tests: the positions, their steps, the dual-axis twin.
:mod:`~imucalib.procedures.common.grade`
    The grades a plan accepts and their default warm-up (:func:`check_grade`).
:mod:`~imucalib.procedures.common.rate_windows`
    Rate windows: the whole-revolution gyro means of every turn on a rate table
    (rate transfer, installation; docs/rate-transfer.md).
:mod:`~imucalib.procedures.common.rate_table_plan`
    Plan parts of the turn tests on a single-axis rate table: rates, remounts, turns, the twin.

What two procedures share lives here; a procedure folder never imports another
(``tests/test_architecture.py``).

Each module is imported from its own path (this package imports nothing eagerly).
"""
