"""The g-sensitivity test's step roles (``g-sensitivity.<purpose>``, docs/g-sensitivity.md).

:data:`G_SENSITIVITY_POSITION` ``"g-sensitivity.position"``
    A long static record at one dual-axis table position (gravity along ±x, ±y, ±z or between).

Contents
--------
:data:`ROLES` (role → what it is for), :data:`G_SENSITIVITY_POSITION`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

__all__ = ["G_SENSITIVITY_POSITION", "ROLES"]

G_SENSITIVITY_POSITION: Final = "g-sensitivity.position"

#: Every g-sensitivity role and what the step is for.
ROLES: Final[Mapping[str, str]] = {
    G_SENSITIVITY_POSITION: "a long static record at one dual-axis table position",
}
