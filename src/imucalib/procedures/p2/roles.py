"""P2's step roles: what each recorded step is for (``p2.<purpose>``, docs/p2.md).

Every P2 step carries the tags ``point=<k>`` (its temperature point) and
``leg=heating|cooling``, the held-out points also ``held-out``, and the steps after a remount
``pose=<axis>`` (the fixture axis up).

:data:`P2_SOAK` ``"p2.soak"``
    Reach a temperature point and wait until chamber and IMUs are stable.
:data:`P2_REMOUNT` ``"p2.remount"``
    The operator places the fixture with another face up (an operator check).
:data:`P2_STATIC` ``"p2.static"``
    A static record in the current pose (tag ``angle=<deg>``: at two angles 180° apart).
:data:`P2_RATE` ``"p2.rate"``
    A turn at +ω or −ω over whole revolutions.

Contents
--------
:data:`ROLES` (role → what it is for), the role constants above.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

__all__ = ["P2_RATE", "P2_REMOUNT", "P2_SOAK", "P2_STATIC", "ROLES"]

P2_SOAK: Final = "p2.soak"
P2_REMOUNT: Final = "p2.remount"
P2_STATIC: Final = "p2.static"
P2_RATE: Final = "p2.rate"

#: Every P2 role and what the step is for.
ROLES: Final[Mapping[str, str]] = {
    P2_SOAK: "reach a temperature point and wait until chamber and IMUs are stable",
    P2_REMOUNT: "the operator places the fixture with another face up (operator check)",
    P2_STATIC: "a static record in the current pose (tag angle=<deg>)",
    P2_RATE: "a turn at +ω or −ω over whole revolutions",
}
