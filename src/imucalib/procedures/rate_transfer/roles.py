"""The rate-transfer test's step roles (``rate-transfer.<purpose>``, docs/rate-transfer.md).

Gyro scale factor on a single-axis rate table; every step after a remount carries the tag
``axis=<x|y|z>`` (the body axis up, along the table's spin axis), the turns also
``rate=<°/s>``.

:data:`RATE_TRANSFER_REMOUNT` ``"rate-transfer.remount"``
    The operator places the unit with another axis up (``remount``).
:data:`RATE_TRANSFER_RATE` ``"rate-transfer.rate"``
    A turn over whole revolutions (``commanded`` gives ``rate_dps`` and ``revolutions``).

Contents
--------
:data:`ROLES` (role → what it is for), the role constants above.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

__all__ = ["RATE_TRANSFER_RATE", "RATE_TRANSFER_REMOUNT", "ROLES"]

RATE_TRANSFER_REMOUNT: Final = "rate-transfer.remount"
RATE_TRANSFER_RATE: Final = "rate-transfer.rate"

#: Every rate-transfer role and what the step is for.
ROLES: Final[Mapping[str, str]] = {
    RATE_TRANSFER_REMOUNT: "the operator places the unit with another axis up (tag axis=)",
    RATE_TRANSFER_RATE: "a turn over whole revolutions (tags axis=, rate=)",
}
