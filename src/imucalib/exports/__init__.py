"""Outputs in one place: every file a calibration or a recording is written to.

Contents
--------
:mod:`imucalib.exports.outputs`
    :func:`write_outputs`: a procedure result → its named output files (result JSON, report
    JSON, parameters CSV, intrinsics, reports, and the formats its procedure writes itself:
    Allan's noise YAML, P2's temperature figure) in a folder; :data:`OUTPUT_FORMATS`.
:mod:`imucalib.exports.report`
    :func:`build_report`, :func:`build_summary_report`: the calibration report of a result (a
    batch's summary), its content made by the result's procedure (found in the registry).
:mod:`imucalib.exports.streams`
    :func:`export_csv`, :func:`export_mat`: a stream of a Recording (or a step of it) as CSV or
    MAT.
:mod:`imucalib.exports.c_runtime`
    :func:`write_c_runtime`: a calibration as a C99 parameter header plus the runtime library
    that applies it in firmware (docs/c-runtime.md).

Each is imported from its module (this package imports nothing eagerly).
"""
