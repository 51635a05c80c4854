"""A one-axis gyro scale-factor test for imucalib, packaged as a plug-in procedure.

The distribution declares the entry point ``scale-factor`` in the group
``imucalib.procedures``; imucalib finds it there (imucalib's docs/plugins.md).

Contents
--------
:mod:`imucalib_scale_factor.options`
    :class:`~imucalib_scale_factor.options.ScaleFactorPlanOptions`, the plan's keywords.
:mod:`imucalib_scale_factor.roles`
    The procedure's name and step roles (:data:`~imucalib_scale_factor.roles.ROLES`).
:mod:`imucalib_scale_factor.plan`
    :func:`~imucalib_scale_factor.plan.generate_scale_factor_plan`.
:mod:`imucalib_scale_factor.analysis`
    :func:`~imucalib_scale_factor.analysis.analyze_scale_factor`,
    :func:`~imucalib_scale_factor.analysis.fit_scale_factor`,
    :class:`~imucalib_scale_factor.analysis.ScaleFactorResult`.
:mod:`imucalib_scale_factor.procedure`
    :data:`~imucalib_scale_factor.procedure.PROCEDURE`, the object the entry point names.
"""

__version__ = "0.1.0"
