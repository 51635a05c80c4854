"""Procedure P3: accelerometer K2 on a centrifuge with dynamic-unbalance compensation.

docs/p3.md. :mod:`.plan` (:func:`~imucalib.procedures.p3.plan.generate_p3_plan`),
:mod:`.observations` (records → means), :mod:`.roundrobin` (the reduction, Eqs. (P3.1)–(P3.4)),
:mod:`.analysis` (:func:`~imucalib.procedures.p3.analysis.analyze_p3`), :mod:`.procedure` (the
registry's ``p3``).
"""
