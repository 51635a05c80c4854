"""The installation-error test's step roles (``installation.<purpose>``, docs/installation.md).

The triad's misalignment angles on a single-axis rate table; every step after a remount carries
the tag ``axis=<x|y|z>`` (the body axis up, along the table's spin axis), the turns also
``rate=<°/s>``.

:data:`INSTALLATION_REMOUNT` ``"installation.remount"``
    The operator places the unit with another axis up (``remount``).
:data:`INSTALLATION_RATE` ``"installation.rate"``
    A turn over whole revolutions (``commanded`` gives ``rate_dps`` and ``revolutions``).

Contents
--------
:data:`ROLES` (role → what it is for), the role constants above.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

__all__ = ["INSTALLATION_RATE", "INSTALLATION_REMOUNT", "ROLES"]

INSTALLATION_REMOUNT: Final = "installation.remount"
INSTALLATION_RATE: Final = "installation.rate"

#: Every installation role and what the step is for.
ROLES: Final[Mapping[str, str]] = {
    INSTALLATION_REMOUNT: "the operator places the unit with another axis up (tag axis=)",
    INSTALLATION_RATE: "a turn at +ω or −ω over whole revolutions (tags axis=, rate=)",
}
