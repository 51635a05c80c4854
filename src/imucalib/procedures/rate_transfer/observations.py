"""The rate-transfer test's observations: the whole-revolution gyro means of every turn.

The turns are reduced by :mod:`~imucalib.procedures.common.rate_windows` (docs/rate-transfer.md,
"Observations"), shared with the installation test; its names are re-exported here.

Contents
--------
:class:`RateProcessing`, :class:`RateWindow`, :func:`extract_rate_windows`, :func:`pooled_se`
"""

from __future__ import annotations

from imucalib.procedures.common.rate_windows import (
    RateProcessing,
    RateWindow,
    extract_rate_windows,
    pooled_se,
)

__all__ = ["RateProcessing", "RateWindow", "extract_rate_windows", "pooled_se"]
