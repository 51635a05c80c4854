"""The random-drift test's step roles (``random-drift.<purpose>``, docs/random-drift.md).

:data:`RANDOM_DRIFT_POSITION` ``"random-drift.position"``
    A static record of one repetition of the multi-position sequence (tag ``rep=<k>``).

Contents
--------
:data:`ROLES` (role → what it is for), :data:`RANDOM_DRIFT_POSITION`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

__all__ = ["RANDOM_DRIFT_POSITION", "ROLES"]

RANDOM_DRIFT_POSITION: Final = "random-drift.position"

#: Every random-drift role and what the step is for.
ROLES: Final[Mapping[str, str]] = {
    RANDOM_DRIFT_POSITION: "a static record of one repetition of the sequence (tag rep=)",
}
