"""What every procedure shares: the procedure protocol and the generic analysis steps.

Contents
--------
:mod:`~imucalib.procedures.common.procedure`
    :class:`Procedure` and :class:`ProcedureResult`, the protocols a procedure folder implements.

Each module is imported from its own path (this package imports nothing eagerly).
"""
